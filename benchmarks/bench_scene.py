"""Benchmark: scene management per step, tile swaps, and the whole world step.

1. Scene management (quadtree query from the 34 contour points, swap decisions, reverse
   replacement) per step for 6.4 km, 64 km and 640 km square fields of 100 m tiles, the ship
   zig-zagging at 4 m/s with 60 Hz steps. Targets: <= 0.1 ms at 6.4 km, at most 2x growth per
   10x field side. Baseline in the same process: the brute-force scan of every tile centre.
2. Swap cost in the ice world: placing a breakable tile, freezing it, thawing it.
3. The default exercise's world step (live floes, swaps) on a straight transit, stepped as the
   node's loop steps (kernels warmed up, the collector's walk frozen): median and p99, and a
   plot of live fragments and step time against distance (paper Fig. 18, 19).
Run: .venv/bin/python benchmarks/bench_scene.py [--distance M]
"""
from __future__ import annotations

import argparse
import gc
import math
import os
import time
from pathlib import Path

import numpy as np
from rich.progress import Progress

from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world, warm_up
from bridge_node.reports.transit import plot_series
from sim_core.frames.hull_contour import waterline_contour
from sim_core.frames.ship_frame import ship_to_world
from bridge_node.node.realtime_loop import resident_mib
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.tiles import (
    advance,
    break_cells,
    freeze_tile,
    new_ice_data,
    place_tile,
    prepare_place,
    prepare_thaw,
    thaw_tile,
)
from sim_core.scene.quadtree import tiles_near_brute_force
from sim_core.scene.scene import SceneSettings, compile_scene, new_scene_data, update_scene
from sim_core.studies.transit import run_transit

B, L = 100.0, 150.0
CONTOUR = waterline_contour(L, 24.0)


def scene_cost(n: int, steps: int = 3000) -> tuple[np.ndarray, np.ndarray]:
    """Per-step update_scene times (ms) on an n x n tile field, and brute-force scan times."""
    model = compile_scene(SceneSettings(), np.zeros((n, n), np.uint8), np.array([0.5]), [np.array([0])], B, L)
    data = new_scene_data(model)
    north, east = 0.5 * n * B - 2000.0, 0.5 * n * B
    times, brute = [], []
    for k in range(steps):
        psi = 0.6 * math.sin(k / 600.0)
        north += 4.0 / 60 * math.cos(psi)
        east += 4.0 / 60 * math.sin(psi)
        pts = ship_to_world(CONTOUR, north, east, psi)
        t0 = time.perf_counter()
        update_scene(model, data, pts, np.array([east, north]))
        times.append(time.perf_counter() - t0)
        if k % 300 == 0 and n <= 640:
            t0 = time.perf_counter()
            tiles_near_brute_force(pts, model.radius, n, n, B)
            brute.append(time.perf_counter() - t0)
    return np.array(times[100:]) * 1e3, np.array(brute) * 1e3


def _steps_until_swapped(data, out: list) -> None:
    """Step the contact space until its swaps are done, recording each step's time."""
    while data.contacts.swaps_pending:
        t0 = time.perf_counter()
        data.contacts.step(1 / 60)
        out.append(time.perf_counter() - t0)


