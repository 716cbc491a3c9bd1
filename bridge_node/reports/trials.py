"""Pictures of the trials: a manoeuvre's track and its heading, rudder and shaft speed over
time; the h-v curve in level ice."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

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


def plot_hv(thickness: np.ndarray, speed: np.ndarray, sticks_at: float, ship: str, path: Path) -> None:
    """The h-v curve: attainable speed (m/s, shown in kn) at full power against level-ice
    thickness (m), with the sticking thickness marked."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(thickness, speed / KNOT, color="#1f4e79", marker="o", markersize=3)
    if np.isfinite(sticks_at):
        ax.axvline(sticks_at, color="#c00000", linestyle="--", label=f"sticks at {sticks_at:.2f} m")
        ax.legend(loc="best")
    ax.set_xlabel("level-ice thickness, m")
    ax.set_ylabel("attainable speed at full power, kn")
    ax.set_ylim(bottom=0.0)
    ax.set_xlim(left=0.0)
    ax.grid(alpha=0.3)
    ax.set_title(f"h-v curve: {ship}")
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
