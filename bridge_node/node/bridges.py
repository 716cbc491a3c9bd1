"""The own ships' bridges of an exercise of several (``[[ships]]``): the first ship's links
hub, then each other ship's links opened, with its own traffic picture and convoy watch,
for a live run and a replay alike (``bridge_node.exercise.fleet``)."""
from __future__ import annotations

from contextlib import ExitStack
from pathlib import Path

from bridge_node.exercise.collision_alarms import COLLISION_ALARM, VESSEL_COLLISION_ALARM
from bridge_node.exercise.fleet import Bridge
from bridge_node.links.hub import LinkHub
from bridge_node.links.traffic_picture import TrafficPicture
from bridge_node.node.config import NodeConfig
from bridge_node.replay.session import FLEET_FOLDER


def open_bridges(cfg: NodeConfig, hub: LinkHub, record: Path | None, stack: ExitStack) -> list[Bridge]:
    """Every own ship's bridge where ``[[ships]]`` lists other ships (none otherwise): the
    first ship's ``hub``, then each other ship's links opened in ``stack``, with its own
    traffic picture (the first ship's sources) and convoy watch; with a ``record`` folder,
    each records its links' traffic under its ``ships/N``."""
    if not cfg.ships:
        return []
    bridges = [Bridge(hub, cfg.ship.mmsi, cfg.ship.shown_name())]
    for k, ship in enumerate(cfg.ships, start=1):
        other = LinkHub(ship.links, ship.arbitration, record / FLEET_FOLDER / str(k) if record else None,
                        TrafficPicture(hub.traffic.sources), convoy=ship.convoy)
        bridges.append(Bridge(stack.enter_context(other), ship.mmsi, ship.shown_name()))
    return bridges


def bridges_summary(hub: LinkHub, bridges: list[Bridge]) -> dict:
    """For a run's summary: every ship's links' health, its active alarms' texts, and every
    collision (between own ships once: on the bridge of the first ship of the pair; with a
    vessel the instructor steers); another ship's texts start with its name. ``bridges`` as
    ``open_bridges`` gave them."""
    hubs = [b.hub for b in bridges] or [hub]
    names = [""] + [f"{b.name}: " for b in bridges[1:]]
    return {"links": [link.health().as_dict() for h in hubs for link in h.links],
            "alarms": [name + a.text for name, h in zip(names, hubs) for a in h.active_alarms.values()],
            "collisions": [name + a.text for k, (name, h) in enumerate(zip(names, hubs)) for _, a in h.alarm_log
                           if a.active and (k < a.number - COLLISION_ALARM < len(hubs)
                                            or a.number == VESSEL_COLLISION_ALARM)]}
