"""A Modbus link's settings (``[[links]]`` with ``type = "modbus"``): the registers it reads
as orders and those it writes as indicators."""
from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, field_validator, model_validator

from bridge_node.common.network import loopback_unless, serial_port_unless
from bridge_node.links.settings import BAUD_RATES, LinkSettingsBase
from sim_core.params import Params
from sim_core.ship.searchlights import MAX_SEARCHLIGHTS

SCALE_RANGE = (1e-6, 1e6)  # |scale| of a register: beyond this it is a typo, not a scaling


def sane_scale(v: float) -> float:
    """A register scale: finite, non-zero, |scale| in SCALE_RANGE."""
    if not (math.isfinite(v) and SCALE_RANGE[0] <= abs(v) <= SCALE_RANGE[1]):
        raise ValueError(f"scale = {v!r}: must be finite and {SCALE_RANGE[0]:g} <= |scale| <= {SCALE_RANGE[1]:g}")
    return v


class RegisterSpec(Params):
    """One console input register: an order, its scaling and type. A searchlight's order
    takes a register per field: on (0 off, 1 on), bearing deg (+ starboard), elevation deg
    (+ up), each of the light ``light``."""

    order: Literal["rudder", "lever", "telegraph", "searchlight_on", "searchlight_bearing", "searchlight_elevation"]
    table: Literal["holding", "input"] = "holding"
    address: int = Field(ge=0, le=65535)
    type: Literal["int16", "uint16"] = "int16"
    scale: float = Field(1.0, description="engineering value = raw x scale (rudder deg, lever %, ETL code, "
                         "searchlight 0/1 or deg)")
    engine: int = Field(0, ge=0, le=9)
    light: int = Field(0, ge=0, le=MAX_SEARCHLIGHTS - 1, description="the searchlight of a searchlight_* register")

    _scale = field_validator("scale")(lambda cls, v: sane_scale(v))


class WriteSpec(Params):
    """One indicator value written to a holding register after each poll."""

    value: Literal["rudder_angle", "shaft_rpm", "heading", "speed"]
    address: int = Field(ge=0, le=65535)
    type: Literal["int16", "uint16"] = "int16"
    scale: float = Field(0.1, description="raw = value / scale (deg, rpm, deg, kn)")

    _scale = field_validator("scale")(lambda cls, v: sane_scale(v))


class ModbusLinkSettings(LinkSettingsBase):
    """The console's I/O polled as a Modbus TCP client or RTU master (pymodbus)."""

    type: Literal["modbus"]
    transport: Literal["tcp", "rtu"] = "tcp"
    host: str = "127.0.0.1"
    port: int = Field(502, ge=1, le=65535)
    allow_network: bool = False
    serial_port: str | None = Field(None, min_length=1)
    baudrate: Literal[BAUD_RATES] = 19200
    device_id: int = Field(1, ge=0, le=247)
    poll_hz: float = Field(20.0, gt=0.0, le=100.0)
    request_timeout_s: float = Field(0.2, gt=0.01, le=5.0)
    registers: list[RegisterSpec] = Field(min_length=1)
    writes: list[WriteSpec] = Field(default_factory=list)

    @model_validator(mode="after")
    def _checks(self) -> "ModbusLinkSettings":
        if self.transport == "tcp":
            loopback_unless(self.host, self.allow_network, "host")
        elif not self.serial_port:
            raise ValueError("serial_port is required when transport = 'rtu'")
        else:
            serial_port_unless(self.serial_port, self.allow_network, "serial_port")
        return self

    def resources(self) -> list[str]:
        if self.transport == "rtu":
            return [f"the serial port {self.serial_port}"]
        return [f"the Modbus server {self.host}:{self.port}, device {self.device_id}"]
