"""Benchmark: one ship-model step (60 Hz) and a 1-hour run.

Prints the median and p99 of one ``step`` at dt = 1/60 s (default ship, turning, full
ahead), the same step advanced with scipy's solve_ivp (RK45) over the same equations as a
straightforward baseline run in the same process, and simulated seconds per wall second for
a 1-hour run at 60 Hz.
Run: .venv/bin/python benchmarks/bench_ship_model.py
"""
from __future__ import annotations

import math
import os
import statistics
import time

import numpy as np
from rich.progress import track
from scipy.integrate import solve_ivp

from bridge_node.node.config import load_ship
from sim_core.ship.model import compile_ship, new_ship_data, order_rudder, state_derivatives, step

DT = 1.0 / 60.0


def main() -> None:
    model = compile_ship(load_ship("polar_cargo"))
    data = new_ship_data(model, 7.5)
    order_rudder(model, data, math.radians(20.0))
    times = []
    for _ in range(5000):
        t0 = time.perf_counter()
        step(model, data, DT)
        times.append(time.perf_counter() - t0)
    ours = statistics.median(times) * 1e6
    p99 = float(np.percentile(times, 99)) * 1e6

    state = [data.eta[0], data.eta[1], data.eta[5], data.nu[0], data.nu[1], data.nu[5]]
    base = []
    for _ in range(300):
        t0 = time.perf_counter()
        sol = solve_ivp(lambda t, s: state_derivatives(model, s, data.rudder, data.rps, (0, 0, 0), 0.0),
                        (0.0, DT), state, method="RK45", rtol=1e-8, atol=1e-8)
        state = sol.y[:, -1]
        base.append(time.perf_counter() - t0)
    baseline = statistics.median(base) * 1e6

    print(f"ship model benchmark, {os.cpu_count()} cores")
    print(f"one step at 60 Hz: median {ours:.1f} us, p99 {p99:.1f} us")
    print(f"baseline solve_ivp RK45 step: median {baseline:.1f} us ({baseline / ours:.1f}x slower)")

    data = new_ship_data(model, 7.5)
    steps = 3600 * 60
    t0 = time.perf_counter()
    for k in track(range(steps), description="1-hour run at 60 Hz"):
        if k % 3600 == 0:
            order_rudder(model, data, math.radians(20.0 * (-1) ** (k // 3600)))
        step(model, data, DT)
    wall = time.perf_counter() - t0
    print(f"1-hour run at 60 Hz: {wall:.1f} s wall, {3600.0 / wall:.0f} simulated s per wall s "
          f"({3600.0 / wall:.0f}x real time)")


if __name__ == "__main__":
    main()
