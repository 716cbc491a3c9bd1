"""Pictures of a transit: fragments and step time against distance, and the channel's plan view."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from bridge_node.reports.figures import plt, save_figure
from bridge_node.reports.ice import cells_where, draw_cells
from sim_core.ice.tiles import placed_cells
from sim_core.studies.transit import TransitSeries
from sim_core.world import WorldData, WorldModel

PAPER_PLATEAU = (2800, 3200)  # live fragments with the paper's reverse replacement


def plot_series(s: TransitSeries, reverse: bool, path: Path) -> None:
    """Fragments and step time against distance (paper Fig. 18 and 19)."""
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    ax.plot(s.distance, s.live, label="live fragments (simulated)")
    ax.plot(s.distance, s.frozen, label="frozen fragments (channel astern)")
    ax.axhspan(*PAPER_PLATEAU, color="0.85", label="paper's plateau with reverse replacement")
    ax.set_ylabel("fragments")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    bx.plot(s.distance, s.step_ms, lw=0.5, color="0.4", label="world step")
    window = max(1, len(s.step_ms) // 100)
    bx.plot(s.distance, np.convolve(s.step_ms, np.ones(window) / window, mode="same"), color="C3",
            label=f"running mean ({window} steps)")
    bx.set_ylabel("step time, ms")
    bx.set_xlabel("distance travelled, m")
    bx.legend(fontsize=8)
    bx.grid(alpha=0.3)
    fig.suptitle(f"Transit, reverse replacement {'on (tiles frozen)' if reverse else 'off'}")
    fig.tight_layout()
    save_figure(fig, path)


def plot_channel(model: WorldModel, data: WorldData, path: Path) -> None:
    """Plan view of the placed tiles: the broken channel, live and frozen."""
    cells = placed_cells(model.ice, data.ice)
    broken = cells.cause != 0
    if not broken.any():
        return
    lo, hi = cells.xy[broken].min(axis=0) - 30.0, cells.xy[broken].max(axis=0) + 30.0
    fig, ax = plt.subplots(figsize=(4.0, min(12.0, 1.5 + 4.0 * (hi[1] - lo[1]) / max(hi[0] - lo[0], 1.0))))
    draw_cells(ax, model.ice, cells_where(cells, np.all((cells.xy >= lo) & (cells.xy <= hi), axis=1)))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    ax.set_title("broken channel (grey: frozen astern)", fontsize=9)
    save_figure(fig, path)
