"""Configuration of the links (``[[links]]`` tables, told apart by ``type``) and of the
order arbitration (``[arbitration]``). Validated by pydantic: every error names the key."""
from __future__ import annotations

import math
from typing import Annotated, Literal

import can
from pydantic import Field, field_validator, model_validator

from bridge_node.links.ais import AisSettings
from bridge_node.links.n2k_network import N2kName, N2kProduct
from bridge_node.links.nmea0183 import COMMON_ORDER_TALKERS, DEFAULT_RATES, DEFAULT_TALKERS, TYPICAL_LENGTH
from bridge_node.common.network import NETWORK_CAN_INTERFACES, loopback_unless, serial_port_unless
from sim_core.params import Params
from sim_core.ship.searchlights import MAX_SEARCHLIGHTS

NAME_MAX = 24  # characters: every alarm text naming a link then fits an ALR sentence
Name = Annotated[str, Field(min_length=1, max_length=NAME_MAX, pattern=r"^[A-Za-z0-9_\-]+$")]
BAUD_RATES = (4800, 9600, 19200, 38400, 57600, 115200)
BAUD_BUDGET_SHARE = 0.8  # outputs may use this share of a serial line's characters per second


class _LinkBase(Params):
    name: Name
    timeout_s: float = Field(1.0, gt=0.05, le=60.0, description="a source silent this long is stale, s")
    engine: int = Field(0, ge=0, le=9, description="the engine number (0 centre or single, odd starboard, even "
                        "port) whose telegraph and lever orders are taken; others are counted as other_engine")


def _known_keys(v: dict, allowed: dict, what: str) -> dict:
    unknown = sorted(set(v) - set(allowed))
    if unknown:
        raise ValueError(f"unknown {what}(s) {unknown}; allowed: {', '.join(sorted(allowed))}")
    return v


Talker = Annotated[str, Field(pattern=r"^[A-Z]{2}$")]


class NmeaLinkSettings(_LinkBase):
    """Serial NMEA 0183 console and instruments, with a UDP copy of the outputs."""

    type: Literal["nmea0183"]
    port: str | None = Field(None, min_length=1, description="serial port or pyserial URL; unset: UDP output only")
    baudrate: Literal[BAUD_RATES] = 38400
    talkers: dict[str, Talker] = Field(default_factory=dict)
    rates: dict[str, Annotated[float, Field(ge=0.0, le=20.0)]] = Field(default_factory=dict, description="Hz")
    udp_output: bool | None = Field(None, description="send the outputs on UDP too; unset: only without a port")
    udp_host: str = "127.0.0.1"
    udp_port: int = Field(10110, ge=1, le=65535)
    allow_network: bool = False
    allowed_talkers: Annotated[list[Talker], Field(min_length=1)] | Literal["any"] = Field(
        list(COMMON_ORDER_TALKERS), description='talkers whose orders are taken, or "any"')
    ais: AisSettings | None = Field(None, description="own ship as !AIVDO and other vessels as !AIVDM; unset: no AIS")

    @field_validator("talkers", "rates")
    @classmethod
    def _known_sentences(cls, v: dict) -> dict:
        return _known_keys(v, DEFAULT_TALKERS, "sentence")

    @model_validator(mode="after")
    def _checks(self) -> "NmeaLinkSettings":
        loopback_unless(self.udp_host, self.allow_network, "udp_host")
        if self.port:
            serial_port_unless(self.port, self.allow_network, "port")
            need = sum(r * TYPICAL_LENGTH[k] for k, r in self.output_rates().items())
            budget = BAUD_BUDGET_SHARE * self.baudrate / 10.0
            if need > budget:
                raise ValueError(f"output rates need about {need:.0f} characters/s, more than {budget:.0f} "
                                 f"({BAUD_BUDGET_SHARE:.0%} of {self.baudrate} baud); lower rates or raise baudrate")
        return self

    def output_rates(self) -> dict[str, float]:
        return DEFAULT_RATES | self.rates

    def sends_udp(self) -> bool:
        """Whether the outputs also go to ``udp_host:udp_port``."""
        return self.udp_output if self.udp_output is not None else not self.port

    def order_talkers(self) -> frozenset[str] | None:
        """Talkers whose orders are taken; None: any."""
        return None if self.allowed_talkers == "any" else frozenset(self.allowed_talkers)


N2K_OUTPUTS = {"rudder": 10.0, "engine_rapid": 10.0, "engine_dynamic": 2.0, "heading": 10.0,
               "rate_of_turn": 10.0, "position": 10.0, "cog_sog": 4.0}  # standard rates, Hz


