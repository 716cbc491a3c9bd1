"""The life of a placed tile's rows: laid intact, broken free, frozen, thawed.

This is the one module that changes a floe's status (through ``FloeState.set_status``):
``place_tile`` adds rows INTACT, ``break_cells`` makes them FREE, ``freeze_tile`` makes
a tile's free floes FROZEN and ``thaw_tile`` FREE again. The contact space follows each
change. ``IceData`` is the dynamic half of the ice world.

Laying or thawing a tile builds a thousand or more engine objects. That work needs no row
and touches no physics, so it can be done ahead of need: ``prepare_place`` and
``prepare_thaw`` start a ``PreparedTile``, ``advance`` builds it a chunk at a time, and
``place_tile`` or ``thaw_tile`` given it only switch the built objects into the space. The
physics is the same either way: the objects are built from the same geometry and poses
and enter the space in the same order, at the same step.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim_core.ice.contact import ContactSpace, TileBodies
from sim_core.ice.floes import BreakCause, FloeState, FloeStatus, TilePlacement
from sim_core.ice.model import IceModel, placed_centroids


@dataclass
class IceData:
    """Dynamic half of the ice world: floe rows, placed tiles, the contact space."""

    state: FloeState
    tiles: TilePlacement
    contacts: ContactSpace


@dataclass
class PreparedTile:
    """Engine objects of a tile built ahead of its switch: the template, corner (m) and
    quarter turns it is laid with, the placement it thaws (-1 for a new one), and the cell
    offsets and floe rows still to build."""

    template: int
    corner: tuple[float, float]
    quarter_turns: int
    placement: int
    bodies: TileBodies
    cells: np.ndarray
    floes: np.ndarray

    @property
    def done(self) -> bool:
        return not len(self.cells) and not len(self.floes)


def new_ice_data(model: IceModel, hull_contour: np.ndarray, hull_friction: float) -> IceData:
    """Empty ice world with a hull of the given ship-frame contour (x forward, y starboard)."""
    outline = np.column_stack([hull_contour[:, 0], -hull_contour[:, 1]])  # body frame: y to port
    tiles = TilePlacement()
    return IceData(FloeState(), tiles, ContactSpace(model, tiles, outline, hull_friction))


def prepare_place(model: IceModel, template: int, corner: tuple[float, float], quarter_turns: int) -> PreparedTile:
    """Start preparing a new tile of the template laid at corner (m), turned by quarter turns."""
    n = model.templates[template].n_cells
    return PreparedTile(template, (float(corner[0]), float(corner[1])), quarter_turns % 4, -1,
                        TileBodies(n), np.arange(n), np.zeros(0, dtype=np.int64))


def prepare_thaw(data: IceData, placement: int) -> PreparedTile:
    """Start preparing a frozen tile's return: its intact cells and its frozen floes, at
    the poses they froze with (they do not change while frozen)."""
    tiles, st = data.tiles, data.state
    rows = tiles.rows(placement)
    status = st.status[rows]
    return PreparedTile(int(tiles.template[placement]), tuple(tiles.corner[placement].tolist()),
                        int(tiles.quarter_turns[placement]), placement, TileBodies(len(rows)),
                        np.nonzero(status == FloeStatus.INTACT)[0], rows[status == FloeStatus.FROZEN])


def advance(data: IceData, prepared: PreparedTile, max_items: int) -> int:
    """Build up to max_items more cells or floes of a prepared tile; returns how many."""
    cells, prepared.cells = prepared.cells[:max_items], prepared.cells[max_items:]
    if len(cells):
        data.contacts.build_cells(prepared.bodies, prepared.template, prepared.corner, prepared.quarter_turns, cells)
    floes, prepared.floes = prepared.floes[:max_items - len(cells)], prepared.floes[max_items - len(cells):]
    if len(floes):
        data.contacts.build_floes(prepared.bodies, data.state, floes)
    return len(cells) + len(floes)


def discard_prepared(data: IceData, prepared: PreparedTile) -> None:
    """Free the engine objects of a preparation that will not be switched in."""
    data.contacts.discard(prepared.bodies)


def _finish(data: IceData, prepared: PreparedTile) -> None:
    while not prepared.done:
        advance(data, prepared, 1 << 30)


def place_tile(model: IceModel, data: IceData, template: int, corner: tuple[float, float],
               quarter_turns: int = 0, prepared: PreparedTile | None = None) -> int:
    """Lay a breakable tile with its south-west corner at (x, y) m, rotated by quarter turns
    about its centre; all its cells intact at their floating height. With a tile prepared
    for this layout, only switch it in. Returns the tile's placement index (its rows:
    ``data.tiles.rows(index)``)."""
    prepared = prepared or prepare_place(model, template, corner, quarter_turns)
    _finish(data, prepared)
    t = model.templates[template]
    g0 = model.template_start[template]
    st = data.state
    rows = st.add_rows(t.n_cells, FloeStatus.INTACT)
    index = data.tiles.add(template, prepared.corner, prepared.quarter_turns, rows)
    home, yaw = placed_centroids(model, template, prepared.corner, prepared.quarter_turns)
    st.gcell[rows] = np.arange(g0, g0 + t.n_cells)
    st.tile[rows] = index
    st.home[rows] = home
    st.xy[rows] = home
    st.yaw[rows] = yaw
    st.heave[rows] = model.z_equilibrium[g0:g0 + t.n_cells]
    data.contacts.insert_tile(prepared.bodies, index)
    return index


def break_cells(data: IceData, rows: np.ndarray, cause: BreakCause) -> None:
    """Break intact rows free: they become free floes."""
    data.contacts.free(data.state, rows)
    data.state.set_status(rows, FloeStatus.FREE)
    data.state.cause[rows] = cause


def freeze_tile(data: IceData, placement: int) -> None:
    """Stop simulating a tile: its bodies leave the contact space, free floes keep their
    last pose and velocity as FROZEN (a row and nothing else), intact cells stay INTACT
    (drawn, not simulated)."""
    rows = data.tiles.rows(placement)
    st = data.state
    st.submerged[rows] = False  # a frozen floe keeps its pose; it surfaces if thawed
    st.resting[rows] = False  # nor is it resting: it thaws into the dynamic set
    st.calm[rows] = 0
    data.contacts.drop_tile(placement)
    st.set_status(rows[st.status[rows] == FloeStatus.FREE], FloeStatus.FROZEN)


def thaw_tile(data: IceData, placement: int, prepared: PreparedTile | None = None) -> None:
    """Simulate a frozen tile again: intact cells rejoin as a tile body, frozen floes come
    back as free floes with the poses and velocities they froze with. With a tile prepared for
    this thaw, only switch it in."""
    prepared = prepared or prepare_thaw(data, placement)
    _finish(data, prepared)
    rows = data.tiles.rows(placement)
    frozen = rows[data.state.status[rows] == FloeStatus.FROZEN]
    data.contacts.insert_tile(prepared.bodies, placement)
    data.state.set_status(frozen, FloeStatus.FREE)
