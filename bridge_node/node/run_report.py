"""Picture of a real-time run: the ship's track and the tick wall times."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from bridge_node.node.realtime_loop import MEMORY_SERIES, LoopStats
from bridge_node.reports.figures import plt, save_figure


def plot_run(stats: LoopStats, path: Path) -> Path:
    """Track (north against east), tick wall time against simulated time, and the node's
    resident memory and C heap in use against the frozen floes it keeps."""
    fig, (ax, bx, cx) = plt.subplots(1, 3, figsize=(15, 4.5))
    if stats.track:
        tr = np.array(stats.track)
        ax.plot(tr[:, 2], tr[:, 1], "-", color="C0")
        ax.plot(tr[-1, 2], tr[-1, 1], "o", color="C3", label="end")
        ax.legend(fontsize=8)
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("ship's track")
    ax.grid(alpha=0.3)
    t = np.arange(1, len(stats.step_ms) + 1) * (stats.sim_s / max(stats.ticks, 1))
    bx.plot(t, stats.step_ms, lw=0.5, color="0.4")
    bx.axhline(1e3 * stats.sim_s / max(stats.ticks, 1), color="C3", ls="--", label="tick period")
    bx.set_xlabel("simulated time, s")
    bx.set_ylabel("tick wall time, ms")
    bx.set_title(f"{stats.ticks} ticks, {stats.overruns} overruns")
    bx.legend(fontsize=8)
    bx.grid(alpha=0.3)
    summary, x_label = stats.memory_summary(), "simulated time, s"
    for (key, col, label), colour in zip(MEMORY_SERIES, ("C2", "C1")):
        mem = np.array([(r[0], r[1], r[col]) for r in stats.memory if r[col] is not None]).reshape(-1, 3)
        if not len(mem):
            continue
        by_frozen = np.ptp(mem[:, 1]) > 0  # before any floe froze, against time
        slope = summary[f"{key}_mib_per_1000_frozen"]
        cx.plot(mem[:, 1 if by_frozen else 0], mem[:, 2], ".-", ms=2, lw=0.5, color=colour,
                label=label + (f": {slope} MiB per 1000 frozen floes" if slope is not None else ""))
        x_label = "frozen floes" if by_frozen else "simulated time, s (no floe frozen yet)"
    if cx.lines:
        cx.legend(fontsize=8)
    cx.set_xlabel(x_label)
    cx.set_title("memory of the node's process")
    cx.set_ylabel("MiB")
    cx.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)
