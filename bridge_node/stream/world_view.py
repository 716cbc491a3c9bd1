"""What a consumer knows of the world: the published state, kept from ``WorldEvents``.

A consumer never reads the world's internals; it applies every step's events (or a
snapshot, to start or to resynchronise) to a ``WorldView``, which keeps the ship's state,
every placed tile (and which are frozen), and every floe row's pose, status and break
cause, the way a Clone-pattern client keeps its copy of a key-value store. The stream's
snapshot service answers late joiners from a view (``to_snapshot``). Since the consumer
last looked, the view also collects what changed: new placements, the span of rows whose
pose changed, and the rows newly broken, so a renderer uploads only those.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ship.outputs import ShipOutputs
from sim_core.world import PlacedTiles, WorldEvents

# The other vessels (AIS, DIS, scripted), one row each: MMSI; x east and y north in world m
# (the frame of ``ship.east``/``ship.north``); true heading in rad, clockwise from north (as
# ``ship.heading``); speed over ground m/s; length and beam m (0: unknown).
TRAFFIC_DTYPE = np.dtype([("id", np.int64), ("x", np.float64), ("y", np.float64), ("heading", np.float64),
                          ("speed", np.float64), ("length", np.float64), ("beam", np.float64)])


@dataclass(frozen=True)
class Placement:
    """A tile laid in the ice world: field tile, template, quarter turns, corner (m), rows."""

    tile: int
    template: int
    quarter_turns: int
    corner: tuple[float, float]
    row_start: int
    row_count: int


@dataclass
class ViewChanges:
    """What changed since the last ``take_changes``: new placement indices, the rows
    [rows_from, rows_to) whose pose or status may have changed, and rows broken."""

    placements: list[int]
    rows_from: int
    rows_to: int
    broken: np.ndarray


class WorldView:
    """The last published state. ``pose`` is (rows, 6): x, y, heave, yaw, roll, pitch in
    world m and rad; ``status`` the FloeStatus of each row; ``traffic`` the other vessels
    as last published (``TRAFFIC_DTYPE`` rows, shape (0,) when there are none)."""

    def __init__(self) -> None:
        self.seq = -1
        self.time = 0.0
        self.ship: ShipOutputs | None = None
        self.placements: dict[int, Placement] = {}
        self.frozen: set[int] = set()  # frozen placements
        self.pose = np.zeros((0, 6))
        self.status = np.zeros(0, dtype=np.uint8)
        self.cause = np.zeros(0, dtype=np.uint8)
        self.ice_load = np.zeros(3)
        self.traffic = np.zeros(0, dtype=TRAFFIC_DTYPE)
        self._blend: tuple | None = None  # (rows, pose before, pose after, ship before, ship after)
        self._new: list[int] = []
        self._span = [np.iinfo(np.int64).max, 0]
        self._broken: list[np.ndarray] = []

    @property
    def rows(self) -> int:
        return len(self.status)

    def _ensure_rows(self, n: int) -> None:
        if n > len(self.status):
            grow = n - len(self.status)
            self.pose = np.concatenate([self.pose, np.zeros((grow, 6))])
            self.status = np.concatenate([self.status, np.zeros(grow, dtype=np.uint8)])
            self.cause = np.concatenate([self.cause, np.zeros(grow, dtype=np.uint8)])

    def apply(self, events: WorldEvents) -> None:
        """Bring the view up to the state after these events."""
        self._unblend()
        before_ship, known_rows = self.ship, self.rows
        self.seq, self.time, self.ship, self.ice_load = events.seq, events.time, events.ship, events.ice_load
        self.frozen = set(events.frozen.tolist()) if events.snapshot else \
            (self.frozen | set(events.frozen.tolist())) - set(events.thawed.tolist())
        p = events.placed
        for i in range(len(p.placement)):
            k = int(p.placement[i])
            if k not in self.placements:
                self._new.append(k)
            self.placements[k] = Placement(int(p.tile[i]), int(p.template[i]), int(p.quarter_turns[i]),
                                           (float(p.corner[i, 0]), float(p.corner[i, 1])),
                                           int(p.row_start[i]), int(p.row_count[i]))
        if len(p.placement):
            self._ensure_rows(int((p.row_start + p.row_count).max()))
        rows = events.floe_rows
        if len(rows):
            self._ensure_rows(int(rows.max()) + 1)
            before = self.pose[rows]
            self.pose[rows] = events.floe_pose
            new = rows >= known_rows  # rows first seen now start where they are
            before[new] = self.pose[rows[new]]
            if not events.snapshot:
                self._blend = (rows, before, self.pose[rows], before_ship or events.ship, events.ship)
            self.status[rows] = events.floe_status
            self._span = [min(self._span[0], int(rows.min())), max(self._span[1], int(rows.max()) + 1)]
        self.cause[events.broken_by_hull] = BreakCause.HULL
        self.cause[events.broken_by_contact] = BreakCause.CONTACT
        self._broken += [events.broken_by_hull, events.broken_by_contact]

    def take_changes(self) -> ViewChanges:
        """What changed since the last call (and forget it)."""
        lo, hi = self._span
        changes = ViewChanges(self._new, min(lo, hi), hi, np.concatenate(self._broken) if self._broken
                              else np.zeros(0, dtype=np.int64))
        self._new, self._span, self._broken = [], [np.iinfo(np.int64).max, 0], []
        return changes

    def to_snapshot(self) -> WorldEvents:
        """The whole state of the view as snapshot events (for a consumer joining late)."""
        keys = sorted(self.placements)
        ps = [self.placements[k] for k in keys]
        placed = PlacedTiles(np.array([p.tile for p in ps], dtype=np.int64), np.array(keys, dtype=np.int64),
                             np.array([p.template for p in ps], dtype=np.int64),
                             np.array([p.quarter_turns for p in ps], dtype=np.int64),
                             np.array([p.corner for p in ps], dtype=float).reshape(-1, 2),
                             np.array([p.row_start for p in ps], dtype=np.int64),
                             np.array([p.row_count for p in ps], dtype=np.int64))
        broken = self.status != FloeStatus.INTACT
        return WorldEvents(
            seq=self.seq, time=self.time, ship=self.ship, placed=placed, thawed=np.zeros(0, dtype=np.int64),
            frozen=np.array(sorted(self.frozen), dtype=np.int64),
            broken_by_hull=np.nonzero(broken & (self.cause == BreakCause.HULL))[0],
            broken_by_contact=np.nonzero(broken & (self.cause == BreakCause.CONTACT))[0],
            floe_rows=np.arange(self.rows), floe_pose=self.pose.copy(), floe_status=self.status.copy(),
            floes_free=int(np.count_nonzero(self.status == FloeStatus.FREE)),
            floes_frozen=int(np.count_nonzero(self.status == FloeStatus.FROZEN)),
            ice_load=self.ice_load.copy(), rejected=(), snapshot=True)

    def blend(self, alpha: float) -> None:
        """Show the state ``alpha`` (0..1) of the way from before the last applied step to
        after it: the ship and that step's rows in between (angles the short way round).
        The next ``apply`` starts from the true state again."""
        if self._blend is None:
            return
        rows, a, b, ship_a, ship_b = self._blend
        alpha = min(max(alpha, 0.0), 1.0)
        d = b - a
        d[:, 3:] = (d[:, 3:] + math.pi) % (2.0 * math.pi) - math.pi
        self.pose[rows] = b - (1.0 - alpha) * d  # exactly the latest state at alpha = 1
        turn = (ship_b.heading - ship_a.heading + math.pi) % (2.0 * math.pi) - math.pi
        self.ship = dataclasses.replace(ship_b, north=ship_b.north - (1.0 - alpha) * (ship_b.north - ship_a.north),
                                        east=ship_b.east - (1.0 - alpha) * (ship_b.east - ship_a.east),
                                        heading=(ship_b.heading - (1.0 - alpha) * turn) % (2.0 * math.pi))
        self._span = [min(self._span[0], int(rows.min())), max(self._span[1], int(rows.max()) + 1)]

    def _unblend(self) -> None:
        if self._blend is not None:
            rows, _, b, _, ship_b = self._blend
            self.pose[rows] = b
            self.ship = ship_b
            self._blend = None
