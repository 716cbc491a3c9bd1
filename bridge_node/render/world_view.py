"""What a renderer knows of the world: the published state, kept from ``WorldEvents``.

A consumer never reads the world's internals; it applies every step's events (or a
snapshot, to start or to resynchronise) to a ``WorldView``, which keeps the ship's state,
every placed tile, and every floe row's pose and status, the way a Clone-pattern client
keeps its copy of a key-value store. Since the consumer last looked, the view also
collects what changed: new placements, the span of rows whose pose changed, and the rows
newly broken, so a renderer uploads only those.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim_core.ship.outputs import ShipOutputs
from sim_core.world import WorldEvents


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
    world m and rad; ``status`` the FloeStatus of each row."""

    def __init__(self) -> None:
        self.seq = -1
        self.time = 0.0
        self.ship: ShipOutputs | None = None
        self.placements: dict[int, Placement] = {}
        self.pose = np.zeros((0, 6))
        self.status = np.zeros(0, dtype=np.uint8)
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

    def apply(self, events: WorldEvents) -> None:
        """Bring the view up to the state after these events."""
        self.seq, self.time, self.ship = events.seq, events.time, events.ship
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
            self.pose[rows] = events.floe_pose
            self.status[rows] = events.floe_status
            self._span = [min(self._span[0], int(rows.min())), max(self._span[1], int(rows.max()) + 1)]
        self._broken += [events.broken_by_hull, events.broken_by_contact]

    def take_changes(self) -> ViewChanges:
        """What changed since the last call (and forget it)."""
        lo, hi = self._span
        changes = ViewChanges(self._new, min(lo, hi), hi, np.concatenate(self._broken) if self._broken
                              else np.zeros(0, dtype=np.int64))
        self._new, self._span, self._broken = [], [np.iinfo(np.int64).max, 0], []
        return changes
