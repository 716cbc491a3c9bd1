"""Benchmark: the ice step with 1000, 3000 and 10000 live floes, against the bare engine.

A broken channel holding the wanted number of live floes (broken and simulated) is laid
ahead of a ship; then the whole ice step is timed while the ship steams into it: hull
contact, floe contacts, breaking and buoyancy. Inside the same steps the bare Chipmunk step
(``cpSpaceStep`` of the same space) is timed too, so the ratio of the two says what the
Python and numba glue around the engine costs, whatever the machine's speed. The field's
tiles are all in the engine before the timing starts (switching tiles in is timed in
``bench_scene.py``). Median and p99 are printed beside the core count, with three ratios:
of the medians, of the totals, and the median of the steps' own ratios. Where floes go to
rest within the timed steps (about half of them at 3000 floes, most at 10 000), the step
times fall from one level to another, and the two medians can land on different steps; the other two are what the
glue costs over the same steps, and the steps are also split by the share of the live
floes resting (under 10 %: the field as broken; over 80 %: come to rest). Buoyancy alone is timed
for the numba kernel and for the plain numpy reference, run in the same process, with
their ratio.
Targets: ice step <= 1.5 x the bare engine step; median within one 60 Hz period at 10 000
live floes. Floes at rest beyond ``rest_distance`` of the hull leave the dynamic set
(``sim_core/ice/resting.py``), which makes the engine step, and so the ratio's denominator,
smaller; the count of resting floes is printed. Run: .venv/bin/python benchmarks/bench_ice_step.py
"""
from __future__ import annotations

import math
import os
import time

import numpy as np
from rich.progress import Progress

from sim_core.fracture.tile_template import build_tile
from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice.buoyancy import submerged_volume_centre, submerged_volume_centre_reference
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import compile_ice_model
from sim_core.ice.step import HullMotion, ice_step, warm_up
from sim_core.ice.tiles import break_cells, new_ice_data, place_tile

DT = 1 / 60
SPEED = 4.0  # m/s


def live_field(target: int):
    """A broken channel with ``target`` free floes ahead of a ship. Tiles of 0.5 m ice are
    laid in a 300 m wide lane; the cells of a 60 m wide channel are broken free, row by row
    of tiles, until the target count is reached, and the tiles beyond it stay intact. The
    ship sits at the start of the channel, so the timed steps include hull contact,
    floe-floe contact, contact with the channel edge, breaking and buoyancy."""
    model = compile_ice_model([build_tile(0.5, 11), build_tile(0.5, 12)])
    data = new_ice_data(model, waterline_contour(150.0, 24.0), 0.1)
    st, row = data.state, 0
    while st.count(FloeStatus.FREE) < target:
        for col in range(3):
            place_tile(model, data, (row + col) % 2, (col * 100.0, row * 100.0), (row * 3 + col) % 4)
        rows = np.nonzero((st.status == FloeStatus.INTACT) & (np.abs(st.home[:, 0] - 150.0) < 30.0))[0]
        rows = rows[np.argsort(st.home[rows, 1])][: target - st.count(FloeStatus.FREE)]
        break_cells(data, rows, BreakCause.HULL)
        row += 1
    for col in range(3):  # intact ice ahead of the channel
        place_tile(model, data, (row + col) % 2, (col * 100.0, row * 100.0), col)
    warm_up(model, data)  # load the compiled kernels, as a world does before its first step
    data.contacts.switch_in_now()  # the whole field in the engine: tile swaps are timed in bench_scene.py
    return model, data, (150.0, 0.0, 0.5 * math.pi)


def time_steps(model, data, pose, n: int = 240) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wall times (ms) of n whole ice steps and of the bare engine step inside each, and the
    share of the live floes resting after each step."""
    x, y, heading = pose
    space = data.contacts
    engine_step, engine = space.engine_step, []

    def timed_engine_step(dt: float) -> None:
        t0 = time.perf_counter()
        engine_step(dt)
        engine.append(time.perf_counter() - t0)

    space.engine_step = timed_engine_step
    out, resting = [], []
    for _ in range(n):
        v = SPEED * np.array([math.cos(heading), math.sin(heading)])
        t0 = time.perf_counter()
        ice_step(model, data, (HullMotion(np.array([x, y]), heading, v, 0.0),), DT)
        out.append(time.perf_counter() - t0)
        resting.append(data.state.resting.sum() / max(data.state.count(FloeStatus.FREE), 1))
        x, y = x + v[0] * DT, y + v[1] * DT
    space.engine_step = engine_step
    return np.array(out) * 1e3, np.array(engine) * 1e3, np.array(resting)


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
    rows = []
    with Progress(transient=True) as progress:
        for target in progress.track((1000, 3000, 10000), description="ice step at 1000/3000/10000 floes"):
            model, data, pose = live_field(target)
            ms, engine, resting = time_steps(model, data, pose)
            rows.append((data.state.count(FloeStatus.FREE), int(data.state.resting.sum()), data.state.n, ms, engine,
                         resting))
    for live, rest, total, ms, engine, resting in rows:
        print(f"ice step, {live:6d} live floes, {rest} of them resting at the end ({total} cells placed): "
              f"median {np.median(ms):6.2f} ms, "
              f"p99 {np.percentile(ms, 99):6.2f} ms; bare engine median {np.median(engine):6.2f} ms; "
              f"ratio of medians {np.median(ms) / np.median(engine):4.2f}, of totals {ms.sum() / engine.sum():4.2f}, "
              f"median of the steps' {np.median(ms / engine):4.2f} ({os.cpu_count()} cores)")
        for name, steps in (("under 10 %", resting < 0.1), ("10-80 %", (resting >= 0.1) & (resting <= 0.8)),
                            ("over 80 %", resting > 0.8)):
            if steps.any():
                print(f"    {steps.sum():3d} steps with {name} of the live floes resting: median {np.median(ms[steps]):6.2f}"
                      f" ms, ratio of medians {np.median(ms[steps]) / np.median(engine[steps]):4.2f}, of totals "
                      f"{ms[steps].sum() / engine[steps].sum():4.2f}")
    for n in (1000, 3000, 10000):
        fast, ref = bench_buoyancy(model, n)
        print(f"buoyancy, {n:6d} floes: numba {fast:6.3f} ms, numpy reference {ref:7.2f} ms ({ref / fast:5.0f}x)")


if __name__ == "__main__":
    main()
