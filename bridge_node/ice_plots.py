"""Plan-view pictures of the ice: cells drawn at their current pose, coloured by state."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sim_core.floe_state import BY_CONTACT, FROZEN, INTACT, FloeState
from sim_core.ice_model import IceModel

COLOURS = {"intact": "#f4f7fa", "by hull": "#2f6690", "by contact": "#d1495b", "frozen": "#9aa5b1"}


def floe_polygons(model: IceModel, st: FloeState, rows: np.ndarray) -> list[np.ndarray]:
    """World outlines (m) of the given rows' cells."""
    out = []
    for i in rows:
        g = st.gcell[i]
        ring = model.outline[model.outline_start[g]:model.outline_start[g + 1]]
        c, s = np.cos(st.yaw[i]), np.sin(st.yaw[i])
        out.append(ring @ np.array([[c, s], [-s, c]]) + st.xy[i])
    return out


def row_colours(st: FloeState, rows: np.ndarray) -> list[str]:
    colours = []
    for i in rows:
        if st.status[i] == INTACT:
            colours.append(COLOURS["intact"])
        elif st.status[i] == FROZEN:
            colours.append(COLOURS["frozen"])
        else:
            colours.append(COLOURS["by contact"] if st.cause[i] == BY_CONTACT else COLOURS["by hull"])
    return colours


def draw_floes(ax, model: IceModel, st: FloeState, rows: np.ndarray | None = None) -> None:
    """Add the rows' cells to a matplotlib axis (equal aspect, metres)."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    rows = np.arange(st.n) if rows is None else rows
    ax.add_collection(PolyCollection(floe_polygons(model, st, rows), facecolors=row_colours(st, rows),
                                     edgecolors="#7a8793", linewidths=0.15))
    ax.set_aspect("equal")
    ax.legend(handles=[Patch(facecolor=c, edgecolor="#7a8793", label=k) for k, c in COLOURS.items()
                       if k != "frozen" or np.any(st.status[rows] == FROZEN)],
              loc="upper right", fontsize=7)


def save_figure(fig, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    import matplotlib.pyplot as plt

    plt.close(fig)

