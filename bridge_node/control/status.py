"""The exercise's state as the control endpoint reports it (``status`` requests): what the
last step published, in the bridge's units."""
from __future__ import annotations

import datetime as dt
import math

from sim_core.frames.units import KNOT
from sim_core.world import WorldEvents


def exercise_status(events: WorldEvents) -> dict:
    """Time, exercise clock, freeze, the own ship and the environment of a step's events."""
    s, e = events.ship, events.environment
    return {
        "seq": events.seq, "time_s": round(events.time, 3), "frozen": e.frozen,
        "utc": dt.datetime.fromtimestamp(s.utc, dt.timezone.utc).isoformat(timespec="seconds"),
        "latitude_deg": round(math.degrees(s.latitude), 7), "longitude_deg": round(math.degrees(s.longitude), 7),
        "north_m": round(s.north, 3), "east_m": round(s.east, 3),
        "heading_deg": round(math.degrees(s.heading), 2), "sog_kn": round(s.speed_over_ground / KNOT, 2),
        "rudder_deg": round(math.degrees(s.rudder_angle), 2), "shaft_rpm": round(s.shaft_rps * 60.0, 1),
        "visibility_m": e.visibility, "wind_kn": round(e.wind_speed / KNOT, 2),
        "wind_from_deg": round(math.degrees(e.wind_from), 1), "current_kn": round(e.current_speed / KNOT, 2),
        "current_to_deg": round(math.degrees(e.current_to), 1),
    }
