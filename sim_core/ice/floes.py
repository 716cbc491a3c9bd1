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
``resting`` marks free floes that came to rest far from the hull: the engine holds them as
static bodies (they cost no solver work) until the hull comes near or a moving floe pushes
them; their pose and velocity stay as they were when they came to rest.
"""
from __future__ import annotations

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
    """A per-row array of a ``_Table``: reads give the rows in use, ``[0, n)``."""

    def __init__(self, dtype: type, width: int | None = None) -> None:
        self.dtype, self.width = dtype, width

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = "_" + name
        owner._columns = (*getattr(owner, "_columns", ()), self)

    def allocate(self, table: _Table, capacity: int) -> None:
        shape = (capacity,) if self.width is None else (capacity, self.width)
        grown = np.zeros(shape, dtype=self.dtype)
        old = getattr(table, self.name, None)
        if old is not None:
            grown[: table.n] = old[: table.n]
        setattr(table, self.name, grown)

    def __get__(self, table: _Table | None, owner: type | None = None) -> np.ndarray:
        if table is None:
            return self  # type: ignore[return-value]
        return getattr(table, self.name)[: table.n]


class _Table:
    """Growable struct of arrays: the subclass declares ``_Column``s; rows ``[0, n)`` are in
    use. Capacity grows by half when full, so a long exercise wastes at most a third."""

    _columns: tuple[_Column, ...] = ()

    def __init__(self, capacity: int) -> None:
        self.n = 0
        self._capacity = capacity
        for column in self._columns:
            column.allocate(self, capacity)

    def _append(self, count: int) -> slice:
        """Make room for ``count`` more zeroed rows; returns their slice."""
        if self.n + count > self._capacity:
            self._capacity = max(self._capacity + self._capacity // 2, self.n + count)
            for column in self._columns:
                column.allocate(self, self._capacity)
        rows = slice(self.n, self.n + count)
        self.n += count
        return rows

    def nbytes_per_row(self) -> int:
        """Bytes one row takes in the columns."""
        return sum(np.dtype(c.dtype).itemsize * (c.width or 1) for c in self._columns)


class FloeState(_Table):
    """One row per floe; only rows ``[0, n)`` are in use. A frozen floe costs its row and
    nothing else (``nbytes_per_row`` bytes); rates and small angles are kept in float32,
    positions in float64 (metre-level fields span kilometres)."""

    gcell = _Column(np.int32)  # global template cell of the row
    tile = _Column(np.int32)  # placement index of the row's tile
    status = _Column(np.uint8)  # FloeStatus; written only through set_status
    cause = _Column(np.uint8)  # BreakCause
    submerged = _Column(np.bool_)  # under the hull, out of planar contact
    resting = _Column(np.bool_)  # a free floe at rest far from the hull, out of the dynamic set
    calm = _Column(np.uint16)  # steps in a row a free floe has been at rest (saturates at 65535)
    home = _Column(np.float32, 2)  # placed centroid in the level ice, world m
    xy = _Column(np.float64, 2)  # centre of mass, world m
    yaw = _Column(np.float64)  # rad, CCW
    vel = _Column(np.float32, 2)  # m/s
    yaw_rate = _Column(np.float32)  # rad/s
    heave = _Column(np.float32)  # centre of mass above the water plane, m
    roll = _Column(np.float32)  # rad
    pitch = _Column(np.float32)  # rad
    heave_rate = _Column(np.float32)  # m/s
    roll_rate = _Column(np.float32)  # rad/s
    pitch_rate = _Column(np.float32)  # rad/s

    def __init__(self, capacity: int = 1024) -> None:
        super().__init__(capacity)
        self._counts = np.zeros(len(FloeStatus), dtype=np.int64)

    def add_rows(self, count: int, status: FloeStatus) -> slice:
        """Append ``count`` zeroed rows with the given status; returns their slice."""
        rows = self._append(count)
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


class TilePlacement(_Table):
    """Placed breakable tiles, by placement index: template, south-west corner (m),
    rotation (quarter turns CCW about the centre), first row and row count."""

    template = _Column(np.int64)
    corner = _Column(np.float64, 2)
    quarter_turns = _Column(np.int64)
    row_start = _Column(np.int64)
    row_count = _Column(np.int64)

    def __init__(self, capacity: int = 64) -> None:
        super().__init__(capacity)

    def add(self, template: int, corner: tuple[float, float], quarter_turns: int, rows: slice) -> int:
        """Record a placement; returns its index."""
        k = self._append(1).start
        self._template[k], self._corner[k], self._quarter_turns[k] = template, corner, quarter_turns
        self._row_start[k], self._row_count[k] = rows.start, rows.stop - rows.start
        return k

    def rows(self, placement: int) -> np.ndarray:
        """Rows of a placed tile."""
        start = int(self._row_start[placement])
        return np.arange(start, start + int(self._row_count[placement]))
