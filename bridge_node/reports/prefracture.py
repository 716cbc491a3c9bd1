"""Picture of the pre-fractured templates: one plan view per thickness class."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import PolyCollection

from bridge_node.reports.figures import plt, save_figure
from sim_core.fracture.tile_template import TileTemplate, plan_areas


def plot_templates(tiles: list[TileTemplate], path: Path) -> None:
    """Plan view of each thickness class's first template: cells outlined, sphere colliders
    shaded, with the cell count and mean size in the title."""

    n = len(tiles)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 4.4), squeeze=False)
    for ax, tile in zip(axes[0], tiles):
        g = tile.geometry
        polys = [g.footprint[g.foot_start[i]:g.foot_start[i + 1]] for i in range(tile.n_cells)]
        faces = np.where(tile.is_sphere, "#cfe3f2", "#ffffff")
        ax.add_collection(PolyCollection(polys, facecolors=faces, edgecolors="#2b5d7d", linewidths=0.3))
        ax.set_xlim(0, tile.side)
        ax.set_ylim(0, tile.side)
        ax.set_aspect("equal")
        ax.set_title(f"h = {tile.thickness:.2f} m: {tile.n_cells} cells, "
                     f"mean {plan_areas(g).mean():.1f} m²", fontsize=9)
        ax.set_xlabel("x, m")
    axes[0][0].set_ylabel("y, m")
    fig.suptitle("Pre-fractured tiles (shaded: sphere colliders)")
    fig.tight_layout()
    save_figure(fig, path)
