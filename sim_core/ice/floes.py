"""Per-step state of the ice (like MuJoCo's mjData): one row per cell of every placed tile.

Rows of one tile are contiguous and are only ever appended: a row keeps its number for the
whole exercise (a frozen or thawed tile keeps its rows), so a row number is a stable name
for a floe that consumers (renderers, recorders) may keep.

A row is ``FloeStatus.INTACT`` (part of the level ice, at rest), ``FREE`` (a floating floe,
simulated) or ``FROZEN`` (left behind the ship: keeps its last pose, costs no physics).
Only ``sim_core.ice.tiles`` changes a row's status, through ``FloeState.set_status``, which
keeps the per-status counts. Positions are world metres (x east, y north, z up; z is the
centre of mass height above the water plane); yaw is counter-clockwise from the template's
frame. ``home`` is where the cell sat in the level ice (its placed centroid), kept for
channel measurements. ``cause`` says what broke a cell. ``submerged`` marks free floes
pushed under the hull: they collide with nothing until the hull has passed over them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np


class FloeStatus(IntEnum):
    """State of a floe row."""

    INTACT = 0
    FREE = 1
    FROZEN = 2


class BreakCause(IntEnum):
    """What broke a cell (``FloeState.cause``)."""

    NONE = 0
    HULL = 1
    CONTACT = 2


class _Column:
    """A per-row array of the state: reads give the rows in use, ``[0, n)``."""

    def __init__(self, dtype: type, width: int | None = None) -> None:
        self.dtype, self.width = dtype, width

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = "_" + name
        owner._columns = (*getattr(owner, "_columns", ()), self)

    def allocate(self, state: FloeState, capacity: int) -> None:
        shape = (capacity,) if self.width is None else (capacity, self.width)
        grown = np.zeros(shape, dtype=self.dtype)
        old = getattr(state, self.name, None)
        if old is not None:
            grown[: state.n] = old[: state.n]
        setattr(state, self.name, grown)

    def __get__(self, state: FloeState | None, owner: type | None = None) -> np.ndarray:
        if state is None:
            return self  # type: ignore[return-value]
        return getattr(state, self.name)[: state.n]


class FloeState:
    """Growable struct of arrays, one row per floe; only rows ``[0, n)`` are in use."""

    gcell = _Column(np.int32)  # global template cell of the row
    tile = _Column(np.int32)  # placement index of the row's tile
    status = _Column(np.uint8)  # FloeStatus; written only through set_status
    cause = _Column(np.uint8)  # BreakCause
    submerged = _Column(np.bool_)  # under the hull, out of planar contact
    home = _Column(np.float64, 2)  # placed centroid in the level ice, world m
    xy = _Column(np.float64, 2)  # centre of mass, world m
    yaw = _Column(np.float64)  # rad, CCW
    vel = _Column(np.float64, 2)  # m/s
    yaw_rate = _Column(np.float64)  # rad/s
    heave = _Column(np.float64)  # centre of mass above the water plane, m
    roll = _Column(np.float64)  # rad
    pitch = _Column(np.float64)  # rad
    heave_rate = _Column(np.float64)  # m/s
    roll_rate = _Column(np.float64)  # rad/s
    pitch_rate = _Column(np.float64)  # rad/s

    def __init__(self, capacity: int = 1024) -> None:
        self.n = 0
        self._counts = np.zeros(len(FloeStatus), dtype=np.int64)
        for column in self._columns:
            column.allocate(self, capacity)

    def add_rows(self, count: int, status: FloeStatus) -> slice:
        """Append ``count`` zeroed rows with the given status; returns their slice."""
        capacity = len(self._gcell)
        if self.n + count > capacity:
            for column in self._columns:
                column.allocate(self, max(2 * capacity, self.n + count))
        rows = slice(self.n, self.n + count)
        self.n += count
        self._status[rows] = status
        self._counts[status] += count
        return rows

    def set_status(self, rows: np.ndarray, status: FloeStatus) -> None:
        """Give rows a new status, keeping the counts."""
        self._counts -= np.bincount(self._status[rows], minlength=len(FloeStatus))
        self._status[rows] = status
        self._counts[status] += len(rows)

    def count(self, status: FloeStatus) -> int:
        """Rows with this status (kept as rows change, so O(1))."""
        return int(self._counts[status])


@dataclass
class TilePlacement:
    """Placed breakable tiles, by placement index: template, south-west corner (m),
    rotation (quarter turns CCW about the centre), first row and row count."""

    template: list[int] = field(default_factory=list)
    corner: list[tuple[float, float]] = field(default_factory=list)
    quarter_turns: list[int] = field(default_factory=list)
    row_start: list[int] = field(default_factory=list)
    row_count: list[int] = field(default_factory=list)

    def add(self, template: int, corner: tuple[float, float], quarter_turns: int, rows: slice) -> int:
        """Record a placement; returns its index."""
        self.template.append(template)
        self.corner.append(corner)
        self.quarter_turns.append(quarter_turns)
        self.row_start.append(rows.start)
        self.row_count.append(rows.stop - rows.start)
        return len(self.template) - 1

    def rows(self, placement: int) -> np.ndarray:
        """Rows of a placed tile."""
        start = self.row_start[placement]
        return np.arange(start, start + self.row_count[placement])
