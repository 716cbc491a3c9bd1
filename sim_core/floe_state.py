"""Per-step state of the ice (like MuJoCo's mjData): one row per cell of every placed tile.

Rows of one tile are contiguous. A row is INTACT (part of the level ice, at rest), FREE
(a floating floe, simulated), or FROZEN (left behind the ship: keeps its last pose, costs
no physics). Positions are world metres (x east, y north, z up; z is the centre of mass
height above the water plane); yaw is counter-clockwise from the template's frame. ``home``
is where the cell sat in the level ice (its placed centroid), kept for channel measurements.
``cause`` says what broke a cell (BY_HULL or BY_CONTACT; 0 while intact). ``submerged`` marks free floes pushed under the hull: they collide with nothing until the
hull has passed over them.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

INTACT, FREE, FROZEN = 0, 1, 2
BY_HULL, BY_CONTACT = 1, 2  # values of ``cause``: what broke the cell

_FIELDS = {
    "gcell": np.int32, "tile": np.int32, "status": np.uint8, "cause": np.uint8, "submerged": np.bool_,
    "home": (np.float64, 2),
    "xy": (np.float64, 2), "yaw": np.float64, "vel": (np.float64, 2), "yaw_rate": np.float64,
    "heave": np.float64, "roll": np.float64, "pitch": np.float64,
    "heave_rate": np.float64, "roll_rate": np.float64, "pitch_rate": np.float64,
}


@dataclass
class FloeState:
    """Growable struct of arrays; only rows [0, n) are in use."""

    n: int = 0
    arrays: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.arrays:
            self._allocate(1024)

    def _allocate(self, capacity: int) -> None:
        new = {}
        for name, spec in _FIELDS.items():
            dtype, width = (spec, None) if not isinstance(spec, tuple) else spec
            shape = (capacity,) if width is None else (capacity, width)
            arr = np.zeros(shape, dtype=dtype)
            if name in self.arrays:
                arr[: self.n] = self.arrays[name][: self.n]
            new[name] = arr
        self.arrays = new

    def add_rows(self, count: int) -> slice:
        """Append count zeroed rows; returns their slice."""
        capacity = len(self.arrays["gcell"])
        if self.n + count > capacity:
            self._allocate(max(2 * capacity, self.n + count))
        rows = slice(self.n, self.n + count)
        self.n += count
        return rows

    def __getattr__(self, name: str) -> np.ndarray:
        arrays = self.__dict__.get("arrays", {})
        if name in arrays:
            return arrays[name][: self.__dict__["n"]]
        raise AttributeError(name)

    def count(self, status: int) -> int:
        return int(np.count_nonzero(self.status == status))


@dataclass
class TilePlacement:
    """Placed breakable tiles: template, corner (m), rotation (quarter turns CCW), rows."""

    template: list = field(default_factory=list)
    corner: list = field(default_factory=list)
    quarter_turns: list = field(default_factory=list)
    row_start: list = field(default_factory=list)
    row_count: list = field(default_factory=list)
