"""Free drift of the broken ice in the wind: Nansen's rule.

Where the ice carries no internal stress (free drift: floes in open water, a broken
channel), the steady balance of the wind's stress, the water's stress and the Coriolis
force drives it at a small share of the surface wind's speed, turned to the right of the
wind in the northern hemisphere and to the left in the southern: Nansen's rule (Nansen
1902, "The oceanography of the North Polar Basin", The Norwegian North Polar Expedition
1893-1896, Scientific Results 3(9); Leppäranta 2011, "The Drift of Sea Ice", 2nd ed.,
Springer, chapter 6: a wind factor of about 2 % and a deviation angle of about 20-40
degrees). The ice moves with the water's current plus this wind drift; the contact engine's
linear water drag (``IceDynamicsSettings.drag_time_s``) pulls each free floe towards that
velocity. The rule holds at polar latitudes, where the exercises are; here only the
hemisphere turns the drift (none on the equator).

Where the whole field drifts (``IceDynamicsSettings.field_drift``: pack), it drifts so as
one body, in its own frame (``IceFrame``): uniform free drift under one wind and current.
Converging ice (pack pressed against fast ice, ridging) is not modelled.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

WIND_FACTOR = 0.02  # ice speed / surface wind speed (Nansen's rule)
DEVIATION_DEG = 30.0  # degrees the drift turns from the wind (right in the north, left in the south)


def free_drift(wind_north: float, wind_east: float, latitude: float, factor: float = WIND_FACTOR,
               deviation: float = math.radians(DEVIATION_DEG)) -> tuple[float, float]:
    """The ice's free-drift velocity in a surface wind, relative to the water.

    Parameters
    ----------
    wind_north, wind_east : the air's velocity (where it blows to), m/s.
    latitude : rad; its sign picks the side the drift turns to.
    factor : ice speed over wind speed; deviation : rad the drift turns from the wind.

    Returns
    -------
    (north, east) m/s.
    """
    turn = math.copysign(deviation, latitude) if latitude != 0.0 else 0.0  # clockwise, seen from above
    c, s = math.cos(turn), math.sin(turn)
    return factor * (wind_north * c - wind_east * s), factor * (wind_east * c + wind_north * s)


@dataclass
class IceFrame:
    """The ice world's own frame, where the whole field drifts as one body of ice (the pack
    driven by the wind and carried by the current): everything of the ice world (tiles,
    floes, regions, rubble, the channel behind the ship) lies in this frame, and a point of
    it lies at ``offset`` + its own coordinates in the world. A floe far from the hull, at
    rest in this frame, drifts with the field and costs no step. Without field drift the
    frame stays where the world is (the level ice fast, the broken floes drifting in it).

    The frame relaxes towards the ice's drift velocity with the floes' drag time (their
    linear water drag), as each free floe would: for a floe moving at v_f relative to the
    frame, dv/dt = (target - v_frame - v_f) / tau - dv_frame/dt = -v_f / tau. In the frame
    the floes' drift target is rest, and a floe at rest stays at rest when the wind or
    the current changes."""

    offset: np.ndarray = field(default_factory=lambda: np.zeros(2))  # m, world x east, y north
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))  # m/s, world x east, y north


def drift_frame(frame: IceFrame, target: np.ndarray, dt: float, drag_time: float) -> None:
    """Advance the frame by dt s towards the drift velocity target (m/s, world x east,
    y north) under linear drag with e-folding time drag_time s, integrated exactly:
    v(t) = target + (v0 - target) exp(-t / tau)."""
    decay = math.exp(-dt / drag_time)
    lag = frame.velocity - target
    frame.offset += target * dt + lag * drag_time * (1.0 - decay)
    frame.velocity[:] = target + lag * decay
