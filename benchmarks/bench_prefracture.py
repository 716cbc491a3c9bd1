"""Benchmark: building one 100 m x 100 m tile, and loading a stored template.

Prints the median over several runs for h = 0.2, 0.5, 1.0 m in both cell modes, with the
ratio against a straightforward baseline run in the same process:
  prism      scipy.spatial.Voronoi of the fully mirrored 2D seeds, one Python pass per region
  voronoi3d  scipy.spatial.Voronoi of the fully mirrored 3D seeds (6 faces), ConvexHull per region
Targets (2 cores): prism at h = 1.0 m in 25 ms or less; loading a template in 5 ms or less.
Run: .venv/bin/python benchmarks/bench_prefracture.py
"""
from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull, Voronoi

from bridge_node.library.templates import load_template, save_template
from sim_core.fracture.fragment_count import seed_count_range
from sim_core.fracture.tile_template import FractureSettings, build_tile

SIDE = 100.0


def median_ms(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def mirror_all(p: np.ndarray, hi: np.ndarray) -> np.ndarray:
    parts = [p]
    for ax in range(p.shape[1]):
        for b in (0.0, hi[ax]):
            q = p.copy()
            q[:, ax] = 2 * b - q[:, ax]
            parts.append(q)
    return np.vstack(parts)


def baseline_prism(h: float, seed: int) -> float:
    rng = np.random.default_rng(seed)
    lo, hi = seed_count_range(h)
    xy = rng.uniform(0, SIDE, (int(rng.integers(lo, hi + 1)), 2))
    vor = Voronoi(mirror_all(xy, np.array([SIDE, SIDE])))
    total = 0.0
    for i in range(len(xy)):
        ring = vor.vertices[vor.regions[vor.point_region[i]]]
        ring = ring[ConvexHull(ring).vertices]
        x, y = ring[:, 0], ring[:, 1]
        total += 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) * h
    return total


def baseline_3d(h: float, seed: int) -> float:
    rng = np.random.default_rng(seed)
    lo, hi = seed_count_range(h)
    n = int(rng.integers(lo, hi + 1))
    pts = np.column_stack([rng.uniform(0, SIDE, (n, 2)), rng.uniform(0, h, n)])
    vor = Voronoi(mirror_all(pts, np.array([SIDE, SIDE, h])))
    return sum(ConvexHull(vor.vertices[vor.regions[vor.point_region[i]]]).volume for i in range(n))


def main() -> None:
    print(f"pre-fracture benchmark, {os.cpu_count()} cores; median ms of one 100 m tile")
    print(f"{'mode':10s} {'h, m':>5s} {'cells':>6s} {'ours ms':>9s} {'baseline ms':>12s} {'speed-up':>9s}")
    for mode, baseline, repeats in (("prism", baseline_prism, 9), ("voronoi3d", baseline_3d, 3)):
        settings = FractureSettings(cells=mode)
        for h in (0.2, 0.5, 1.0):
            tile = build_tile(h, 1, settings)
            vol = tile.geometry.volume.sum()
            assert abs(baseline(h, 1) - vol) < 1e-6 * vol  # same partition as the baseline
            ours = median_ms(lambda: build_tile(h, 1, settings), repeats)
            base = median_ms(lambda: baseline(h, 1), max(2, repeats // 3))
            print(f"{mode:10s} {h:5.1f} {tile.n_cells:6d} {ours:9.1f} {base:12.1f} {base / ours:8.1f}x")
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "t.npz"
        tile = build_tile(1.0, 1)
        save_template(path, tile)
        load = median_ms(lambda: load_template(path), 21)
        rebuild = median_ms(lambda: build_tile(1.0, 1), 5)
    print(f"load stored template (h = 1.0 m, {tile.n_cells} cells): {load:.2f} ms "
          f"(rebuild {rebuild:.1f} ms, {rebuild / load:.1f}x slower)")


if __name__ == "__main__":
    main()
