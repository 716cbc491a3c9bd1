"""The node's real-time loop: links -> orders -> world step -> outputs, at a fixed rate.

Each tick polls the links and arbitrates (``LinkHub.tick``, which also publishes the
previous tick's ship state), steps the world by the tick's period, and hands the events to
the listeners (renderers, recorders). A tick that overruns its period is counted; the loop
never tries to catch up in a burst: if it falls more than a period behind, the schedule
restarts from now, so simulated time runs slower than real time and the real-time factor
reports it.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from bridge_node.link_hub import LinkHub
from sim_core.floe_state import FREE
from sim_core.ship_outputs import ShipOutputs, ship_outputs
from sim_core.world import WorldData, WorldEvents, WorldModel, step


@dataclass
class LoopStats:
    """What the loop measured: per-tick wall times (ms), overruns, and the ship's track."""

    ticks: int = 0
    overruns: int = 0
    wall_s: float = 0.0
    sim_s: float = 0.0
    step_ms: list = field(default_factory=list)
    track: list = field(default_factory=list)  # (sim time s, north m, east m, speed m/s, live floes)

    def summary(self) -> dict:
        ms = np.array(self.step_ms) if self.step_ms else np.zeros(1)
        return {"ticks": self.ticks, "overruns": self.overruns, "wall_s": round(self.wall_s, 2),
                "sim_s": round(self.sim_s, 2), "real_time_factor": round(self.sim_s / max(self.wall_s, 1e-9), 3),
                "tick_ms_median": round(float(np.median(ms)), 2), "tick_ms_p99": round(float(np.percentile(ms, 99)), 2)}


def run_realtime(model: WorldModel, data: WorldData, hub: LinkHub, rate_hz: float, duration: float | None,
                 origin: tuple[float, float], on_tick: Callable[[WorldData, WorldEvents, ShipOutputs], None] | None = None,
                 should_stop: Callable[[], bool] = lambda: False) -> LoopStats:
    """Run until ``duration`` wall seconds have passed (None: until should_stop() or Ctrl-C).
    origin: latitude and longitude of the exercise origin, rad."""
    period = 1.0 / rate_hz
    stats = LoopStats()
    start = time.monotonic()
    next_tick = start
    outputs = ship_outputs(data.ship, *origin)
    try:
        while (duration is None or time.monotonic() - start < duration) and not should_stop():
            t0 = time.monotonic()
            decision = hub.tick(outputs, t0)
            events = step(model, data, period, decision.controls)
            outputs = ship_outputs(data.ship, *origin)
            if on_tick:
                on_tick(data, events, outputs)
            spent = time.monotonic() - t0
            stats.ticks += 1
            stats.sim_s += period
            stats.step_ms.append(spent * 1e3)
            if stats.ticks % max(1, round(rate_hz)) == 0:
                stats.track.append((data.time, data.ship.eta[0], data.ship.eta[1], data.ship.nu[0],
                                    data.ice.state.count(FREE)))
            next_tick += period
            now = time.monotonic()
            if now > next_tick:
                stats.overruns += 1
                if now - next_tick > period:
                    next_tick = now  # fell behind: restart the schedule rather than burst
            else:
                time.sleep(next_tick - now)
    except KeyboardInterrupt:
        pass
    stats.wall_s = time.monotonic() - start
    return stats

