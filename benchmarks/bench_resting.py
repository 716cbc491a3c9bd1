"""Benchmark: floes at rest leaving the dynamic set, against the previous design, same run.

Two worlds of the default exercise steam the same transit at 60 Hz, one with
``ice_dynamics.rest_far_floes`` on (the default) and one with it off (every free floe in
the engine's dynamic set, the previous design). Their steps alternate, so both see the same
machine load. Printed: whole world step and bare engine step (median, p99, max), their
ratios, the live, resting and frozen floes, and the cells broken by hull and by contact
(the physics should stay the same). Run: .venv/bin/python benchmarks/bench_resting.py
[--distance M]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np
from rich.progress import Progress

from bridge_node.node.config import NodeConfig, load_config
from bridge_node.node.world_setup import build_world, start_world
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.tiles import broken_counts
from sim_core.world import step

DT = 1 / 60


class TimedWorld:
    """One world of a comparison, with its step and engine-step times (ms): the config's
    with these ``ice_dynamics`` settings changed."""

    def __init__(self, cfg: NodeConfig, **dynamics) -> None:
        cfg = cfg.model_copy(update={"ice_dynamics": cfg.ice_dynamics.model_copy(update=dynamics)})
        self.model = build_world(cfg, None)
        self.data = start_world(self.model, cfg)
        self.start = self.data.ship.eta[:2].copy()
        self.step_ms, self.engine_ms = [], []
        space = self.data.ice.contacts
        engine_step = space.engine_step

        def timed(dt: float) -> None:
            t0 = time.perf_counter()
            engine_step(dt)
            self.engine_ms.append((time.perf_counter() - t0) * 1e3)

        space.engine_step = timed

    def step(self) -> float:
        """One world step; returns the distance made good (m)."""
        t0 = time.perf_counter()
        step(self.model, self.data, DT)
        self.step_ms.append((time.perf_counter() - t0) * 1e3)
        return float(np.hypot(*(self.data.ship.eta[:2] - self.start)))


def figures(ms: list[float]) -> str:
    """Median, p99 and max of step times (ms), as text."""
    a = np.array(ms)
    return f"median {np.median(a):6.2f} ms, p99 {np.percentile(a, 99):6.2f} ms, max {a.max():6.1f} ms"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--distance", type=float, default=1500.0, help="transit distance, m")
    args = ap.parse_args()
    before, after = TimedWorld(load_config(), rest_far_floes=False), TimedWorld(load_config())
    with Progress(transient=True) as progress:
        task = progress.add_task("transit, resting off and on, steps alternating", total=args.distance)
        made = 0.0
        while made < args.distance:
            before.step()
            made = after.step()
            progress.update(task, completed=made)
    print(f"default exercise, {args.distance:.0f} m at 60 Hz, {os.cpu_count()} cores, steps alternating:")
    for w in (before, after):
        st = w.data.ice.state
        on = w.model.ice.settings.rest_far_floes
        print(f"  resting {'on ' if on else 'off'}: world step {figures(w.step_ms)}; engine {figures(w.engine_ms)}")
        print(f"              live {st.count(FloeStatus.FREE)}, resting {int(st.resting.sum())}, frozen "
              f"{w.data.ice.frozen.count}; broken by hull {broken_counts(w.data.ice)[BreakCause.HULL]}, "
              f"by contact {broken_counts(w.data.ice)[BreakCause.CONTACT]}")
    half = len(after.step_ms) // 2  # the second half: the channel astern has filled
    print(f"  ratio on/off (same run): world step median {np.median(after.step_ms) / np.median(before.step_ms):.2f}, "
          f"second half {np.median(after.step_ms[half:]) / np.median(before.step_ms[half:]):.2f}, "
          f"p99 {np.percentile(after.step_ms, 99) / np.percentile(before.step_ms, 99):.2f}; engine median "
          f"{np.median(after.engine_ms) / np.median(before.engine_ms):.2f}")


if __name__ == "__main__":
    main()
