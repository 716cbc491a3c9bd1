"""What a consumer knows of the world: the published state, kept from ``WorldEvents``.

A consumer never reads the world's internals; it applies every step's events (or a
snapshot, to start or to resynchronise) to a ``WorldView``, which keeps the ship's state,
every placed tile (and which are frozen), every live floe row's pose, status and break
cause, and every frozen tile's floes (its ``FROZEN_FLOE_EVENT`` records, the only thing a
frozen floe costs here), the way a Clone-pattern client keeps its copy of a key-value
store. Rows a frozen tile gave up are VACANT until a placement is given them. The stream's
snapshot service answers late joiners from a view (``to_snapshot``). Since the consumer
last looked, the view also collects what changed: placements given rows (new or thawed),
placements frozen, the span of rows whose pose changed, and the rows newly broken (a thawed
tile's floes among them), so a renderer uploads only those; and the tiles the instructor
gave other ice.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from bridge_node.links.traffic_picture import TRAFFIC_DTYPE
from sim_core.ice.bending import crack_events
from sim_core.ice.floes import NO_FROZEN_CRACKS, BreakCause, FloeStatus, frozen_crack_records
from sim_core.fleet import ShipReport
from sim_core.ship.outputs import ShipOutputs
from sim_core.environment import Environment
from sim_core.scene.scene import retiled_records
from sim_core.scene.switches import FROZEN_FLOE_EVENT, PlacedTiles
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
    """What changed since the last ``take_changes``: placements given rows (new or thawed)
    and placements frozen, each only if still so; the rows [rows_from, rows_to) whose pose or
    status may have changed; rows broken (they may since have gone to another tile); and the
    tiles whose ice class changed (``WorldView.retiled`` gives the class, or none: as laid)."""

    placements: list[int]
    frozen: list[int]
    rows_from: int
    rows_to: int
    broken: np.ndarray
    retiled: list[int] = dataclasses.field(default_factory=list)


class WorldView:
    """The last published state. ``pose`` is (rows, 6): x, y, heave, yaw, roll, pitch in
    m and rad; ``status`` the FloeStatus of each row; ``frozen_floes`` each frozen
    placement's floes (``FROZEN_FLOE_EVENT`` records); ``traffic`` the other vessels as
    last published (``TRAFFIC_DTYPE`` rows, shape (0,) when there are none); ``ice_offset``
    where the ice's frame lies in the world (m, x east, y north: the poses, corners and frozen
    floes are in that frame, ``WorldEvents.ice_offset``); ``retiled`` the class of every tile
    the instructor gave ice not as laid (field tile -> class); ``environment``
    the instructor's (``sim_core.environment``) and ``ship.utc`` the exercise clock, as
    last published."""

    def __init__(self) -> None:
        self.seq = -1
        self.time = 0.0
        self.ship: ShipOutputs | None = None
        self.others: tuple[ShipReport, ...] = ()  # the other own ships as last published
        self.placements: dict[int, Placement] = {}
        self.frozen: set[int] = set()  # frozen placements
        self.frozen_floes: dict[int, np.ndarray] = {}
        self.frozen_cracks: dict[int, np.ndarray] = {}  # frozen placement -> its cracked intact cells
        self.pose = np.zeros((0, 6))
        self.status = np.zeros(0, dtype=np.uint8)
        self.cause = np.zeros(0, dtype=np.uint8)
        self.crack = np.zeros(0, dtype=np.uint8)  # each row's bending-crack label (sim_core.ice.bending)
        self.ice_load = np.zeros(3)
        self.ice_offset = np.zeros(2)
        self.environment = Environment()  # visibility, wind, current, freeze: as last published
        self.traffic = np.zeros(0, dtype=TRAFFIC_DTYPE)
        self.retiled: dict[int, int] = {}
        self.retiled_version = 0  # counts the changes of ``retiled``
        self._retiled_new: set[int] = set()
        self._blend: tuple | None = None  # (rows, pose before, after, ship before, after, ice offset before, after)
        self._new: list[int] = []
        self._frozen_new: list[int] = []
        self._span = [np.iinfo(np.int64).max, 0]
        self._broken: list[np.ndarray] = []

    @property
    def rows(self) -> int:
        return len(self.status)

    def _ensure_rows(self, n: int) -> None:
        if n > len(self.status):
            grow = n - len(self.status)
            self.pose = np.concatenate([self.pose, np.zeros((grow, 6))])
            self.status = np.concatenate([self.status, np.full(grow, FloeStatus.VACANT, dtype=np.uint8)])
            self.cause = np.concatenate([self.cause, np.zeros(grow, dtype=np.uint8)])
            self.crack = np.concatenate([self.crack, np.zeros(grow, dtype=np.uint8)])

    def _give_up_rows(self, placement: Placement) -> None:
        rows = slice(placement.row_start, placement.row_start + placement.row_count)
        self.status[rows], self.cause[rows], self.crack[rows] = FloeStatus.VACANT, BreakCause.NONE, 0
        if placement.row_count:
            self._span = [min(self._span[0], rows.start), max(self._span[1], rows.stop)]

    def apply(self, events: WorldEvents) -> None:
        """Bring the view up to the state after these events."""
        self._unblend()
        before_ship, known_rows, before_offset = self.ship, self.rows, self.ice_offset
        self.ice_offset = np.array(events.ice_offset, dtype=float)
        self.seq, self.time, self.ship, self.ice_load = events.seq, events.time, events.ship, events.ice_load
        self.others = events.others
        self.environment = events.environment
        self._take_retiled(events)
        frozen = set(events.frozen.tolist())
        held, held_cracks = self.frozen_floes, self.frozen_cracks
        if events.snapshot:  # every frozen tile with all its floes; rows it does not name belong to no tile
            self.status[:], self.cause[:], self.crack[:] = FloeStatus.VACANT, BreakCause.NONE, 0
            self.frozen_floes = {k: np.zeros(0, dtype=FROZEN_FLOE_EVENT) for k in frozen}
            self.frozen_cracks = {}
        for k in frozen - self.frozen:
            self._frozen_new.append(k)
            self.frozen_floes[k] = np.zeros(0, dtype=FROZEN_FLOE_EVENT)  # no floes, unless listed
            self.frozen_cracks.pop(k, None)  # nor cracks
            if k in self.placements:
                self._give_up_rows(self.placements[k])
                self.placements[k] = dataclasses.replace(self.placements[k], row_start=0, row_count=0)
        self.frozen = frozen if events.snapshot else (self.frozen | frozen) - set(events.thawed.tolist())
        self._take_frozen_records(events)
        if events.snapshot:  # frozen before and after a gap, but thawed and frozen again within it
            self._frozen_new += [k for k in frozen & held.keys() if not np.array_equal(held[k], self.frozen_floes[k])
                                 or not np.array_equal(held_cracks.get(k, NO_FROZEN_CRACKS),
                                                       self.frozen_cracks.get(k, NO_FROZEN_CRACKS))]
        p = events.placed
        self._take_placements(p)
        for k in events.thawed.tolist():
            self._thaw(k)
        rows = events.floe_rows
        if len(rows):
            self._ensure_rows(int(rows.max()) + 1)
            before = self.pose[rows]
            self.pose[rows] = events.floe_pose
            # rows first seen now, or just given to a tile, start where they are
            new = rows >= known_rows
            for a, n in zip(p.row_start.tolist(), p.row_count.tolist()):
                new |= (rows >= a) & (rows < a + n)
            before[new] = self.pose[rows[new]]
            if not events.snapshot:
                self._blend = (rows, before, self.pose[rows], before_ship or events.ship, events.ship,
                               before_offset if before_ship else self.ice_offset, self.ice_offset)
            # rows free now that were intact: broken, or bonded to a wide floe that woke (drawn as floes)
            self._broken.append(rows[~new & (self.status[rows] == FloeStatus.INTACT)
                                     & (events.floe_status == FloeStatus.FREE)])
            self.status[rows] = events.floe_status
            self._span = [min(self._span[0], int(rows.min())), max(self._span[1], int(rows.max()) + 1)]
        self._apply_cracks(events.cracked)
        self._free_from_placing(p)
        self.cause[events.broken_by_hull] = BreakCause.HULL
        self.cause[events.broken_by_contact] = BreakCause.CONTACT
        self._broken += [events.broken_by_hull, events.broken_by_contact]

    def _take_retiled(self, events: WorldEvents) -> None:
        """Keep the tiles' new ice classes (a snapshot's are all; the tiles it omits are as laid)."""
        given = dict(zip(events.retiled["tile"].tolist(), events.retiled["ice_class"].tolist()))
        if given or events.snapshot and self.retiled:
            self.retiled_version += 1
        if events.snapshot:
            self._retiled_new |= {t for t in self.retiled.keys() | given.keys() if self.retiled.get(t) != given.get(t)}
            self.retiled = given
        else:
            self._retiled_new |= given.keys()
            self.retiled.update(given)

    def _take_placements(self, p: PlacedTiles) -> None:
        """Keep the tiles placed (those new or changed, and not frozen, noted for the
        renderers), and give each its rows, uncracked."""
        for i in range(len(p.placement)):
            k = int(p.placement[i])
            placement = Placement(int(p.tile[i]), int(p.template[i]), int(p.quarter_turns[i]),
                                  (float(p.corner[i, 0]), float(p.corner[i, 1])),
                                  int(p.row_start[i]), int(p.row_count[i]))
            if k not in self.frozen and self.placements.get(k) != placement:
                self._new.append(k)
            self.placements[k] = placement
        if len(p.placement):
            self._ensure_rows(int((p.row_start + p.row_count).max()))
            for a, n in zip(p.row_start.tolist(), p.row_count.tolist()):
                self.crack[a:a + n] = 0  # rows given to a tile start uncracked

    def _take_frozen_records(self, events: WorldEvents) -> None:
        """Keep the frozen tiles' floes and cracked cells the events carry, by placement."""
        for records, kept in ((events.frozen_floes, self.frozen_floes), (events.frozen_cracks, self.frozen_cracks)):
            order = np.argsort(records["placement"], kind="stable")
            keys, starts = np.unique(records["placement"][order], return_index=True)
            for k, part in zip(keys.tolist(), np.split(records[order], starts[1:])):
                kept[k] = part.copy()  # its own memory, not the message's

    def _free_from_placing(self, placed: PlacedTiles) -> None:
        """The rows of tiles given rows that are free already (a floe field's floes, a thawed
        tile's) count as broken: they are drawn as floes."""
        for a, n in zip(placed.row_start.tolist(), placed.row_count.tolist()):
            given = np.arange(a, a + n)
            self._broken.append(given[self.status[given] == FloeStatus.FREE])

    def _apply_cracks(self, cracked: np.ndarray) -> None:
        """Take the labels of the cells cracked (their rows' statuses are uploaded again)."""
        if not len(cracked):
            return
        rows = cracked["row"].astype(np.int64)
        self._ensure_rows(int(rows.max()) + 1)
        self.crack[rows] = cracked["label"]
        self._span = [min(self._span[0], int(rows.min())), max(self._span[1], int(rows.max()) + 1)]

    def _thaw(self, placement: int) -> None:
        """A thawed tile's floes take back their causes in its new rows (they count as broken
        as the free rows of any tile given rows do: ``_free_from_placing``)."""
        self.frozen_cracks.pop(placement, None)  # its cracks come back by row
        floes = self.frozen_floes.pop(placement, None)
        if floes is not None:
            self.cause[self.placements[placement].row_start + floes["cell"].astype(np.int64)] = floes["cause"]

    def take_changes(self) -> ViewChanges:
        """What changed since the last call (and forget it)."""
        lo, hi = self._span
        changes = ViewChanges(list(dict.fromkeys(k for k in self._new if k not in self.frozen)),
                              list(dict.fromkeys(k for k in self._frozen_new if k in self.frozen)),
                              min(lo, hi), hi, np.unique(np.concatenate(self._broken)) if self._broken
                              else np.zeros(0, dtype=np.int64), sorted(self._retiled_new))
        self._new, self._frozen_new, self._span, self._broken = [], [], [np.iinfo(np.int64).max, 0], []
        self._retiled_new = set()
        return changes

    def live_rows(self) -> np.ndarray:
        """Rows of the placements that are not frozen."""
        spans = [(p.row_start, p.row_count) for k, p in self.placements.items() if k not in self.frozen]
        if not spans:
            return np.zeros(0, dtype=np.int64)
        return np.concatenate([np.arange(a, a + n) for a, n in spans])

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
        rows = self.live_rows()
        broken = rows[self.status[rows] == FloeStatus.FREE]
        frozen = sorted(self.frozen)
        floes = [self.frozen_floes[k] for k in frozen if k in self.frozen_floes]
        return WorldEvents(
            seq=self.seq, time=self.time, ship=self.ship, placed=placed, thawed=np.zeros(0, dtype=np.int64),
            frozen=np.array(frozen, dtype=np.int64),
            frozen_floes=np.concatenate(floes) if floes else np.zeros(0, dtype=FROZEN_FLOE_EVENT),
            broken_by_hull=broken[self.cause[broken] == BreakCause.HULL],
            broken_by_contact=broken[self.cause[broken] == BreakCause.CONTACT],
            floe_rows=rows, floe_pose=self.pose[rows], floe_status=self.status[rows],
            cracked=crack_events(self.crack, rows),
            frozen_cracks=frozen_crack_records(self.frozen_cracks[k] for k in frozen if k in self.frozen_cracks),
            floes_free=len(broken), floes_frozen=sum(len(f) for f in floes),
            ice_load=self.ice_load.copy(), rejected=(), snapshot=True, ice_offset=tuple(self.ice_offset.tolist()),
            environment=self.environment, others=self.others,
            retiled=retiled_records(list(self.retiled), list(self.retiled.values())))

    def blend(self, alpha: float) -> None:
        """Show the state ``alpha`` (0..1) of the way from before the last applied step to
        after it: the ship and that step's rows in between (angles the short way round).
        The next ``apply`` starts from the true state again."""
        if self._blend is None:
            return
        rows, a, b, ship_a, ship_b, offset_a, offset_b = self._blend
        alpha = min(max(alpha, 0.0), 1.0)
        d = b - a
        d[:, 3:] = (d[:, 3:] + math.pi) % (2.0 * math.pi) - math.pi
        self.pose[rows] = b - (1.0 - alpha) * d  # exactly the latest state at alpha = 1
        turn = (ship_b.heading - ship_a.heading + math.pi) % (2.0 * math.pi) - math.pi
        self.ship = dataclasses.replace(ship_b, north=ship_b.north - (1.0 - alpha) * (ship_b.north - ship_a.north),
                                        east=ship_b.east - (1.0 - alpha) * (ship_b.east - ship_a.east),
                                        heading=(ship_b.heading - (1.0 - alpha) * turn) % (2.0 * math.pi))
        self.ice_offset = offset_b - (1.0 - alpha) * (offset_b - offset_a)
        self._span = [min(self._span[0], int(rows.min())), max(self._span[1], int(rows.max()) + 1)]

    def _unblend(self) -> None:
        if self._blend is not None:
            rows, _, b, _, ship_b, _, offset_b = self._blend
            self.pose[rows] = b
            self.ship, self.ice_offset = ship_b, offset_b
            self._blend = None
