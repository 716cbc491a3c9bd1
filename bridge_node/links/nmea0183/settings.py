"""An NMEA 0183 link's settings (``[[links]]`` with ``type = "nmea0183"``)."""
from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from bridge_node.common.network import loopback_unless, serial_port_unless
from bridge_node.links.nmea0183.ais import AisSettings
from bridge_node.links.nmea0183.sentences import COMMON_ORDER_TALKERS, DEFAULT_RATES, DEFAULT_TALKERS, TYPICAL_LENGTH
from bridge_node.links.settings import BAUD_RATES, LinkSettingsBase, known_keys

BAUD_BUDGET_SHARE = 0.8  # outputs may use this share of a serial line's characters per second
Talker = Annotated[str, Field(pattern=r"^[A-Z]{2}$")]


class NmeaLinkSettings(LinkSettingsBase):
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
        return known_keys(v, DEFAULT_TALKERS, "sentence")

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

    def resources(self) -> list[str]:
        return [f"the serial port {self.port}"] if self.port else []

    def output_rates(self) -> dict[str, float]:
        return DEFAULT_RATES | self.rates

    def sends_udp(self) -> bool:
        """Whether the outputs also go to ``udp_host:udp_port``."""
        return self.udp_output if self.udp_output is not None else not self.port

    def udp_destination(self) -> tuple[str, int] | None:
        return (self.udp_host, self.udp_port) if self.sends_udp() else None

    def order_talkers(self) -> frozenset[str] | None:
        """Talkers whose orders are taken; None: any."""
        return None if self.allowed_talkers == "any" else frozenset(self.allowed_talkers)
