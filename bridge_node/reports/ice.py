"""Plan-view pictures of the ice: cells drawn at their current pose, coloured by state."""
from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.patches import Patch

from sim_core.ice.floes import BreakCause, FloeState, FloeStatus
from sim_core.ice.model import IceModel, placed_outlines

COLOURS = {"intact": "#f4f7fa", "by hull": "#2f6690", "by contact": "#d1495b", "frozen": "#9aa5b1"}


def floe_polygons(model: IceModel, st: FloeState, rows: np.ndarray) -> list[np.ndarray]:
    """World outlines (m) of the given rows' cells."""
    pts, counts = placed_outlines(model, st.gcell[rows], st.xy[rows], st.yaw[rows])
    return np.split(pts, np.cumsum(counts)[:-1])


def row_colours(st: FloeState, rows: np.ndarray) -> np.ndarray:
    """Face colour of each row: intact, frozen, or what broke it."""
    names = np.where(st.cause[rows] == BreakCause.CONTACT, "by contact", "by hull").astype(object)
    names[st.status[rows] == FloeStatus.INTACT] = "intact"
    names[st.status[rows] == FloeStatus.FROZEN] = "frozen"
    return np.array([COLOURS[n] for n in names])


def draw_floes(ax, model: IceModel, st: FloeState, rows: np.ndarray | None = None) -> None:
    """Add the rows' cells to a matplotlib axis (equal aspect, metres)."""
    rows = np.arange(st.n) if rows is None else rows
    ax.add_collection(PolyCollection(floe_polygons(model, st, rows), facecolors=row_colours(st, rows),
                                     edgecolors="#7a8793", linewidths=0.15))
    ax.set_aspect("equal")
    ax.legend(handles=[Patch(facecolor=c, edgecolor="#7a8793", label=k) for k, c in COLOURS.items()
                       if k != "frozen" or np.any(st.status[rows] == FloeStatus.FROZEN)],
              loc="upper right", fontsize=7)
