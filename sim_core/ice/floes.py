"""Per-step state of the ice (like MuJoCo's mjData): one row per cell of every live tile.

Rows of one tile are contiguous, and a row keeps its number for as long as its tile is live
(placed or thawed, not frozen), so consumers (renderers, recorders) may keep live floes by
row number. A frozen tile gives its rows back and keeps only its broken cells, in
``FrozenFloes`` (one small record each, no row): behind the ship tiles freeze by the
hundred, and a row for each of their intact cells would grow memory for as long as the ship
steams. Vacant rows are handed to the next tile placed or thawed.

A row is ``FloeStatus.INTACT`` (part of the level ice, at rest), ``FREE`` (a floating floe,
simulated), ``FROZEN`` (a broken cell of a tile just frozen, whose engine objects are still
leaving the space; the row is given back once they have) or ``VACANT`` (held by no tile).
Only ``sim_core.ice.tiles`` changes a row's status, through ``FloeState.set_status``, which
keeps the per-status counts. Positions are world metres (x east, y north, z up; z is the
centre of mass height above the water plane); yaw is counter-clockwise from the template's
frame. ``home`` is where the cell sat in the level ice (its placed centroid), kept for
channel measurements. ``cause`` says what broke a cell. ``submerged`` marks free floes
pushed under the hull: they collide with nothing until the hull has passed over them; a
piece the bow strikes first turns against it (``turn``, ``turn_dir``: ``sim_core.ice.turning``).
``resting`` marks free floes that came to rest far from the hull: the engine holds them as
static bodies (they cost no solver work) until the hull comes near or a moving floe pushes
them; their pose and velocity stay as they were when they came to rest. ``bonded`` marks free
rows that are still part of a wide floe moving as one body (``sim_core.ice.compound_floes``):
they have no body of their own, and their pose follows the floe's body, at ``bond_xy`` and
``bond_yaw`` in its frame.
"""
from __future__ import annotations

from collections.abc import Iterable
from enum import IntEnum

import numpy as np


class FloeStatus(IntEnum):
    """State of a floe row."""

    INTACT = 0
    FREE = 1
    FROZEN = 2
    VACANT = 3


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

    def _zero(self, rows: slice) -> None:
        """Zero rows in use, in every column."""
        for column in self._columns:
            getattr(self, column.name)[rows] = 0

    def nbytes_per_row(self) -> int:
        """Bytes one row takes in the columns."""
        return sum(np.dtype(c.dtype).itemsize * (c.width or 1) for c in self._columns)


