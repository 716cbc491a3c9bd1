"""Picture of a replay: the track over the ice field with the broken channel, and the
ship's speed and heading against logged time; the held gaps for the summary."""
from __future__ import annotations

import dataclasses

from pathlib import Path

import numpy as np
from matplotlib.patches import Rectangle

from bridge_node.replay.console import logged_text
from bridge_node.replay.engine import ReplayStats
from bridge_node.replay.track import Track
from bridge_node.reports.figures import plt, save_figure
from bridge_node.reports.ice import cells_where, draw_cells
from sim_core.frames.units import KNOT
from sim_core.ice.floes import FloeStatus
from sim_core.ice.tiles import placed_cells
from sim_core.world import WorldData, WorldModel

MAX_DRAWN_CELLS = 60_000  # beyond this only the broken cells are drawn, on squares for the placed tiles
MARGIN = 60.0  # m around the track in the plan view
ASPECT = 3.0  # the plan view's longest side over its shortest, at most
MIN_HEADING_SPAN = 10.0  # deg: the heading axis spans at least this
HELD = "#f2c14e"  # held gaps: shaded against time, dashed in the plan


def gap_summary(track: Track) -> dict:
    """The summary's view of a track's gaps: ``gaps_held`` (from, to, length s, why, the
    distance m the vessel would run through it at its logged speed) and how many gaps
    were interpolated (``gaps_interpolated``, with their total length s)."""
    absolute = track.log.absolute
    return {"gaps_held": [{"from": logged_text(g.start, absolute), "to": logged_text(g.end, absolute),
                           "s": round(g.end - g.start, 1), "why": g.reason, "run_m": round(g.run, 1)}
                          for g in track.gaps],
            "gaps_interpolated": {"count": len(track.bridged),
                                  "s": round(sum(g.end - g.start for g in track.bridged), 1)}}


def _held_in_plan(ax, track: Track, track_ne: np.ndarray) -> None:
    """Each held gap as a dashed line from the fix before it to the fix after it (the jump
    the ship makes at its end), labelled by its length."""
    for k, gap in enumerate(track.gaps):
        i = int(np.searchsorted(track.t, gap.start))
        if i + 1 >= len(track_ne):
            continue
        (n0, e0), (n1, e1) = track_ne[i], track_ne[i + 1]
        ax.plot([e0, e1], [n0, n1], "--", color="#b8860b", lw=1.6, zorder=5,
                label="gap held (jump at its end)" if k == 0 else None)
        ax.annotate(f"{gap.end - gap.start:.0f} s held", (0.5 * (e0 + e1), 0.5 * (n0 + n1)), fontsize=7,
                    color="#7a5a00", xytext=(4, 4), textcoords="offset points", zorder=6)


def _plan(ax, model: WorldModel, data: WorldData, xy: np.ndarray, track_ne: np.ndarray | None,
          track: Track | None) -> None:
    """Plan view (east right, north up, m): the field, the cells near the track coloured
    by what broke them (where the field lies at the end: a drifting field has moved on), the
    replayed track, the logged fixes and the held gaps."""
    scene, shift = model.scene, data.ice_frame.offset
    lo, hi = xy.min(axis=0) - MARGIN, xy.max(axis=0) + MARGIN
    span = hi - lo  # at most ASPECT times as tall as wide, or as wide as tall: a straight track stays readable
    grow = np.maximum(span.max() / ASPECT - span, 0.0)
    lo, hi = lo - 0.5 * grow, hi + 0.5 * grow
    ax.add_patch(Rectangle(tuple(shift), scene.nx * scene.side, scene.ny * scene.side, facecolor="#e8eef3",
                           edgecolor="#7a8793", lw=0.8, zorder=0, label="ice field (level ice)"))
    cells = placed_cells(model.ice, data.ice)
    cells = dataclasses.replace(cells, xy=cells.xy + shift)
    near = np.all((cells.xy >= lo) & (cells.xy <= hi), axis=1)
    if np.count_nonzero(near) > MAX_DRAWN_CELLS:
        for corner in data.ice.tiles.corner:
            ax.add_patch(Rectangle(tuple(corner + shift), scene.side, scene.side, facecolor="#f4f7fa", edgecolor="none",
                                   zorder=0))
        near &= cells.status != FloeStatus.INTACT
    if near.any():
        draw_cells(ax, model.ice, cells_where(cells, near))
    ax.plot(xy[:, 0], xy[:, 1], "-", color="#e07a1f", lw=1.0, label="replayed track")
    if track_ne is not None:
        ax.plot(track_ne[:, 1], track_ne[:, 0], ".", color="#222222", ms=2.5, label="logged fixes")
        if track is not None:
            _held_in_plan(ax, track, track_ne)
    ax.plot(*xy[0], "o", color="#2a9d4b", label="start")
    ax.plot(*xy[-1], "s", color="#c0392b", label="end")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    handles = ax.get_legend_handles_labels()[0]
    old = ax.get_legend()  # draw_floes' legend of cell colours, merged into one
    ax.legend(handles=handles + (old.legend_handles if old else []), fontsize=7, ncol=3, loc="upper center",
              bbox_to_anchor=(0.5, -0.08))  # below the plan: "best" would test every cell outline (seconds)


