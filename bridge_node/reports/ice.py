"""Plan-view pictures of the ice: cells drawn at their current pose, coloured by state."""
from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.patches import Patch

from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import IceModel, placed_outlines
from sim_core.ice.tiles import Cells

COLOURS = {"intact": "#f4f7fa", "by hull": "#2f6690", "by contact": "#d1495b", "frozen": "#9aa5b1"}


def cell_colours(cells: Cells) -> np.ndarray:
    """Face colour of each cell: intact, frozen, or what broke it."""
    names = np.where(cells.cause == BreakCause.CONTACT, "by contact", "by hull").astype(object)
    names[cells.status == FloeStatus.INTACT] = "intact"
    names[cells.status == FloeStatus.FROZEN] = "frozen"
    return np.array([COLOURS[n] for n in names], dtype=object)


def draw_cells(ax, model: IceModel, cells: Cells) -> None:
    """Add the cells' outlines to a matplotlib axis (equal aspect, metres)."""
    pts, counts = placed_outlines(model, cells.gcell, cells.xy, cells.yaw)
    ax.add_collection(PolyCollection(np.split(pts, np.cumsum(counts)[:-1]), facecolors=cell_colours(cells),
                                     edgecolors="#7a8793", linewidths=0.15))
    ax.set_aspect("equal")
    ax.legend(handles=[Patch(facecolor=c, edgecolor="#7a8793", label=k) for k, c in COLOURS.items()
                       if k != "frozen" or np.any(cells.status == FloeStatus.FROZEN)],
              loc="upper right", fontsize=7)


def cells_where(cells: Cells, keep: np.ndarray) -> Cells:
    """The cells where keep (bool, one per cell) is set."""
    return Cells(cells.gcell[keep], cells.xy[keep], cells.yaw[keep], cells.status[keep], cells.cause[keep])