class FloeState(_Table):
    """One row per cell of the live tiles; rows ``[0, n)`` exist, some of them vacant. Rates
    and small angles are kept in float32, positions in float64 (metre-level fields span
    kilometres)."""

    gcell = _Column(np.int32)  # global template cell of the row
    tile = _Column(np.int32)  # placement index of the row's tile
    status = _Column(np.uint8)  # FloeStatus; written only through set_status
    cause = _Column(np.uint8)  # BreakCause
    crack = _Column(np.uint8)  # bending-crack label of a cell (sim_core.ice.bending); 0: none
    submerged = _Column(np.bool_)  # under the hull, out of planar contact
    turn = _Column(np.float32)  # a submerged piece turning or sliding under: the hull's advance left, m (ice.turning)
    turn_dir = _Column(np.float32)  # a turning piece's direction to the hull, rad CCW from east
    resting = _Column(np.bool_)  # a free floe at rest far from the hull, out of the dynamic set
    calm = _Column(np.uint16)  # steps in a row a free floe has been at rest (saturates at 65535)
    bonded = _Column(np.bool_)  # a free row still part of its wide floe's body (``compound_floes``)
    bond_xy = _Column(np.float64, 2)  # a bonded row's centre of mass in its floe body's frame, m
    bond_yaw = _Column(np.float64)  # a bonded row's yaw in its floe body's frame, rad
    bond_slot = _Column(np.int32)  # a bonded row's floe body's slot (``compound_floes.CompoundSlots``)
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
    shown_pose = _Column(np.float64, 6)  # a free row's pose as last published (``scene.switches.moved_rows``)
    shown = _Column(np.bool_)  # published free, at ``shown_pose``, since its status last changed

    def __init__(self, capacity: int = 1024) -> None:
        super().__init__(capacity)
        self._counts = np.zeros(len(FloeStatus), dtype=np.int64)
        self._vacant: list[list[int]] = []  # [start, stop) runs of vacant rows, by start, none adjacent

    def add_rows(self, count: int, status: FloeStatus) -> slice:
        """``count`` contiguous zeroed rows with the given status: the first vacant run long
        enough, else new rows at the end; returns their slice."""
        run = next((r for r in self._vacant if r[1] - r[0] >= count), None)
        if run is None:
            rows = self._append(count)
        else:
            rows = slice(run[0], run[0] + count)
            run[0] += count
            if run[0] == run[1]:
                self._vacant.remove(run)
            self._zero(rows)
            self._counts[FloeStatus.VACANT] -= count
        self._status[rows] = status
        self._counts[status] += count
        return rows

    def release_rows(self, rows: slice) -> None:
        """Make rows vacant, for a later ``add_rows``."""
        self.set_status(np.arange(rows.start, rows.stop), FloeStatus.VACANT)
        self._cause[rows] = BreakCause.NONE  # a vacant row broke nothing
        k = next((i for i, r in enumerate(self._vacant) if r[0] > rows.start), len(self._vacant))
        self._vacant.insert(k, [rows.start, rows.stop])
        if k + 1 < len(self._vacant) and self._vacant[k + 1][0] == rows.stop:  # joins the run after
            self._vacant[k][1] = self._vacant.pop(k + 1)[1]
        if k > 0 and self._vacant[k - 1][1] == rows.start:  # and the run before
            self._vacant[k - 1][1] = self._vacant.pop(k)[1]

    def set_status(self, rows: np.ndarray, status: FloeStatus) -> None:
        """Give rows a new status, keeping the counts."""
        self._counts -= np.bincount(self._status[rows], minlength=len(FloeStatus))
        self._status[rows] = status
        self._shown[rows] = False  # its new status goes out
        self._counts[status] += len(rows)

    def count(self, status: FloeStatus) -> int:
        """Rows with this status (kept as rows change, so O(1))."""
        return int(self._counts[status])


class TilePlacement(_Table):
    """Placed breakable tiles, by placement index: template, south-west corner (m),
    rotation (quarter turns CCW about the centre), first row and row count (0 rows while
    the tile is frozen)."""

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


# A frozen tile's broken cell: its offset in the tile, what broke it, and the pose and
# velocities it froze with (as the FloeState columns of the same names). 65 bytes; a thaw
# gives them back exactly.
FROZEN_FLOE = np.dtype([("cell", np.uint32), ("cause", np.uint8), ("xy", np.float64, 2), ("yaw", np.float64),
                        ("heave", np.float32), ("roll", np.float32), ("pitch", np.float32), ("vel", np.float32, 2),
                        ("yaw_rate", np.float32), ("heave_rate", np.float32), ("roll_rate", np.float32),
                        ("pitch_rate", np.float32)])
# a cracked intact cell of a frozen tile (whose rows it gave up), as kept and published
FROZEN_CRACK = np.dtype([("placement", "<i4"), ("cell", "<u4"), ("label", "u1")])
NO_FROZEN_CRACKS = np.zeros(0, dtype=FROZEN_CRACK)
NO_FROZEN_CRACKS.flags.writeable = False  # shared by every tile frozen without cracks
# a frozen floe that was a cell of a woken wide floe's body: its offset in the tile, which of
# the tile's bodies it was on (0, 1, ... in the order of their slots), and its place in that
# body's frame (``FloeState.bond_xy``, ``bond_yaw``), so that the floe thaws as one body
FROZEN_BOND = np.dtype([("cell", np.uint32), ("body", np.uint32), ("bond_xy", np.float64, 2),
                        ("bond_yaw", np.float64)])
NO_FROZEN_BONDS = np.zeros(0, dtype=FROZEN_BOND)
NO_FROZEN_BONDS.flags.writeable = False


def frozen_crack_records(parts: Iterable[np.ndarray]) -> np.ndarray:
    """``FROZEN_CRACK`` records of several tiles in one array (none: an empty one)."""
    return np.concatenate([NO_FROZEN_CRACKS, *parts])
_KEPT = FROZEN_FLOE.names[2:]  # the columns a frozen floe keeps


