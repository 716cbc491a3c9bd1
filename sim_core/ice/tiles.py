"""The life of a placed tile's rows: laid intact, broken free, frozen, thawed.

This is the one module that changes a floe's status (through ``FloeState.set_status``):
``place_tile`` takes rows INTACT, ``break_cells`` makes them FREE (``bond_floe`` too, for a
wide floe's cells that start moving as one body), ``freeze_tile`` keeps a
tile's free floes as ``FrozenFloes`` records (their rows FROZEN until the tile's engine
objects have left the space, then ``reclaim_rows`` makes the tile's rows VACANT for the
next tile), and ``thaw_tile`` gives the tile rows again, its floes FREE with the poses and
velocities they froze with. The contact space follows each change. ``IceData`` is the
dynamic half of the ice world.

Laying or thawing a tile builds a thousand or more engine objects. That work needs no row
and touches no physics, so it can be done ahead of need: ``prepare_place`` and
``prepare_thaw`` start a ``PreparedTile``, ``advance`` builds it a chunk at a time, and
``place_tile`` or ``thaw_tile`` given it only switch the built objects into the space. The
physics is the same either way: the objects are built from the same geometry and poses
and enter the space in the same order, at the same step.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sim_core.ice.chipmunk_bodies import TileBodies
from sim_core.ice.contact import ContactSpace
from sim_core.ice.floes import BreakCause, FloeState, FloeStatus, FrozenFloes, TilePlacement
from sim_core.ice.model import IceModel, placed_centroids
from sim_core.ice.wide_floes import held_back
from sim_core.stage_timer import StageTimer


@dataclass
class HullRows:
    """The rows one hull keeps track of."""

    # rows sent under the hull, each once: a superset of the submerged rows (a row surfaces,
    # or is vacated or thawed, without leaving it), so that surfacing need not scan every row
    went_under: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    # free and intact rows a tile switch laid under the hull, to go under it in the next ice step
    laid_under: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    # the hull's reference point (m) at the last look at every row for resting floes to
    # wake, and the resting rows (ascending) within the zone it kept (``resting.wake_near_hull``)
    wake_look: tuple[np.ndarray, np.ndarray] = field(
        default_factory=lambda: (np.full(2, np.inf), np.zeros(0, dtype=np.int64)))


@dataclass
class IceData:
    """Dynamic half of the ice world: floe rows, placed tiles, the contact space, frozen
    tiles' floes, and the rows of frozen tiles whose engine objects are still leaving."""

    state: FloeState
    tiles: TilePlacement
    contacts: ContactSpace
    frozen: FrozenFloes = field(default_factory=FrozenFloes)
    leaving_rows: dict[int, slice] = field(default_factory=dict)  # placement -> rows to give back
    hulls: list[HullRows] = field(default_factory=lambda: [HullRows()])  # by hull index, as contacts.hulls
    rest_water: tuple[float, float] = (0.0, 0.0)  # the drift (m/s, east, north) the resting floes came to rest in
    wash_turn: int = 0  # the share of the floes the propeller's wash drags this step (``wash.drag_in_wash``)
    timer: StageTimer = field(default_factory=StageTimer)  # the last step's stages (the world's and the ice's)


@dataclass
class PreparedTile:
    """Engine objects of a tile built ahead of its switch: the template, corner (m) and
    quarter turns it is laid with, the placement it thaws (-1 for a new one), the cell
    offsets (intact), frozen floes (their places in the tile's ``FrozenFloes`` record) and
    loose cells (a new floe-field tile's floes, at rest where the template lays them) still
    to build, and where the tile lays its cells (``placed_centroids``: home (n, 2) m,
    yaw rad; worked out once, not for every chunk). A preparation takes no rows: rows are
    taken at the switch, in step order, so that the rows (and so the physics, which orders
    some sums by row) do not depend on how much wall time preparing had."""

    template: int
    corner: tuple[float, float]
    quarter_turns: int
    placement: int
    bodies: TileBodies
    cells: np.ndarray
    floes: np.ndarray
    home: np.ndarray
    yaw: float
    loose: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @property
    def done(self) -> bool:
        return not len(self.cells) and not len(self.floes) and not len(self.loose)


