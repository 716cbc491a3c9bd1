"""Benchmark: the pack drifting as a whole against a fast field, same run.

Two worlds of the pack-ice exercise (``config/exercises/pack_ice.toml``: 7/10 pack, a 20 kn
east wind) steam north at half ahead at 60 Hz, one with ``ice_dynamics.field_drift`` on (as
the exercise has it: the whole field drifts, the floes at rest far from the hull with it)
and one with it off (the level ice and unsimulated tiles fast, every free floe drifting
through them as a body). Their steps alternate, so both see the same machine load.
Printed: world step and engine step (median, p99, max), their ratios, the live, resting
and frozen floes, and how far the field drifted. Run:
.venv/bin/python benchmarks/bench_drift.py [--seconds S]
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
from bench_resting import TimedWorld, figures
from rich.progress import Progress

from bridge_node.node.config import load_config
from sim_core.ice.floes import FloeStatus

DT = 1 / 60
EXERCISE = Path(__file__).resolve().parents[1] / "config" / "exercises" / "pack_ice.toml"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=240.0, help="simulated seconds")
    args = ap.parse_args()
    cfg = load_config(EXERCISE)
    fast, drifting = TimedWorld(cfg, field_drift=False), TimedWorld(cfg, field_drift=True)
    steps = round(args.seconds / DT)
    with Progress(transient=True) as progress:
        task = progress.add_task("pack in its wind, fast field and drifting field, steps alternating", total=steps)
        for k in range(steps):
            fast.step()
            drifting.step()
            if k % 60 == 0:
                progress.update(task, completed=k)
    print(f"pack-ice exercise, {args.seconds:.0f} s at 60 Hz, {cfg.exercise.wind_speed_kn:.0f} kn of wind, "
          f"{os.cpu_count()} cores, steps alternating:")
    for name, w in (("fast field    ", fast), ("drifting field", drifting)):
        st = w.data.ice.state
        print(f"  {name}: world step {figures(w.step_ms)}; engine {figures(w.engine_ms)}")
        drifted = np.round(w.data.ice_frame.offset, 1).tolist()
        print(f"                  live {st.count(FloeStatus.FREE)}, resting {int(st.resting.sum())}, frozen "
              f"{w.data.ice.frozen.count}; field drifted {drifted} m (east, north)")
    print(f"  ratio drifting/fast (same run): world step median "
          f"{np.median(drifting.step_ms) / np.median(fast.step_ms):.2f}, p99 "
          f"{np.percentile(drifting.step_ms, 99) / np.percentile(fast.step_ms, 99):.2f}; engine median "
          f"{np.median(drifting.engine_ms) / np.median(fast.engine_ms):.2f}")


if __name__ == "__main__":
    main()