class CanLinkSettings(_LinkBase):
    """A CAN bus through python-can: console frames decoded with a DBC, NMEA 2000 in and out."""

    type: Literal["can"]
    interface: str = Field("virtual", min_length=1,
                           description="python-can interface: socketcan, pcan, kvaser, slcan, virtual, ...")
    channel: str = Field("icebridge", min_length=1)
    bitrate: int = Field(250_000, ge=10_000, le=1_000_000)
    dbc: str = Field("console.dbc", min_length=1,
                     description="console frames: relative to the config file's folder, else to config/")
    source_address: int = Field(0x23, ge=0, le=251, description="this node's preferred NMEA 2000 source address, "
                                "claimed and defended per ISO 11783-5")
    n2k_name: N2kName = Field(default_factory=N2kName, description="the node's ISO NAME (PGN 60928)")
    n2k_product: N2kProduct = Field(default_factory=N2kProduct, description="product information (PGN 126996)")
    heartbeat_s: float = Field(60.0, ge=1.0, le=60.0, description="heartbeat (PGN 126993) period, s")
    allowed_sources: Annotated[list[Annotated[int, Field(ge=0, le=253)]], Field(min_length=1)] | Literal["any"] = Field(
        description='source addresses whose orders are taken (the console\'s), or "any": every device on the bus')
    allow_network: bool = Field(False, description="allow interfaces and channels that reach a network")
    rudder_order_pgn: bool = Field(True, description="take PGN 127245 rudder angle orders as a helm source")
    rates: dict[str, Annotated[float, Field(ge=0.0, le=50.0)]] = Field(default_factory=dict, description="Hz")

    @field_validator("rates")
    @classmethod
    def _known_outputs(cls, v: dict) -> dict:
        return _known_keys(v, N2K_OUTPUTS, "output")

    @field_validator("interface")
    @classmethod
    def _known_interface(cls, v: str) -> str:
        if v not in can.VALID_INTERFACES:
            raise ValueError(f"python-can has no interface {v!r}; known: {', '.join(sorted(can.VALID_INTERFACES))}")
        return v

    @model_validator(mode="after")
    def _off_the_host(self) -> "CanLinkSettings":
        if self.interface in NETWORK_CAN_INTERFACES and not self.allow_network:
            raise ValueError(f"interface = {self.interface!r} reaches a network; set allow_network = true to use it")
        serial_port_unless(self.channel, self.allow_network, "channel")
        return self

    def output_rates(self) -> dict[str, float]:
        return N2K_OUTPUTS | self.rates


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


class ModbusLinkSettings(_LinkBase):
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


class DisLinkSettings(_LinkBase):
    """The own ship as DIS Entity State PDUs, unicast to ``send_to`` (loopback unless
    ``allow_network``), and other simulators' entities heard on ``listen_host:listen_port``."""

    type: Literal["dis"]
    exercise_id: int = Field(1, ge=1, le=255)
    site: int = Field(1, ge=1, le=65534)
    application: int = Field(1, ge=1, le=65534)
    entity: int = Field(1, ge=1, le=65534)
    force_id: int = Field(1, ge=0, le=255, description="1: friendly")
    country: int = Field(0, ge=0, le=65535, description="entity type's country (0: other)")
    category: int = Field(0, ge=0, le=255)
    subcategory: int = Field(0, ge=0, le=255)
    marking: str = Field("ICEBRIDGE", max_length=11, pattern=r"^[\x20-\x7e]*$")
    listen_host: str = "127.0.0.1"
    listen_port: int = Field(3000, ge=1, le=65535)
    send_to: list[Annotated[str, Field(pattern=r"^[0-9A-Za-z.:\[\]]+:\d{1,5}$")]] = Field(
        ["127.0.0.1:3000"], description='"host:port" of each simulator the PDUs go to')
    allow_network: bool = False
    heartbeat_s: float = Field(5.0, gt=0.0, le=60.0)
    position_threshold_m: float = Field(1.0, gt=0.0, le=100.0)
    orientation_threshold_deg: float = Field(3.0, gt=0.0, le=90.0)
    vessel_timeout_s: float = Field(12.0, gt=0.0, le=600.0, description="an entity silent this long is gone")
    mmsi_base: int = Field(200_000_000, ge=100_000_000, le=999_000_000, description="MMSIs of the vessels heard")

    @model_validator(mode="after")
    def _off_the_host(self) -> "DisLinkSettings":
        loopback_unless(self.listen_host, self.allow_network, "listen_host")
        for host, port in self.destinations():
            loopback_unless(host, self.allow_network, "send_to")
            if not 1 <= port <= 65535:
                raise ValueError(f"send_to: port {port} is not in 1..65535")
        return self

    def destinations(self) -> list[tuple[str, int]]:
        """(host, port) of each entry of ``send_to``."""
        return [(h.strip("[]"), int(p)) for h, p in (entry.rsplit(":", 1) for entry in self.send_to)]


LinkSettings = Annotated[NmeaLinkSettings | CanLinkSettings | ModbusLinkSettings | DisLinkSettings,
                         Field(discriminator="type")]


class ArbitrationSettings(Params):
    """Which link's orders win (first fresh source in each list), and what happens when
    every source of an order has gone stale. Searchlight orders are not arbitrated: every
    one from a searchlight source is passed on, and a light holds its last order."""

    rudder: list[Name] = Field(default_factory=list, description="rudder order sources by priority")
    engine: list[Name] = Field(default_factory=list, description="engine order sources by priority")
    searchlight: list[Name] | None = Field(None, description="links whose searchlight orders are taken (each order "
                                           "as it comes; a light holds its last); unset: the rudder and engine sources")
    fail_safe: Literal["hold", "midships_stop"] = "midships_stop"
    fail_safe_after_s: float = Field(3.0, ge=0.0, le=600.0, description="after every source is stale, s")
