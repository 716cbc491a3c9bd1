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
"""
from __future__ import annotations

import math

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