class FrozenFloes:
    """The broken cells of frozen tiles, by placement (``FROZEN_FLOE`` records, by cell),
    and which of them were cells of a woken wide floe's body (``FROZEN_BOND``). A frozen
    tile's intact cells need no record: they lie where the placement put them."""

    def __init__(self) -> None:
        self._tiles: dict[int, np.ndarray] = {}
        self._cracks: dict[int, np.ndarray] = {}  # placement -> its cracked intact cells (FROZEN_CRACK)
        self._bonds: dict[int, np.ndarray] = {}  # placement -> its floes that were on woken floes' bodies
        self.count = 0  # frozen floes held

    def keep_cracks(self, placement: int, state: FloeState, rows: np.ndarray) -> None:
        """Keep the cracked intact cells among a freezing tile's rows (all of them, from its
        first) as its ``FROZEN_CRACK`` records."""
        cracked = rows[(state.status[rows] == FloeStatus.INTACT) & (state.crack[rows] != 0)]
        cracks = np.zeros(len(cracked), dtype=FROZEN_CRACK)
        cracks["placement"], cracks["cell"], cracks["label"] = placement, cracked - rows[0], state.crack[cracked]
        self._cracks[placement] = cracks

    def cracks(self, placement: int) -> np.ndarray:
        """A frozen tile's cracked intact cells (``FROZEN_CRACK`` records, maybe none)."""
        return self._cracks.get(placement, NO_FROZEN_CRACKS)

    def keep_bonds(self, placement: int, state: FloeState, rows: np.ndarray) -> None:
        """Keep the freezing tile's rows (all of them, from its first) that are bonded to a
        woken wide floe's body (``compound_floes``) as its ``FROZEN_BOND`` records."""
        bonded = rows[(state.status[rows] == FloeStatus.FREE) & state.bonded[rows]]
        if not len(bonded):
            return
        bonds = np.zeros(len(bonded), dtype=FROZEN_BOND)
        bonds["cell"] = bonded - rows[0]
        bonds["body"] = np.unique(state.bond_slot[bonded], return_inverse=True)[1].ravel()
        bonds["bond_xy"], bonds["bond_yaw"] = state.bond_xy[bonded], state.bond_yaw[bonded]
        self._bonds[placement] = bonds

    def bonds(self, placement: int) -> np.ndarray:
        """A frozen tile's floes that were bonded to woken floes' bodies (``FROZEN_BOND``
        records, maybe none)."""
        return self._bonds.get(placement, NO_FROZEN_BONDS)

    def freeze(self, placement: int, state: FloeState, rows: np.ndarray, cells: np.ndarray) -> None:
        """Keep the given rows (cells: their offsets in the tile) as the placement's record."""
        floes = np.zeros(len(rows), dtype=FROZEN_FLOE)
        floes["cell"], floes["cause"] = cells, state.cause[rows]
        for name in _KEPT:
            floes[name] = getattr(state, name)[rows]
        self._tiles[placement] = floes
        self.count += len(floes)

    def restore(self, placement: int, state: FloeState, first_row: int) -> np.ndarray:
        """Write the placement's record back into its tile's rows (from first_row on);
        returns those rows. The record stays until ``forget``."""
        floes = self._tiles[placement]
        rows = first_row + floes["cell"].astype(np.int64)
        state.cause[rows] = floes["cause"]
        for name in _KEPT:
            getattr(state, name)[rows] = floes[name]
        cracks = self.cracks(placement)
        state.crack[first_row + cracks["cell"].astype(np.int64)] = cracks["label"]
        return rows

    def forget(self, placement: int) -> None:
        """Drop the placement's record (its tile has thawed)."""
        self.count -= len(self._tiles.pop(placement))
        self._cracks.pop(placement, None)
        self._bonds.pop(placement, None)

    def __getitem__(self, placement: int) -> np.ndarray:
        return self._tiles[placement]

    def __contains__(self, placement: int) -> bool:
        return placement in self._tiles

    def records(self) -> np.ndarray:
        """Every frozen floe's record, in the order their tiles froze."""
        return np.concatenate([np.zeros(0, dtype=FROZEN_FLOE), *self._tiles.values()])

    def nbytes(self) -> int:
        """Bytes of the records (floes, cracked cells and the bonds of woken floes' cells)."""
        return sum(a.nbytes for kept in (self._tiles, self._cracks, self._bonds) for a in kept.values())
