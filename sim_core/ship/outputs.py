"""What the ship model reports each step: the values bridge instruments and displays need."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from sim_core.frames.geodesy import local_to_geodetic
from sim_core.frames.ship_frame import ship_vector_to_world
from sim_core.ship.model import ShipData
from sim_core.ship.searchlights import SearchlightState


@dataclass(frozen=True)
class ShipOutputs:
    """Ship state for instruments, SI: m, m/s, rad, rad/s, rev/s, N."""

    time: float
    north: float  # m from the exercise origin
    east: float
    latitude: float  # rad
    longitude: float  # rad
    heading: float  # rad, [0, 2 pi), true
    course_over_ground: float  # rad, [0, 2 pi)
    speed_over_ground: float  # m/s
    speed_longitudinal: float  # through the water, m/s (no current: = u)
    speed_transverse: float  # m/s, + to starboard
    rate_of_turn: float  # rad/s, + to starboard
    rudder_angle: float  # rad, + to starboard
    shaft_rps: float  # rev/s, - astern
    ice_resistance: float  # N
    utc: float = 0.0  # the exercise clock: UTC of this state, unix s
    searchlights: tuple[SearchlightState, ...] = ()  # every configured light as commanded, by index
    fix_valid: bool = True  # False: no position fix (a GNSS receiver without one; ``sim_core.ship.sensors``)
    heave: float = 0.0  # m, + up, from the floating position
    pitch: float = 0.0  # rad, + bow up
    roll: float = 0.0  # rad, + starboard down

    def as_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> ShipOutputs:
        """The outputs ``as_dict`` gave (the searchlights as dicts)."""
        return cls(**{**d, "searchlights": tuple(SearchlightState(**s) for s in d.get("searchlights", ()))})


def ship_outputs(data: ShipData, time: float, lat0: float, lon0: float, utc: float = 0.0,
                 searchlights: tuple[SearchlightState, ...] = ()) -> ShipOutputs:
    """Outputs of the ship at its current state at simulated time (s) and exercise UTC
    (unix s), with its searchlights as commanded; origin (lat0, lon0) in radians."""
    north, east, psi = float(data.eta[0]), float(data.eta[1]), float(data.eta[5])
    u, v, r = float(data.nu[0]), float(data.nu[1]), float(data.nu[5])
    ve, vn = ship_vector_to_world((u, v), psi)
    vn, ve = vn + float(data.current[0]), ve + float(data.current[1])  # over ground: through the water + current
    lat, lon = local_to_geodetic(north, east, lat0, lon0)
    two_pi = 2.0 * math.pi
    return ShipOutputs(
        time=time, north=north, east=east, latitude=lat, longitude=lon,
        heading=psi % two_pi, course_over_ground=math.atan2(ve, vn) % two_pi,
        speed_over_ground=math.hypot(vn, ve), speed_longitudinal=u, speed_transverse=v,
        rate_of_turn=r, rudder_angle=data.rudder, shaft_rps=data.rps, ice_resistance=data.ice_resistance, utc=utc,
        searchlights=searchlights, heave=-float(data.eta[2]), pitch=float(data.eta[4]),
        roll=float(data.eta[3]),
    )
