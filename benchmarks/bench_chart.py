"""Benchmark: an exercise's ice field set up from a SIGRID-3 chart (issue 26's target: 50
polygons over 20 km x 20 km in under 10 s).

A chart of 50 boxes (5 x 10, west to east and south to north from 74 N 20 E, 20 km x 20 km
in all) is written with pyshp; its egg codes cycle through ice free, fast ice of four stages
(grey, grey-white, thin and medium first-year) and 7/10 pack of small floes. An exercise
names it (``[ice_field] chart``) over a 20 km x 20 km field of 100 m tiles (40 000 tiles).
Timed, each stage separately: the config loaded (the chart read and checked), the world
built (regions in the local frame, each tile's thickness, the pre-fractured templates of each
thickness class) and started (the tiles around the ship prepared). Cold: an empty template
cache (every class pre-fractured); warm: the cache the cold run filled. Baseline in the same
run: the same field without the chart (one thickness).
Run: .venv/bin/python benchmarks/bench_chart.py
"""
from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import shapefile

from bridge_node.charts.sigrid3 import FIELDS
from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world

LAT0, LON0 = 74.0, 20.0
SIDE_M = 20_000.0
COLUMNS, ROWS = 5, 10
WGS84_PRJ = ('GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]],'
             'PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]]')
CODES = (
    {"POLY_TYPE": "W", "CT": "00"},
    {"POLY_TYPE": "I", "CT": "92", "SA": "84", "FA": "08"},  # fast grey ice
    {"POLY_TYPE": "I", "CT": "92", "SA": "85", "FA": "08"},  # grey-white
    {"POLY_TYPE": "I", "CT": "92", "SA": "87", "FA": "08"},  # thin first-year
    {"POLY_TYPE": "I", "CT": "92", "SA": "91", "FA": "08"},  # medium first-year
    {"POLY_TYPE": "I", "CT": "70", "SA": "87", "FA": "04"},  # 7/10 pack, small floes
)


def write_chart(folder: Path) -> Path:
    """The 50-box chart (WGS 84), returned as its .shp path."""
    dlat = SIDE_M / 111_320.0 / ROWS
    dlon = SIDE_M / (111_320.0 * 0.2756) / COLUMNS  # cos 74 deg = 0.2756
    base = folder / "chart"
    with shapefile.Writer(str(base), shapeType=shapefile.POLYGON) as w:
        for name in FIELDS:
            w.field(name, "C", size=2)
        for k in range(COLUMNS * ROWS):
            i, j = k % COLUMNS, k // COLUMNS
            lon0, lat0 = LON0 + i * dlon, LAT0 + j * dlat
            w.poly([[[lon0, lat0], [lon0, lat0 + dlat], [lon0 + dlon, lat0 + dlat], [lon0 + dlon, lat0],
                     [lon0, lat0]]])
            codes = CODES[k % len(CODES)]
            w.record(*[codes.get(name, "") for name in FIELDS])
    base.with_suffix(".prj").write_text(WGS84_PRJ)
    return base.with_suffix(".shp")


def exercise(folder: Path, cache: Path, chart: Path | None) -> Path:
    text = (f'[ship]\nname = "polar_cargo"\n[exercise]\norigin_latitude_deg = {LAT0}\n'
            f'origin_longitude_deg = {LON0}\nstart_north = 2000.0\nstart_east = 3000.0\n'
            f'[ice_field]\nwidth = {SIDE_M}\nheight = {SIDE_M}\nthickness = 0.5\n'
            + (f'chart = "{chart}"\n' if chart else "") + f'[paths]\ncache_dir = "{cache}"\n')
    path = folder / ("chart.toml" if chart else "plain.toml")
    path.write_text(text)
    return path


def set_up(config: Path) -> dict[str, float]:
    """Seconds to load the config, build the world and start it; and the world's thickness
    classes and the share of its tiles that are open water."""
    t0 = time.perf_counter()
    cfg = load_config(str(config))
    t1 = time.perf_counter()
    model = build_world(cfg, str(config))
    t2 = time.perf_counter()
    start_world(model, cfg)
    t3 = time.perf_counter()
    scene = model.scene
    water = float((scene.class_thickness[scene.tile_class] <= 0.0).mean())
    return {"load": t1 - t0, "build": t2 - t1, "start": t3 - t2, "total": t3 - t0,
            "classes": len(scene.class_thickness), "water": water}


def main() -> None:
    folder = Path(tempfile.mkdtemp(prefix="bench_chart_"))
    chart = write_chart(folder)
    print(f"{os.cpu_count()} CPUs; a chart of {COLUMNS * ROWS} polygons over {SIDE_M / 1e3:g} km x "
          f"{SIDE_M / 1e3:g} km, 100 m tiles")
    for cache_state in ("cold", "warm"):
        runs = {}
        for name, chart_path, cache in (("chart", chart, folder / "cache_chart"),
                                        ("plain", None, folder / "cache_plain")):
            runs[name] = set_up(exercise(folder, cache, chart_path))
        c, p = runs["chart"], runs["plain"]
        print(f"  {cache_state}: chart {c['total']:.2f} s (load {c['load']:.2f}, build {c['build']:.2f}, start "
              f"{c['start']:.2f}; {c['classes']} thickness classes, {c['water']:.0%} of the tiles open water); "
              f"without the chart {p['total']:.2f} s; ratio {c['total'] / p['total']:.2f}")


if __name__ == "__main__":
    main()
