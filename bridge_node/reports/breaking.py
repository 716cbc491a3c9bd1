"""Pictures of the breaking experiments: a plan view per run and a summary of widths."""
from __future__ import annotations

import math
from pathlib import Path

from bridge_node.reports.figures import plt, save_figure
from bridge_node.reports.ice import draw_floes
from sim_core.frames.units import KNOT
from sim_core.studies.breaking import BreakingRun


def plot_breaking_run(r: BreakingRun, out: Path) -> Path:
    """Plan view of one breaking run, cells coloured by what broke them; returns its path."""
    tile = r.model.templates[0].side
    length = len(r.data.tiles.template) * tile
    fig, ax = plt.subplots(figsize=(4.5, 1.2 + 4.5 * length / tile))
    draw_floes(ax, r.model, r.data.state)
    ax.set_xlim(0, tile)
    ax.set_ylim(0, length)
    ax.set_xlabel("x, m")
    ax.set_ylabel("y (track), m")
    ax.set_title(f"h {r.thickness} m, {r.colliders}, {r.speed / KNOT:.0f} kn\n"
                 f"channel {r.channel_width:.1f} m, band {r.band_width:.2f} m", fontsize=9)
    path = out / f"breaking_h{r.thickness:g}_{r.colliders}_{r.speed / KNOT:.0f}kn.png"
    save_figure(fig, path)
    return path


def plot_breaking_summary(runs: list[BreakingRun], path: Path) -> None:
    """Channel and conduction-band width against thickness, per collider setup and speed."""
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
    keys = sorted({(r.colliders, round(r.speed / KNOT, 1)) for r in runs})
    for setup, kn in keys:
        sel = sorted((r for r in runs if r.colliders == setup and math.isclose(r.speed / KNOT, kn, abs_tol=0.05)),
                     key=lambda r: r.thickness)
        h = [r.thickness for r in sel]
        ax.plot(h, [r.channel_width for r in sel], "o-", label=f"{setup}, {kn:g} kn")
        bx.plot(h, [r.band_width for r in sel], "o-", label=f"{setup}, {kn:g} kn")
    ax.set_xlabel("ice thickness, m")
    ax.set_ylabel("channel width, m")
    bx.set_xlabel("ice thickness, m")
    bx.set_ylabel("conduction band width, m (per side)")
    for a in (ax, bx):
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle("Breaking experiment: channel and conduction cracking")
    fig.tight_layout()
    save_figure(fig, path)
