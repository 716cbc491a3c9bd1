"""Benchmark: the ice step with 1000, 3000 and 10000 live floes, and buoyancy alone.

A ship steams through a lane of breakable tiles until the wanted number of floes is
live (broken and simulated); tiles become breakable near the ship and freeze astern. Then the whole ice step is timed: hull contact, floe
contacts, breaking and buoyancy. Median and p99 are printed. Buoyancy alone is timed for
the numba kernel and for the plain numpy reference, run in the same process, with their
ratio. Targets (2 cores): buoyancy for 3000 floes <= 1.5 ms; ice step with 3000 live
floes <= 6 ms. Run: .venv/bin/python benchmarks/bench_ice_step.py
"""
from __future__ import annotations

import math
import os
import time

import numpy as np
from rich.progress import Progress

from sim_core.buoyancy import submerged_volume_centre, submerged_volume_centre_reference
from sim_core.floe_state import FREE
from sim_core.hull_contour import waterline_contour
from sim_core.ice_dynamics import HullMotion, freeze_tile, ice_step, new_ice_data, place_tile
from sim_core.ice_model import compile_ice_model
from sim_core.tile_template import build_tile

DT = 1 / 60
SPEED = 4.0  # m/s


def live_field(target: int, progress: Progress):
    """Ship zig-zagging north through a 300 m wide lane of 100 m tiles of 0.5 m ice until
    ``target`` floes are free. As the scene manager does, a tile row becomes breakable when
    the ship is 150 m from it and is frozen once it lies ``behind`` metres astern, so only
    the ice near the hull is in the contact engine."""
    model = compile_ice_model([build_tile(0.5, 11), build_tile(0.5, 12)])
    data = new_ice_data(model, waterline_contour(150.0, 24.0), 0.1)
    behind = {1000: 150.0, 3000: 400.0}.get(target, 1e9)
    x, y, heading = 150.0, -80.0, 0.5 * math.pi
    placed, frozen_rows = 0, 0
    task = progress.add_task(f"breaking ice to {target} live floes", total=target)
    while data.state.count(FREE) < target and y < 3000.0:
        while placed * 100.0 < y + 150.0:
            for col in range(3):
                place_tile(model, data, (placed + col) % 2, (col * 100.0, placed * 100.0), (placed * 3 + col) % 4)
            placed += 1
        while (frozen_rows + 1) * 100.0 < y - behind:
            for col in range(3):
                freeze_tile(data, 3 * frozen_rows + col)
            frozen_rows += 1
        heading = 0.5 * math.pi + 0.35 * math.sin(data.time / 25.0)
        v = SPEED * np.array([math.cos(heading), math.sin(heading)])
        ice_step(model, data, HullMotion(np.array([x, y]), heading, v, 0.0), DT)
        x, y = x + v[0] * DT, y + v[1] * DT
        progress.update(task, completed=min(target, data.state.count(FREE)))
    progress.remove_task(task)
    return model, data, (x, y, heading)


def time_steps(model, data, pose, n: int = 240) -> np.ndarray:
    x, y, heading = pose
    out = []
    for _ in range(n):
        v = SPEED * np.array([math.cos(heading), math.sin(heading)])
        t0 = time.perf_counter()
        ice_step(model, data, HullMotion(np.array([x, y]), heading, v, 0.0), DT)
        out.append(time.perf_counter() - t0)
        x, y = x + v[0] * DT, y + v[1] * DT
    return np.array(out) * 1e3


def bench_buoyancy(model, n: int) -> tuple[float, float]:
    rng = np.random.default_rng(0)
    cells = rng.integers(0, len(model.mass), n)
    args = (model.tris, model.tri_start, cells, model.z_equilibrium[cells] + rng.normal(0, 0.05, n),
            rng.normal(0, 0.05, n), rng.normal(0, 0.05, n))
    submerged_volume_centre(*args)
    fast = []
    for _ in range(50):
        t0 = time.perf_counter()
        submerged_volume_centre(*args)
        fast.append(time.perf_counter() - t0)
    ref = []
    for _ in range(3):
        t0 = time.perf_counter()
        submerged_volume_centre_reference(*args)
        ref.append(time.perf_counter() - t0)
    return float(np.median(fast) * 1e3), float(np.median(ref) * 1e3)


def main() -> None:
    print(f"ice step benchmark, {os.cpu_count()} cores, dt = 1/60 s, 0.5 m ice, ship at {SPEED} m/s")
    with Progress(transient=True) as progress:
        rows = []
        for target in (1000, 3000, 10000):
            model, data, pose = live_field(target, progress)
            ms = time_steps(model, data, pose)
            rows.append((data.state.count(FREE), data.state.n, ms))
    for live, total, ms in rows:
        print(f"ice step, {live:6d} live floes ({total} cells placed so far): median {np.median(ms):6.2f} ms, "
              f"p99 {np.percentile(ms, 99):6.2f} ms")
    for n in (1000, 3000, 10000):
        fast, ref = bench_buoyancy(model, n)
        print(f"buoyancy, {n:6d} floes: numba {fast:6.3f} ms, numpy reference {ref:7.2f} ms ({ref / fast:5.0f}x)")


if __name__ == "__main__":
    main()
