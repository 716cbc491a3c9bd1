"""The node's real-time loop: links -> orders -> world step -> outputs, at a fixed rate.

Each tick polls the links and arbitrates (``LinkHub.poll``), steps the world by the tick's
period with the decided orders, notes the orders the ship refused, publishes the new ship
state on every link (``LinkHub.publish``) and hands the step's ``WorldEvents`` to the
listener (status display, renderers, recorders). A tick that overruns its period is
counted; the loop never catches up in a burst: tick k never starts before k periods after
the start, and if the loop falls more than a period behind, the schedule restarts from
now, so simulated time runs slower than real time and the real-time factor reports it.
Simulated time is always ticks x period.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from bridge_node.links.hub import LinkHub
from bridge_node.node.order_refusals import OrderRefusals
from sim_core.world import WorldData, WorldEvents, WorldModel, step


@dataclass
class LoopStats:
    """What the loop measured: per-tick wall times (ms), overruns, refused orders, and the
    ship's track."""

    ticks: int = 0
    overruns: int = 0
    wall_s: float = 0.0
    sim_s: float = 0.0
    step_ms: list = field(default_factory=list)
    track: list = field(default_factory=list)  # (sim time s, north m, east m, speed m/s, live floes)
    refusals: OrderRefusals = field(default_factory=OrderRefusals)

    def summary(self) -> dict:
        ms = np.array(self.step_ms) if self.step_ms else np.zeros(1)
        return {"ticks": self.ticks, "overruns": self.overruns, "wall_s": round(self.wall_s, 2),
                "sim_s": round(self.sim_s, 2), "real_time_factor": round(self.sim_s / max(self.wall_s, 1e-9), 3),
                "tick_ms_median": round(float(np.median(ms)), 2), "tick_ms_p99": round(float(np.percentile(ms, 99)), 2),
                "orders_rejected": dict(self.refusals.counts)}


def _tick(model: WorldModel, data: WorldData, hub: LinkHub, period: float, stats: LoopStats) -> WorldEvents:
    """One tick: poll and decide, step, note refusals, publish."""
    now = time.monotonic()
    events = step(model, data, period, hub.poll(now).controls)
    for alarm in stats.refusals.note(events.rejected, now):
        hub.raise_alarm(alarm, now)
    hub.publish(events.ship, now)
    return events


def run_realtime(model: WorldModel, data: WorldData, hub: LinkHub, rate_hz: float, duration: float | None,
                 on_events: Callable[[WorldEvents], None] | None = None,
                 should_stop: Callable[[], bool] = lambda: False) -> LoopStats:
    """Run at ``rate_hz`` until ``duration`` wall seconds have passed (None: until
    should_stop() or Ctrl-C); ``on_events`` gets every step's events."""
    period = 1.0 / rate_hz
    stats = LoopStats()
    start = time.monotonic()
    next_tick = start
    try:
        while (duration is None or time.monotonic() - start < duration) and not should_stop():
            t0 = time.monotonic()
            events = _tick(model, data, hub, period, stats)
            if on_events:
                on_events(events)
            stats.ticks += 1
            stats.sim_s = stats.ticks * period
            stats.step_ms.append((time.monotonic() - t0) * 1e3)
            if stats.ticks % max(1, round(rate_hz)) == 0:
                s = events.ship
                stats.track.append((events.time, s.north, s.east, s.speed_over_ground, events.floes_free))
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
