"""The exercise's state as the control endpoint reports it (``status`` requests): what the
last step published, the orders and failures the ship has now, the links' health and the
active alarms, in the bridge's units. Read from the control endpoint's thread while the
loop runs: the values are numbers the loop replaces whole, and the lists are copied."""
from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence

from bridge_node.links.hub import LinkHub
from sim_core.frames.units import KNOT
from sim_core.ship.outputs import ShipOutputs
from sim_core.world import WorldData, WorldEvents


def _ship_fields(s: ShipOutputs) -> dict:
    """A ship's position, heading, speed, rudder and shaft in the bridge's units."""
    return {"latitude_deg": round(math.degrees(s.latitude), 7), "longitude_deg": round(math.degrees(s.longitude), 7),
            "north_m": round(s.north, 3), "east_m": round(s.east, 3),
            "heading_deg": round(math.degrees(s.heading), 2), "sog_kn": round(s.speed_over_ground / KNOT, 2),
            "rudder_deg": round(math.degrees(s.rudder_angle), 2), "shaft_rpm": round(s.shaft_rps * 60.0, 1)}


def exercise_status(events: WorldEvents, data: WorldData | None = None, hub: LinkHub | None = None,
                    others: Sequence[tuple[str, LinkHub]] = ()) -> dict:
    """Time, exercise clock, freeze, the own ship (and the other own ships, ``other_ships``)
    and the environment of a step's events;
    with the world's data, the ship's orders and failures; with the hub, link health and
    active alarms, and with ``others`` (each other own ship's name and hub) theirs too, an
    alarm's text after the ship's name."""
    s, e = events.ship, events.environment
    status = {
        "seq": events.seq, "time_s": round(events.time, 3), "frozen": e.frozen,
        "utc": dt.datetime.fromtimestamp(s.utc, dt.timezone.utc).isoformat(timespec="seconds"),
        **_ship_fields(s), "other_ships": [_ship_fields(o.outputs) for o in events.others],
        "visibility_m": e.visibility, "wind_kn": round(e.wind_speed / KNOT, 2),
        "wind_from_deg": round(math.degrees(e.wind_from), 1), "current_kn": round(e.current_speed / KNOT, 2),
        "current_to_deg": round(math.degrees(e.current_to), 1), "vessels": len(events.vessels),
    }
    if data is not None:
        ship = data.ship
        status |= {"rudder_order_deg": round(math.degrees(ship.rudder_order), 2),
                   "shaft_rpm_order": round(ship.rps_order * 60.0, 1), "steering_pumps": ship.steering_pumps,
                   "power_percent": round(ship.power_share * 100.0, 1), "sensors": data.sensors[0].modes()}
        for other, ship, sensors in zip(status["other_ships"], data.ships[1:], data.sensors[1:]):
            other |= {"steering_pumps": ship.steering_pumps, "power_percent": round(ship.power_share * 100.0, 1),
                      "sensors": sensors.modes()}
    if hub is not None:
        hubs = [("", hub), *((f"{name}: ", h) for name, h in others)]
        status |= {"alarms": [{"number": a.number, "text": prefix + a.text} for prefix, h in hubs
                              for a in list(h.active_alarms.values())],
                   "links": [link.health().as_dict() for _, h in hubs for link in list(h.links)]}
    return status