def new_ice_data(model: IceModel, hull_contour: np.ndarray, hull_friction: float) -> IceData:
    """Empty ice world with a hull of the given ship-frame contour ((n, 2) m: x forward, y
    starboard) and friction against ice; ``add_hull`` adds more."""
    tiles = TilePlacement()
    return IceData(FloeState(), tiles, ContactSpace(model, tiles, _body_frame(hull_contour), hull_friction))


def add_hull(data: IceData, hull_contour: np.ndarray, hull_friction: float) -> int:
    """Add another ship's hull to the ice world (its contour and friction as ``new_ice_data``
    takes them); returns its index, the place of its motion among an ice step's hulls."""
    data.hulls.append(HullRows())
    return data.contacts.add_hull(_body_frame(hull_contour), hull_friction)


def _body_frame(contour: np.ndarray) -> np.ndarray:
    """A ship-frame contour (x forward, y starboard) in the engine's body frame (y to port)."""
    return np.column_stack([contour[:, 0], -contour[:, 1]])


def prepare_place(model: IceModel, template: int, corner: tuple[float, float], quarter_turns: int) -> PreparedTile:
    """Start preparing a new tile of the template laid at corner (m), turned by quarter turns:
    its cells intact, but those that start free (a floe field's floes) loose."""
    n, g0 = model.templates[template].n_cells, int(model.template_start[template])
    free = model.starts_free[g0:g0 + n]
    corner = (float(corner[0]), float(corner[1]))
    return PreparedTile(template, corner, quarter_turns % 4, -1, TileBodies(n, held_back(model.wide, g0, ~free)),
                        np.flatnonzero(~free), np.zeros(0, dtype=np.int64),
                        *placed_centroids(model, template, corner, quarter_turns), np.flatnonzero(free))


def prepare_thaw(model: IceModel, data: IceData, placement: int) -> PreparedTile:
    """Start preparing a frozen tile's return: its intact cells, and its frozen floes at
    the poses they froze with (they do not change while frozen)."""
    tiles = data.tiles
    template = int(tiles.template[placement])
    n = model.templates[template].n_cells
    floes, bonded = data.frozen[placement], data.frozen.bonds(placement)["cell"]
    intact = np.ones(n, dtype=bool)
    intact[floes["cell"]] = False
    intact[bonded] = True  # built as its floe's cells, on the floe's body (``thaw_tile``)
    hold = held_back(model.wide, int(model.template_start[template]), intact)
    corner, turns = tuple(tiles.corner[placement].tolist()), int(tiles.quarter_turns[placement])
    return PreparedTile(template, corner, turns, placement, TileBodies(n, hold), np.nonzero(intact)[0],
                        np.flatnonzero(~np.isin(floes["cell"], bonded)),
                        *placed_centroids(model, template, corner, turns))


def _lay(model: IceModel, st: FloeState, rows: slice, prepared: PreparedTile, placement: int) -> None:
    """Fill a tile's rows as level ice: its cells at their placed centroids and floating height."""
    g0, n = int(model.template_start[prepared.template]), rows.stop - rows.start
    st.gcell[rows] = np.arange(g0, g0 + n)
    st.tile[rows] = placement
    st.home[rows] = prepared.home
    st.xy[rows] = prepared.home
    st.yaw[rows] = prepared.yaw
    st.heave[rows] = model.z_equilibrium[g0:g0 + n]


def advance(data: IceData, prepared: PreparedTile, max_items: int) -> int:
    """Build up to max_items more cells or floes of a prepared tile; returns how many."""
    cells, prepared.cells = prepared.cells[:max_items], prepared.cells[max_items:]
    if len(cells):
        data.contacts.build_cells(prepared.bodies, prepared.template, prepared.home[cells], prepared.yaw, cells)
    floes, prepared.floes = prepared.floes[:max_items - len(cells)], prepared.floes[max_items - len(cells):]
    if len(floes):
        f = data.frozen[prepared.placement][floes]
        offsets = f["cell"].astype(np.int64)
        g0 = int(data.contacts.model.template_start[prepared.template])
        data.contacts.build_floes(prepared.bodies, offsets, g0 + offsets, f["xy"], f["yaw"], f["vel"], f["yaw_rate"])
    budget = max_items - len(cells) - len(floes)
    loose, prepared.loose = prepared.loose[:budget], prepared.loose[budget:]
    if len(loose):
        g0 = int(data.contacts.model.template_start[prepared.template])
        data.contacts.build_floes(prepared.bodies, loose, g0 + loose, prepared.home[loose],
                                  np.full(len(loose), prepared.yaw), np.zeros((len(loose), 2)), np.zeros(len(loose)))
    return len(cells) + len(floes) + len(loose)