def plot_replay(model: WorldModel, data: WorldData, stats: ReplayStats, track: Track | None,
                track_ne: np.ndarray | None, title: str, path: Path) -> Path:
    """The replay's figure: plan view, speed and heading against logged time (s from the
    first step; gaps shaded). ``track_ne``: the logged fixes placed on the field (north,
    east m), or None. Returns the path."""
    rows = stats.samples()
    fig = plt.figure(figsize=(13, 7))
    grid = fig.add_gridspec(2, 2, width_ratios=(1.0, 1.25))
    ax, bx = fig.add_subplot(grid[:, 0]), fig.add_subplot(grid[0, 1])
    cx = fig.add_subplot(grid[1, 1], sharex=bx)
    t0 = rows[0, 0] if len(rows) else 0.0
    if len(rows):
        _plan(ax, model, data, rows[:, [2, 1]], track_ne, track)
        t = rows[:, 0] - t0
        bx.plot(t, rows[:, 4] / KNOT, color="#e07a1f", lw=1.0, label="replayed")
        heading = np.degrees(rows[:, 3])
        jumps = np.abs(np.diff(heading)) > 180.0  # break the line where it wraps through north
        cx.plot(t, np.where(np.concatenate([[False], jumps]), np.nan, heading), color="#e07a1f", lw=1.0,
                label="replayed")
    if track is not None:
        if track.speed is not None:
            bx.plot(track.speed.t - t0, track.speed.value / KNOT, ".", color="#222222", ms=2.5, label="logged")
        h = track.heading
        cx.plot(h.t - t0, np.degrees(h.value) % 360.0, ".", color="#222222", ms=2.5,
                label=f"logged ({track.heading_source})")
        for k, gap in enumerate(track.gaps):
            for a in (bx, cx):
                a.axvspan(gap.start - t0, gap.end - t0, color=HELD, alpha=0.35, lw=0,
                          label=f"gap held ({len(track.gaps)})" if k == 0 else None)
    bx.set_ylim(0.0, 1.15 * max(1.0, bx.get_ylim()[1]))
    bx.set_ylabel("speed over ground, kn")
    cx.set_ylabel("heading, deg")
    low, high = cx.get_ylim()
    pad = max(0.0, MIN_HEADING_SPAN - (high - low)) / 2.0
    cx.set_ylim(low - pad, high + pad)
    cx.set_xlabel("logged time from the start, s (shaded: gaps held)")
    for a in (bx, cx):
        a.grid(alpha=0.3)
        a.legend(fontsize=7, loc="upper right")
    gaps = f"; gaps {len(track.bridged)} interpolated, {len(track.gaps)} held" if track is not None else ""
    fig.suptitle(f"{title}: {stats.distance / 1852.0:.2f} nm, cells broken {stats.broken_by_hull} by the hull, "
                 f"{stats.broken_by_contact} by contact{gaps}", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)

