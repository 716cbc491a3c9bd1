"""The convoy watch (issue 31, item 3, with the convoy's other ships in the traffic picture):
the ship ahead of the own ship in the convoy and the ship astern, each named by its MMSI
(an icebreaker the instructor steers, a ship a DIS simulator sends, a scripted one), as an
ARPA tracks a target: distance, true bearing, course and speed over ground, and the closest
point of approach (CPA) and the time to it (TCPA). The links send them (NMEA 0183 TTM), and
an alarm is raised while a distance is below ``min_distance_m``.

CPA and TCPA are the standard relative-motion solution of radar plotting (A. G. Bole,
W. O. Dineley and A. Wall, *Radar and ARPA Manual*, 2nd ed., Butterworth-Heinemann 2005,
ISBN 0-7506-6434-7, the relative plot): with the target's position r and velocity v
relative to the own ship, TCPA = -(r . v) / |v|^2 and
CPA = |r + v TCPA|; without relative motion the distance stays as it is (TCPA 0). Positions
are relative on the local plane of the own ship's position (``geodetic_to_local``): a
convoy spans a few kilometres.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from pydantic import Field, model_validator

from bridge_node.links.messages import Alarm, Vessel
from sim_core.frames.geodesy import geodetic_to_local
from sim_core.params import Params
from sim_core.ship.outputs import ShipOutputs

CONVOY_ALARM = 300  # + 0: the ship ahead too close; + 1: the ship astern
ROLES = ("ahead", "astern")  # target numbers 1 and 2 on the links


class ConvoySettings(Params):
    """``[convoy]``: the MMSIs of the ship ahead and the ship astern (either may be unset),
    and the distance below which the alarm is raised."""

    ahead_mmsi: int | None = Field(None, ge=100_000_000, le=999_999_999, description="the ship ahead")
    astern_mmsi: int | None = Field(None, ge=100_000_000, le=999_999_999, description="the ship astern")
    min_distance_m: float = Field(300.0, gt=0.0, le=20_000.0, description="alarm below this distance, m")

    @model_validator(mode="after")
    def _a_convoy(self) -> ConvoySettings:
        if self.ahead_mmsi is None and self.astern_mmsi is None:
            raise ValueError("give ahead_mmsi, astern_mmsi or both (the MMSIs of the convoy's other ships)")
        if self.ahead_mmsi == self.astern_mmsi:
            raise ValueError(f"ahead_mmsi and astern_mmsi are both {self.ahead_mmsi}: one ship cannot be both")
        return self

    def mmsi(self, role: str) -> int | None:
        return self.ahead_mmsi if role == "ahead" else self.astern_mmsi


@dataclass(frozen=True)
class ConvoyTarget:
    """A convoy ship as tracked from the own ship: SI (m, rad true, m/s, s)."""

    role: str  # "ahead" or "astern"
    number: int  # 1 ahead, 2 astern
    mmsi: int
    name: str
    distance: float
    bearing: float  # from the own ship, [0, 2 pi)
    course: float  # over ground
    speed: float  # over ground
    cpa: float
    tcpa: float  # negative: the closest point is past


def closest_approach(north: float, east: float, v_north: float, v_east: float) -> tuple[float, float]:
    """(CPA m, TCPA s) of a target at (north, east) m from the own ship moving at (v_north,
    v_east) m/s relative to it (the module's citation)."""
    v2 = v_north * v_north + v_east * v_east
    if v2 < 1e-12:
        return math.hypot(north, east), 0.0
    tcpa = -(north * v_north + east * v_east) / v2
    return math.hypot(north + v_north * tcpa, east + v_east * tcpa), tcpa


def _velocity(course: float, speed: float) -> tuple[float, float]:
    return speed * math.cos(course), speed * math.sin(course)


def convoy_targets(own: ShipOutputs, vessels: list[Vessel], settings: ConvoySettings) -> list[ConvoyTarget]:
    """The convoy's ships in the picture, as tracked from the own ship (none without a fix
    of its own, and none for a ship without one)."""
    if not own.fix_valid:
        return []
    by_mmsi = {v.mmsi: v for v in vessels if v.fix_valid}
    own_v = _velocity(own.course_over_ground, own.speed_over_ground)
    out = []
    for number, role in enumerate(ROLES, 1):
        v = by_mmsi.get(settings.mmsi(role))
        if v is None:
            continue
        north, east = geodetic_to_local(v.latitude, v.longitude, own.latitude, own.longitude)
        vn, ve = _velocity(v.course_over_ground, v.speed_over_ground)
        cpa, tcpa = closest_approach(north, east, vn - own_v[0], ve - own_v[1])
        out.append(ConvoyTarget(role, number, v.mmsi, v.name, math.hypot(north, east),
                                math.atan2(east, north) % (2.0 * math.pi), v.course_over_ground, v.speed_over_ground,
                                cpa, tcpa))
    return out


class ConvoyWatch:
    """Raises the convoy's distance alarm of a role while its ship is closer than the limit,
    and clears it when the ship is beyond it again (or out of the picture)."""

    def __init__(self, settings: ConvoySettings) -> None:
        self.settings = settings
        self.active: set[str] = set()  # roles alarmed now

    def changes(self, targets: list[ConvoyTarget]) -> list[Alarm]:
        """The alarm changes the targets bring."""
        limit = self.settings.min_distance_m
        close = {t.role: t for t in targets if t.distance < limit}
        seen = {t.role: t for t in targets}
        out = []
        for number, role in enumerate(ROLES):
            if (role in close) == (role in self.active):
                continue
            self.active ^= {role}
            if role in close:
                text = f"convoy: ship {role} at {close[role].distance:.0f} m (limit {limit:.0f} m)"
            elif role in seen:
                text = f"convoy: ship {role} at {seen[role].distance:.0f} m again"
            else:
                text = f"convoy: ship {role} out of the picture"
            out.append(Alarm(CONVOY_ALARM + number, text, role in close))
        return out