def swap_cost(world, repeats: int = 12) -> dict:
    """Costs (ms, one entry per repeat or per step) of one 100 m tile of the default
    exercise: building it ahead (whole, and per chunk of 64 cells as the step spreads it),
    switching the built tile in (the decision, then each step that moves its share of
    objects into the space), placing it unprepared (the previous design: build and switch in
    one step), freezing it with half its cells broken (the decision, then the steps that
    take its objects out), and switching in its prepared thaw."""
    out = {k: [] for k in ("prepare", "prepare_chunk", "switch", "switch_step", "unprepared", "freeze",
                           "freeze_step", "thaw", "thaw_step")}
    n_templates = len(world.ice.templates)
    for k in range(repeats):
        data = new_ice_data(world.ice, world.contour, 0.1)
        t0 = time.perf_counter()
        place_tile(world.ice, data, k % n_templates, (0.0, 0.0), k)
        data.contacts.step(1 / 60)  # the previous design switched a whole tile in one step
        out["unprepared"].append(time.perf_counter() - t0)
        prepared = prepare_place(world.ice, k % n_templates, (100.0, 0.0), k)
        t0 = time.perf_counter()
        while not prepared.done:
            t1 = time.perf_counter()
            advance(data, prepared, 64)
            out["prepare_chunk"].append(time.perf_counter() - t1)
        out["prepare"].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        index = place_tile(world.ice, data, k % n_templates, (100.0, 0.0), k, prepared)
        out["switch"].append(time.perf_counter() - t0)
        _steps_until_swapped(data, out["switch_step"])
        rows = data.tiles.rows(index)
        break_cells(data, rows[::2], BreakCause.HULL)
        t0 = time.perf_counter()
        freeze_tile(data, index)
        out["freeze"].append(time.perf_counter() - t0)
        _steps_until_swapped(data, out["freeze_step"])
        prepared = prepare_thaw(world.ice, data, index)
        while not prepared.done:
            advance(data, prepared, 64)
        t0 = time.perf_counter()
        thaw_tile(world.ice, data, index, prepared)
        out["thaw"].append(time.perf_counter() - t0)
        _steps_until_swapped(data, out["thaw_step"])
    return {k: np.array(v) * 1e3 for k, v in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--distance", type=float, default=1500.0, help="transit distance, m")
    ap.add_argument("--out", default="out", help="folder for the plot")
    args = ap.parse_args()
    print(f"scene benchmark, {os.cpu_count()} cores, 100 m tiles, 150 m ship, 60 Hz steps")
    rows = []
    for n in (64, 640, 6400):
        ms, brute = scene_cost(n)
        rows.append((n, ms, brute))
    base = np.median(rows[0][1])
    for n, ms, brute in rows:
        line = (f"scene update, {n * B / 1000:6.1f} km field ({n * n:>9d} tiles): "
                f"median {np.median(ms) * 1e3:6.1f} us, "
                f"p99 {np.percentile(ms, 99) * 1e3:6.1f} us, {np.median(ms) / base:4.2f}x the 6.4 km cost")
        if len(brute):
            line += f"; brute-force scan {np.median(brute):8.2f} ms ({np.median(brute) / np.median(ms):7.0f}x slower)"
        print(line)
    cfg = load_config()
    world = build_world(cfg, None)
    cost = swap_cost(world)
    cells = world.ice.templates[0].n_cells
    print(f"tile swaps in the ice world ({cells} cells per tile; {len(cost['switch'])} tiles; {os.cpu_count()} cores):")
    for name, ms in cost.items():
        print(f"  {name:13s} median {np.median(ms):6.2f} ms, p99 {np.percentile(ms, 99):6.2f} ms, max {ms.max():6.2f} ms")
    worst = max(cost["switch"].max() + cost["switch_step"].max(), cost["freeze_step"].max(), cost["thaw_step"].max())
    print(f"  the costliest step of any swap takes {worst / np.median(cost['unprepared']):.2f} of the step that "
          f"placed a tile unprepared in the previous design (same run)")
    data = start_world(world, cfg)
    # Step as the node's loop does (``realtime_loop.run_realtime``): every kernel loaded first, and
    # what was built so far out of the collector's walk. Without this the transit's longest step
    # (95-133 ms) was a full collection, which the node never has in a tick.
    warm_up(world, cfg)
    gc.collect()
    gc.freeze()
    rss_start = resident_mib()
    with Progress(transient=True) as progress:
        task = progress.add_task("default exercise transit", total=args.distance)
        series = run_transit(world, data, args.distance, 1 / 60, lambda d: progress.update(task, completed=d))
    s = series.summary(True)
    print(f"world step, default exercise, {s['distance_m']} m at 60 Hz: median {s['step_ms_median']} ms, "
          f"p99 {s['step_ms_p99']} ms, max {s['step_ms_max']} ms ({os.cpu_count()} cores); late switches "
          f"{data.late_switches}; live fragments max {s['max_live']}, plateau "
          f"{s['plateau_live_min']}..{s['plateau_live_max']}, frozen {s['final_frozen']}")
    st, frozen = data.ice.state, data.ice.frozen
    rss_end = resident_mib()
    if rss_start is not None and frozen.count:
        print(f"resident memory {rss_start:.0f} -> {rss_end:.0f} MiB over the transit, "
              f"{(rss_end - rss_start) / frozen.count * 1000:.2f} MiB per 1000 frozen floes (live floes and start-up "
              f"included, an upper bound); {frozen.count} frozen floes keep {frozen.nbytes() / frozen.count:.0f} "
              f"bytes each; {st.n} floe rows of {st.nbytes_per_row()} bytes for the live tiles "
              f"({st.count(FloeStatus.VACANT)} vacant)")
    plot = Path(args.out) / "bench_transit.png"
    plot_series(series, True, plot)
    print(f"plot: {plot}")


if __name__ == "__main__":
    main()
