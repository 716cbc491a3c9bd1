"""The life of a placed tile's rows: laid intact, broken free, frozen, thawed.

This is the one module that changes a floe's status (through ``FloeState.set_status``):
``place_tile`` adds rows INTACT, ``break_cells`` makes them FREE, ``freeze_tile`` makes
a tile's free floes FROZEN and ``thaw_tile`` FREE again. The contact space follows each
change. ``IceData`` is the dynamic half of the ice world.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim_core.ice.contact import ContactSpace
from sim_core.ice.floes import BreakCause, FloeState, FloeStatus, TilePlacement
from sim_core.ice.model import IceModel


@dataclass
class IceData:
    """Dynamic half of the ice world: floe rows, placed tiles, the contact space."""

    state: FloeState
    tiles: TilePlacement
    contacts: ContactSpace


def new_ice_data(model: IceModel, hull_contour: np.ndarray, hull_friction: float) -> IceData:
    """Empty ice world with a hull of the given ship-frame contour (x forward, y starboard)."""
    outline = np.column_stack([hull_contour[:, 0], -hull_contour[:, 1]])  # body frame: y to port
    return IceData(FloeState(), TilePlacement(), ContactSpace(model, outline, hull_friction))


def place_tile(model: IceModel, data: IceData, template: int, corner: tuple[float, float],
               quarter_turns: int = 0) -> int:
    """Lay a breakable tile with its south-west corner at (x, y) m, rotated by quarter turns
    about its centre; all its cells intact at their floating height. Returns the tile's
    placement index (its rows: ``data.tiles.rows(index)``)."""
    t = model.templates[template]
    g0 = model.template_start[template]
    st = data.state
    rows = st.add_rows(t.n_cells, FloeStatus.INTACT)
    k = quarter_turns % 4
    c, s = round(math.cos(k * math.pi / 2)), round(math.sin(k * math.pi / 2))
    rel = model.centroid[g0:g0 + t.n_cells, :2] - 0.5 * t.side
    home = np.column_stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]]) + 0.5 * t.side
    home += np.asarray(corner, dtype=float)
    index = data.tiles.add(template, (float(corner[0]), float(corner[1])), k, rows)
    st.gcell[rows] = np.arange(g0, g0 + t.n_cells)
    st.tile[rows] = index
    st.home[rows] = home
    st.xy[rows] = home
    st.yaw[rows] = k * math.pi / 2
    st.heave[rows] = model.z_equilibrium[g0:g0 + t.n_cells]
    data.contacts.add_tile(st, index, np.arange(rows.start, rows.stop))
    return index


def break_cells(data: IceData, rows: np.ndarray, cause: BreakCause) -> None:
    """Break intact rows free: they become free floes."""
    data.contacts.free(data.state, rows)
    data.state.set_status(rows, FloeStatus.FREE)
    data.state.cause[rows] = cause


def freeze_tile(data: IceData, placement: int) -> None:
    """Stop simulating a tile: its bodies leave the contact space, free floes keep their
    last pose as FROZEN, intact cells stay INTACT (drawn, not simulated)."""
    rows = data.tiles.rows(placement)
    st = data.state
    st.submerged[rows] = False  # a frozen floe keeps its pose; it surfaces if thawed
    status = st.status[rows]
    data.contacts.remove(st, rows[(status == FloeStatus.INTACT) | (status == FloeStatus.FREE)])
    free = rows[status == FloeStatus.FREE]
    st.set_status(free, FloeStatus.FROZEN)
    st.vel[free] = 0.0
    st.yaw_rate[free] = 0.0


def thaw_tile(data: IceData, placement: int) -> None:
    """Simulate a frozen tile again: intact cells rejoin as a tile body, frozen floes come
    back as free floes at rest, at the poses they froze with."""
    rows = data.tiles.rows(placement)
    st = data.state
    status = st.status[rows]
    intact = rows[status == FloeStatus.INTACT]
    if len(intact):
        data.contacts.add_tile(st, placement, intact)
    frozen = rows[status == FloeStatus.FROZEN]
    data.contacts.add_floes(st, frozen)
    st.set_status(frozen, FloeStatus.FREE)
