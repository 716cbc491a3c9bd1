"""Pictures of the breaking experiments: a plan view per run and a summary of the medians."""
from __future__ import annotations

import math
from pathlib import Path

from bridge_node.reports.figures import plt, save_figure
from bridge_node.reports.ice import draw_cells
from sim_core.frames.units import KNOT
from sim_core.ice.tiles import placed_cells
from sim_core.studies.breaking import BreakingMedians, BreakingRun

# summary panels: metric, axis label
_PANELS = (("contact_count", "cells broken by contact, per 100 m"),
           ("contact_area", "their plan area, m2 per 100 m"),
           ("channel_beams", "channel width / beam"),
           ("band_pieces", "conduction band, mean piece diameters per side"))


def plot_breaking_run(r: BreakingRun, out: Path) -> Path:
    """Plan view of one breaking run, cells coloured by what broke them; returns its path."""
    tile = r.model.templates[0].side
    length = len(r.data.tiles.template) * tile
    fig, ax = plt.subplots(figsize=(4.5, 1.2 + 4.5 * length / tile))
    draw_cells(ax, r.model, placed_cells(r.model, r.data))
    ax.set_xlim(0, tile)
    ax.set_ylim(0, length)
    ax.set_xlabel("x, m")
    ax.set_ylabel("y (track), m")
    ax.set_title(f"h {r.thickness} m, {r.colliders}, {r.speed / KNOT:.0f} kn, seed {r.seed}\n"
                 f"channel {r.channel_width:.1f} m, band {r.band_width:.2f} m, "
                 f"{r.contact_count:.0f} contact cells / 100 m", fontsize=9)
    path = out / f"breaking_h{r.thickness:g}_{r.colliders}_{r.speed / KNOT:.0f}kn.png"
    save_figure(fig, path)
    return path


def plot_breaking_summary(results: list[BreakingMedians], path: Path) -> None:
    """Conduction cracking, channel and band against thickness, per collider setup and
    speed: medians as lines, single seeds as dots."""
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    keys = sorted({(m.colliders, round(m.speed / KNOT, 1)) for m in results})
    for setup, kn in keys:
        sel = sorted((m for m in results if m.colliders == setup and math.isclose(m.speed / KNOT, kn, abs_tol=0.05)),
                     key=lambda m: m.thickness)
        h = [m.thickness for m in sel]
        for ax, (metric, _) in zip(axes.flat, _PANELS):
            line, = ax.plot(h, [m.median(metric) for m in sel], "o-", label=f"{setup}, {kn:g} kn")
            for m in sel:
                ax.plot([m.thickness] * len(m.runs), [getattr(r, metric) for r in m.runs], ".",
                        color=line.get_color(), alpha=0.35)
    for ax, (_, label) in zip(axes.flat, _PANELS):
        ax.set_xlabel("ice thickness, m")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    seeds = len(results[0].runs) if results else 0
    fig.suptitle(f"Breaking experiment: conduction cracking, channel and band (medians of {seeds} seeds)")
    fig.tight_layout()
    save_figure(fig, path)
