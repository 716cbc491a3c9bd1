"""A straight transit through the ice field (paper §3.4, Fig. 18 and 19) as series.

The ship steams on its configured orders; after every world step the series records the
distance made good, the live (free, simulated) and frozen fragment counts, the breakable
tiles and the wall time of the step.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sim_core.ice.floes import FloeStatus
from sim_core.world import WorldData, WorldModel, step


@dataclass
class TransitSeries:
    """One row per world step."""

    distance: np.ndarray  # m made good from the start
    live: np.ndarray  # free floes simulated
    frozen: np.ndarray  # floes frozen in the channel astern
    live_tiles: np.ndarray  # breakable tiles
    step_ms: np.ndarray  # wall time of the world step, ms

    def summary(self, reverse: bool) -> dict:
        """Headline numbers; the plateau is the live count over the last third of the run."""
        last = self.distance >= self.distance[-1] * 2 / 3
        return {
            "distance_m": round(float(self.distance[-1]), 1), "steps": int(len(self.distance)),
            "reverse_replacement": reverse, "max_live": int(self.live.max()),
            "plateau_live_min": int(self.live[last].min()), "plateau_live_max": int(self.live[last].max()),
            "final_frozen": int(self.frozen[-1]), "max_live_tiles": int(self.live_tiles.max()),
            "step_ms_median": round(float(np.median(self.step_ms)), 2),
            "step_ms_p99": round(float(np.percentile(self.step_ms, 99)), 2),
            "step_ms_max": round(float(np.max(self.step_ms)), 2),
        }


def run_transit(model: WorldModel, data: WorldData, distance: float, dt: float,
                on_progress: Callable[[float], None] | None = None) -> TransitSeries:
    """Step the world until the ship has made good ``distance`` metres (or stopped for a
    simulated minute); on_progress gets the distance made good after each step."""
    start = data.ship.eta[:2].copy()
    rows = []
    stopped_since = None
    made = 0.0
    while made < distance:
        t0 = time.perf_counter()
        step(model, data, dt)
        ms = (time.perf_counter() - t0) * 1e3
        made = float(math.hypot(*(data.ship.eta[:2] - start)))
        st = data.ice.state
        rows.append((made, st.count(FloeStatus.FREE), data.ice.frozen.count, len(data.scene.live), ms))
        if on_progress:
            on_progress(made)
        if data.ship.nu[0] < 0.05:
            stopped_since = data.time if stopped_since is None else stopped_since
            if data.time - stopped_since > 60.0:
                break
        else:
            stopped_since = None
    a = np.array(rows, dtype=float).reshape(-1, 5)
    return TransitSeries(a[:, 0], a[:, 1].astype(int), a[:, 2].astype(int), a[:, 3].astype(int), a[:, 4])