def discard_prepared(data: IceData, prepared: PreparedTile) -> None:
    """Free the engine objects of a preparation that will not be switched in."""
    data.contacts.discard(prepared.bodies)


def _finish(data: IceData, prepared: PreparedTile) -> None:
    while not prepared.done:
        advance(data, prepared, 1 << 30)


def place_tile(model: IceModel, data: IceData, template: int, corner: tuple[float, float],
               quarter_turns: int = 0, prepared: PreparedTile | None = None) -> int:
    """Lay a breakable tile with its south-west corner at (x, y) m, rotated by quarter turns
    about its centre; all its cells at their floating height, intact (level ice) or, for a
    floe field's template, free floes at rest (their ``BreakCause`` NONE). With a tile prepared
    for this layout, only switch it in. Returns the tile's placement index (its rows:
    ``data.tiles.rows(index)``)."""
    prepared = prepared or prepare_place(model, template, corner, quarter_turns)
    _finish(data, prepared)
    rows = data.state.add_rows(model.templates[template].n_cells, FloeStatus.INTACT)
    index = data.tiles.add(template, prepared.corner, prepared.quarter_turns, rows)
    _lay(model, data.state, rows, prepared, index)
    if model.floe_field[template]:  # its floes of their own from the start, broken by nothing
        g0 = int(model.template_start[template])
        loose = rows.start + np.flatnonzero(model.starts_free[g0:g0 + rows.stop - rows.start])
        data.contacts.name_floes(prepared.bodies, loose - rows.start, loose)
        data.state.set_status(loose, FloeStatus.FREE)
    data.contacts.insert_tile(prepared.bodies, index)
    return index


def break_cells(data: IceData, rows: np.ndarray, cause: BreakCause) -> None:
    """Break intact or bonded rows free: they become free floes, each a body of its own."""
    data.contacts.free(data.state, rows)
    data.state.set_status(rows, FloeStatus.FREE)
    data.state.cause[rows] = cause


def bond_floe(data: IceData, placement: int, floe: int) -> None:
    """A wide floe of a placed tile (global floe index) starts moving as one body: its
    intact cells become FREE rows bonded to it (``compound_floes``), broken by nothing."""
    rows = data.contacts.bond(data.state, placement, floe)
    data.state.set_status(rows, FloeStatus.FREE)
    data.state.cause[rows] = BreakCause.NONE


def freeze_tile(data: IceData, placement: int) -> None:
    """Stop simulating a tile: its bodies leave the contact space, its free floes are kept
    with their last pose and velocity as ``FrozenFloes`` records, and its rows go back to
    the table once the bodies have left (``reclaim_rows``); until then its floes' rows are
    FROZEN. Its intact cells are level ice again (drawn, not simulated), the cracked ones kept
    with their crack labels."""
    tiles, st = data.tiles, data.state
    if placement in data.leaving_rows:  # its last freeze's rows: its thaw took its objects out of the space
        st.release_rows(data.leaving_rows.pop(placement))
    rows = tiles.rows(placement)
    free = rows[st.status[rows] == FloeStatus.FREE]
    data.frozen.freeze(placement, st, free, free - rows[0])
    data.frozen.keep_cracks(placement, st, rows)
    data.frozen.keep_bonds(placement, st, rows)
    data.contacts.drop_tile(placement)
    st.set_status(free, FloeStatus.FROZEN)
    st.submerged[rows] = st.resting[rows] = False  # a frozen floe thaws afloat, in the dynamic set
    st.bonded[rows] = False  # and a floe of its own (its wide floe's body leaves with the tile)
    st.turn[rows] = 0.0  # and not turning against the bow
    st.calm[rows] = 0
    data.leaving_rows[placement] = slice(int(rows[0]), int(rows[-1]) + 1)
    tiles.row_start[placement], tiles.row_count[placement] = 0, 0


