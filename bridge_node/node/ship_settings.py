"""The exercise's own ships in the config: ``[ship]`` (with its start in ``[exercise]``, its
links in ``[[links]]`` and its arbitration in ``[arbitration]``) and each ``[[ships]]``
table, another own ship in the same ice with its own bridge: its particulars, start, links,
arbitration and convoy watch (issue 31). ``check_fleet`` holds the rules between ships:
each has its own links and its own MMSI, and no link, device or port is two ships'.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from pydantic import Field

from bridge_node.links.convoy import ConvoySettings
from bridge_node.links.registry import LinkSettings
from bridge_node.links.settings import ArbitrationSettings, LinkSettingsBase
from sim_core.params import Params, repeated
from sim_core.ship.particulars import TELEGRAPH_POSITIONS

SHIP_NAME = r"^[A-Za-z0-9_\-]{1,64}$"  # ships/<name>.toml
AIS_NAME = r"^[A-Z0-9 @\-.]*$"  # a name as AIS sends it (a subset of its 6-bit text)


class ShipChoice(Params):
    """Which ship: ``config/ships/<name>.toml`` beside the config (or the built-in one), and
    how the other own ships know it (required where ``[[ships]]`` lists any)."""

    name: str = Field(pattern=SHIP_NAME)
    mmsi: int | None = Field(None, ge=100_000_000, le=999_999_999,
                             description="its MMSI in the other own ships' AIS and DIS")
    ais_name: str = Field("", max_length=20, pattern=AIS_NAME, description="its name there; unset: the ship "
                          "file's name")

    def shown_name(self) -> str:
        """The name the other ships' traffic picture gives this ship."""
        return self.ais_name or self.name.upper().replace("_", " ")[:20]


class StartSettings(Params):
    """How a ship starts: position in the local north/east frame (m from the field's
    south-west corner), heading, speed and engine order."""

    start_north: float | None = Field(None, ge=-1.0e5, le=1.0e6, description="m from the field's south edge")
    start_east: float | None = Field(None, ge=-1.0e5, le=1.0e6, description="m from the field's west edge")
    start_heading_deg: float = Field(0.0, ge=0.0, lt=360.0, description="true heading, deg")
    start_speed_kn: float = Field(6.0, ge=0.0, le=25.0, description="speed through the water, kn")
    start_telegraph: Literal[TELEGRAPH_POSITIONS] | None = Field("full_ahead", description="engine order at the start")


class OtherShipSettings(ShipChoice, StartSettings):
    """``[[ships]]``: another own ship in the exercise's ice, steered from its own bridge:
    its ship file, MMSI and start (both positions required), its links
    (``[[ships.links]]``, as ``[[links]]``), their arbitration (``[ships.arbitration]``),
    optionally its convoy watch (``[ships.convoy]``), and whether the run renders its
    bridge's channels too."""

    mmsi: int = Field(ge=100_000_000, le=999_999_999, description="its MMSI in the other ships' AIS and DIS")
    start_north: float = Field(ge=-1.0e5, le=1.0e6, description="m from the field's south edge")
    start_east: float = Field(ge=-1.0e5, le=1.0e6, description="m from the field's west edge")
    links: list[LinkSettings] = Field(default_factory=list)
    arbitration: ArbitrationSettings = ArbitrationSettings()
    convoy: ConvoySettings | None = None
    render: bool = Field(False, description="icebridge run starts this ship's render processes too: the channel "
                         "groups of [render] from its bridge (its files under OUT/ship<K>/)")


def check_links(links: Sequence[LinkSettingsBase], arbitration: ArbitrationSettings, prefix: str = "") -> None:
    """One ship's links: unique names, and arbitration sources among them. ValueError
    naming the key (under ``prefix``)."""
    names = [link.name for link in links]
    doubled = repeated(names)
    if doubled:
        raise ValueError(f"{prefix}links: names must be unique, repeated: {doubled}")
    for order in ("rudder", "engine"):
        unknown = [n for n in getattr(arbitration, order) if n not in names]
        if unknown:
            raise ValueError(f"{prefix}arbitration.{order}: unknown link(s) {unknown}; links: {names}")


def check_fleet(own: ShipChoice, own_links: Sequence[LinkSettingsBase], has_console: bool,
                ships: Sequence[OtherShipSettings]) -> None:
    """The rules between the exercise's ships. Every ship has links of its own (the first
    may have its run console's), an MMSI of its own, and no link name, device, port or UDP
    destination is two ships' (a device or port may be two links' of one ship; a UDP
    destination is one link's). ValueError naming the key, the value and the other holder."""
    fleet = [("ship", "", own_links)] + [(f"ships.{i}", f"ships.{i}.", s.links) for i, s in enumerate(ships)]
    if ships:
        if own.mmsi is None:
            raise ValueError("ship.mmsi: required when [[ships]] lists other own ships (their AIS and DIS show "
                             "this ship by it)")
        if not own_links and not has_console:
            raise ValueError("links: the first ship has no links and no [console]; each ship of [[ships]] needs "
                             "its own bridge's links")
        for i, s in enumerate(ships):
            if not s.links:
                raise ValueError(f"ships.{i}.links: ship {s.mmsi} has no links; each ship needs its own "
                                 "bridge's links ([[ships.links]])")
        mmsis = [own.mmsi, *(s.mmsi for s in ships)]
        if repeated(mmsis):
            raise ValueError(f"ships.*.mmsi: each ship needs its own MMSI, repeated: {repeated(mmsis)}")
    holders: dict[str, tuple[str, str]] = {}  # resource -> (ship key, link name)
    for ship_key, prefix, links in fleet:
        for j, link in enumerate(links):
            destination = link.udp_destination()
            if destination is not None:
                _hold(holders, f"UDP {destination[0]}:{destination[1]}", ship_key, link.name,
                      f"{prefix}links.{j}.udp_port = {destination[1]}", "; give it another udp_port, or udp_output "
                      "= false")
            for resource in (f"link name {link.name!r}", *link.resources()):
                if holders.setdefault(resource, (ship_key, link.name))[0] != ship_key:  # one ship's may share
                    _hold(holders, resource, ship_key, link.name, f"{prefix}links.{j} ({link.name!r})",
                          "; each ship's bridge has links of its own")


def _hold(holders: dict[str, tuple[str, str]], resource: str, ship_key: str, link: str, where: str,
          advice: str) -> None:
    """Note that ``link`` of ``ship_key`` holds ``resource``; ValueError naming ``where``
    if another link holds it."""
    other = holders.setdefault(resource, (ship_key, link))
    if other != (ship_key, link):
        raise ValueError(f"{where}: {resource} is also link {other[1]!r}'s, of {other[0]}{advice}")
