"""A CAN link's settings (``[[links]]`` with ``type = "can"``), and the check of its console DBC."""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Literal

import can
import cantools
from pydantic import Field, field_validator, model_validator

from bridge_node.common.errors import UserError
from bridge_node.common.input_files import DBC_LIMIT, read_input
from bridge_node.common.network import NETWORK_CAN_INTERFACES, serial_port_unless
from bridge_node.links.can.n2k_network import N2kName, N2kProduct
from bridge_node.links.settings import LinkSettingsBase, known_keys


def checked_dbc(path: Path, where: str) -> None:
    """Check a console DBC file: regular, readable, of sane size, and parsed by cantools;
    UserError naming ``where`` (the config file, key and value) otherwise."""
    data = read_input(path, "DBC file", DBC_LIMIT, where)
    database_format = "dbc" if path.suffix.lower() == ".dbc" else None  # else: cantools tries each
    text = data.decode("cp1252" if database_format else "utf-8", errors="replace")  # cantools' encodings
    try:
        cantools.database.load_string(text, database_format=database_format, strict=False)
    except Exception as exc:  # cantools raises many kinds (its own, ValueError, KeyError...) on a bad file
        raise UserError(f"{where}: {path} is not a DBC file cantools can read ({type(exc).__name__})") from None


N2K_OUTPUTS = {"rudder": 10.0, "engine_rapid": 10.0, "engine_dynamic": 2.0, "heading": 10.0,
               "rate_of_turn": 10.0, "position": 10.0, "cog_sog": 4.0, "attitude": 10.0}  # standard rates, Hz


class CanLinkSettings(LinkSettingsBase):
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
        return known_keys(v, N2K_OUTPUTS, "output")

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

    def resources(self) -> list[str]:
        return [f"the CAN bus {self.interface}:{self.channel}"]

    def output_rates(self) -> dict[str, float]:
        return N2K_OUTPUTS | self.rates

    def with_files(self, resolve: Callable[..., Path]) -> CanLinkSettings:
        return self.model_copy(update={"dbc": str(resolve("dbc", self.dbc, checked_dbc))})