def reclaim_rows(data: IceData) -> None:
    """Give back to the table the rows of frozen tiles whose engine objects have left the
    space (until then a contact may still name them)."""
    for placement in [k for k in data.leaving_rows if not data.contacts.is_leaving(k)]:
        data.state.release_rows(data.leaving_rows.pop(placement))


def thaw_tile(model: IceModel, data: IceData, placement: int, prepared: PreparedTile | None = None) -> None:
    """Simulate a frozen tile again, in rows of its own: intact cells rejoin as a tile body,
    frozen floes come back as free floes with the poses and velocities they froze with, and
    those that were cells of a woken wide floe's body as that body again, at rest where it
    froze (``CompoundFloes.rebond``). With a tile prepared for this thaw, only switch it in."""
    prepared = prepared or prepare_thaw(model, data, placement)
    _finish(data, prepared)
    tiles, st = data.tiles, data.state
    rows = st.add_rows(model.templates[prepared.template].n_cells, FloeStatus.INTACT)
    _lay(model, st, rows, prepared, placement)
    floes = data.frozen.restore(placement, st, rows.start)
    bonds = data.frozen.bonds(placement)
    own = floes[~np.isin(floes - rows.start, bonds["cell"])]  # a body of their own each
    data.contacts.name_floes(prepared.bodies, own - rows.start, own)
    tiles.row_start[placement], tiles.row_count[placement] = rows.start, rows.stop - rows.start
    data.contacts.insert_tile(prepared.bodies, placement)
    st.set_status(floes, FloeStatus.FREE)
    data.contacts.rebond(st, placement, bonds)
    data.frozen.forget(placement)


def broken_counts(data: IceData) -> np.ndarray:
    """Cells broken so far, by ``BreakCause`` (an array indexed by it): the live tiles'
    free floes and the frozen tiles' floes."""
    st, n = data.state, len(BreakCause)
    return (np.bincount(st.cause[st.status == FloeStatus.FREE], minlength=n)
            + np.bincount(data.frozen.records()["cause"], minlength=n))


@dataclass(frozen=True)
class Cells:
    """Cells of placed tiles, one entry each: global template cell, centre of mass (n, 2)
    world m, yaw rad, ``FloeStatus`` and ``BreakCause``."""

    gcell: np.ndarray
    xy: np.ndarray
    yaw: np.ndarray
    status: np.ndarray
    cause: np.ndarray


def placed_cells(model: IceModel, data: IceData) -> Cells:
    """Every cell of every placed tile, live or frozen (a frozen tile's intact cells where
    its placement laid them, its floes FROZEN at the poses they froze with), for pictures."""
    tiles, st = data.tiles, data.state
    parts = []
    for k in range(tiles.n):
        if k not in data.frozen:
            rows = tiles.rows(k)
            parts.append((st.gcell[rows], st.xy[rows], st.yaw[rows], st.status[rows], st.cause[rows]))
            continue
        template = int(tiles.template[k])
        home, yaw = placed_centroids(model, template, tiles.corner[k], int(tiles.quarter_turns[k]))
        yaws, status, cause = np.full(len(home), yaw), np.zeros(len(home), np.uint8), np.zeros(len(home), np.uint8)
        floes = data.frozen[k]
        cell = floes["cell"].astype(np.int64)
        home[cell], yaws[cell], status[cell], cause[cell] = floes["xy"], floes["yaw"], FloeStatus.FROZEN, floes["cause"]
        g0 = int(model.template_start[template])
        parts.append((np.arange(g0, g0 + len(home)), home, yaws, status, cause))
    if not parts:
        return Cells(np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0), np.zeros(0, np.uint8), np.zeros(0, np.uint8))
    return Cells(*(np.concatenate(column) for column in zip(*parts)))
