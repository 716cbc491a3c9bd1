"""Picture of a manoeuvring trial: the track and heading, rudder and shaft speed over time."""
from __future__ import annotations

import math
from pathlib import Path

from bridge_node.reports.figures import plt, save_figure
from sim_core.frames.units import KNOT
from sim_core.studies.trials import TrialResult


def plot_track(result: TrialResult, length: float, path: Path) -> None:
    """Track in ship lengths (east right, north up) and heading, rudder and rpm over time."""
    tr = result.track
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.8))
    ax.plot(tr["east"] / length, tr["north"] / length, color="#1f4e79")
    ax.plot(0, 0, "o", color="#c00000", label="execute")
    ax.set_aspect("equal")
    ax.set_xlabel("east, ship lengths")
    ax.set_ylabel("north, ship lengths")
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    ax.set_title(f"{result.kind}: {result.ship}, {result.speed / KNOT:.1f} kn")
    bx.plot(tr["t"], [math.degrees(x) for x in tr["heading"]], label="heading change, deg")
    bx.plot(tr["t"], [math.degrees(x) for x in tr["rudder"]], label="rudder, deg")
    bx.plot(tr["t"], tr["rpm"], label="shaft, rpm")
    bx.set_xlabel("time, s")
    bx.grid(alpha=0.3)
    bx.legend(loc="best")
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
