"""A DIS link's settings (``[[links]]`` with ``type = "dis"``)."""
from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from bridge_node.common.network import loopback_unless
from bridge_node.links.settings import LinkSettingsBase


class DisLinkSettings(LinkSettingsBase):
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
    send_vessels: bool = Field(True, description="send the node's other vessels (instructor's, scripted, logged) too")

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

    def resources(self) -> list[str]:
        return [f"the DIS port {self.listen_host}:{self.listen_port}",
                f"the DIS entity {self.site}.{self.application}.{self.entity}"]
