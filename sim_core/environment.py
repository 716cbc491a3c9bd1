"""The exercise's environment, as the instructor sets it: visibility, wind, surface current,
and whether the exercise is frozen. Part of ``WorldData``, published in every
``WorldEvents``; the time of day is the world's exercise clock (``WorldData.epoch``).

SI inside: m, m/s, rad. Directions are clockwise from true north, each in the convention
its trade uses: the wind by where it blows from (meteorology), the current by where it
sets to (oceanography).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

RHO_AIR = 1.225  # kg/m3, air at 15 deg C and 1013.25 hPa (ISA sea level)


@dataclass(frozen=True)
class Environment:
    """Visibility (m: meteorological visibility, where contrast falls to 5 %), wind
    speed (m/s) and the direction it blows from (rad), surface current speed (m/s) and
    the direction it sets to (rad), and the freeze (physics held, clock stopped)."""

    visibility: float = 8000.0
    wind_speed: float = 0.0
    wind_from: float = 0.0
    current_speed: float = 0.0
    current_to: float = 0.0
    frozen: bool = False

    def current_north_east(self) -> tuple[float, float]:
        """The water's velocity over ground, north and east, m/s."""
        return self.current_speed * math.cos(self.current_to), self.current_speed * math.sin(self.current_to)

    def wind_north_east(self) -> tuple[float, float]:
        """The air's velocity over ground (where it blows to), north and east, m/s."""
        to = self.wind_from + math.pi
        return self.wind_speed * math.cos(to), self.wind_speed * math.sin(to)
