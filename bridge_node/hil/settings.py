"""The software console's configuration (``icebridge console --config``): one ``[[links]]``
table per console end, each the peer of one node link and named by its role in scenarios
(``primary``, ``backup``, ``panel``). ``icebridge hil run`` writes one beside the node config
it generates; ``config/console.toml`` is the peer of ``config/bridge_console.toml``."""
from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from bridge_node.hil.scenario import ROLES
from bridge_node.hil.toml_file import load_toml_model
from bridge_node.links.modbus.settings import RegisterSpec, WriteSpec
from bridge_node.links.settings import BAUD_RATES
from bridge_node.common.network import NETWORK_CAN_INTERFACES, loopback_unless, serial_port_unless
from sim_core.params import Params, repeated

Rate = Annotated[float, Field(gt=0.0, le=100.0, description="orders are sent again this often, Hz")]


class CanConsoleSettings(Params):
    """The console on a CAN bus: HelmOrder, EngineOrder and SearchlightOrder frames of the
    DBC (or the helm as NMEA 2000 PGN 127245); reads PGNs 127245, 127488, 127250 and 127251."""

    role: Literal[ROLES]
    type: Literal["can"]
    interface: str = Field("slcan", min_length=1)
    channel: str = Field(min_length=1)
    bitrate: int = Field(250_000, ge=10_000, le=1_000_000)
    dbc: str = Field("console.dbc", min_length=1, description="absolute, or in config/")
    source_address: int = Field(0x42, ge=0, le=251)
    helm: Literal["dbc", "pgn127245"] = "dbc"
    rate_hz: Rate = 10.0
    open_delay_s: float = Field(0.0, ge=0.0, le=10.0, description="slcan: wait this long after opening the "
                                "adapter (python-can's default, 2 s, is for real adapters; a pty needs none)")

    @model_validator(mode="after")
    def _on_the_host(self) -> "CanConsoleSettings":
        if self.interface in NETWORK_CAN_INTERFACES:
            raise ValueError(f"interface = {self.interface!r} reaches a network; the console stays on the host")
        serial_port_unless(self.channel, False, "channel")
        return self


class NmeaConsoleSettings(Params):
    """The console on a serial NMEA 0183 line: ROR, ETL, PRC and PICBSL (searchlight) out;
    RSA, RPM, HDT, ROT and ALR in."""

    role: Literal[ROLES]
    type: Literal["nmea0183"]
    port: str = Field(min_length=1)
    baudrate: Literal[BAUD_RATES] = 38400
    talker: str = Field("RC", pattern=r"^[A-Z]{2}$")
    rate_hz: Rate = 10.0

    _port = model_validator(mode="after")(lambda self: serial_port_unless(self.port, False, "port") and self)


class ModbusConsoleSettings(Params):
    """The console's Modbus I/O as a TCP register server on the loopback: orders in the
    node's ``registers``, the indicators the node writes (``writes``) read back."""

    role: Literal[ROLES]
    type: Literal["modbus"]
    host: str = "127.0.0.1"
    port: int = Field(ge=1, le=65535)
    device_id: int = Field(1, ge=0, le=247)
    registers: list[RegisterSpec] = Field(min_length=1)
    writes: list[WriteSpec] = Field(default_factory=list)
    rate_hz: Rate = 10.0

    _host = model_validator(mode="after")(lambda self: loopback_unless(self.host, False, "host") and self)


ConsoleLinkSettings = Annotated[CanConsoleSettings | NmeaConsoleSettings | ModbusConsoleSettings,
                                Field(discriminator="type")]


class ConsoleConfig(Params):
    """The console's ends, one per role."""

    links: list[ConsoleLinkSettings] = Field(min_length=1)

    @model_validator(mode="after")
    def _unique(self) -> "ConsoleConfig":
        twice = repeated([s.role for s in self.links])
        if twice:
            raise ValueError(f"role(s) {twice} given twice; one console end per role")
        return self


def load_console_config(path: str | Path) -> ConsoleConfig:
    """A console config file, validated; ConfigError naming the file, line and key otherwise."""
    return load_toml_model(path, ConsoleConfig, "console config")
