"""``icebridge prefracture``: build (or load) the tile templates for the configured field.

Without ``--thickness`` it builds every thickness class of the configured ice field (each
with ``fracture.variants`` variants) into the template library, showing progress, and
prints a table and writes a plan-view plot. With ``--thickness`` it builds one tile with the
given seed and options, and ``--export`` writes it as GLB.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from rich.console import Console
from rich.progress import Progress
from rich.table import Table

from bridge_node.library.gltf import export_glb
from bridge_node.library.templates import library_template
from bridge_node.node.config import load_config, resolve_path
from bridge_node.common.errors import UserError
from bridge_node.common.paths import writable_dir
from bridge_node.node.world_setup import field_tile_classes
from bridge_node.reports.prefracture import plot_templates
from sim_core.fracture.fragment_count import check_thickness
from sim_core.fracture.tile_template import TileTemplate, build_tile, plan_areas, template_seed


MAX_SEED = 2**64  # seeds are 0 .. 2**64 - 1 (numpy's generators take no negative seed)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--thickness", type=float, help="build one tile of this thickness, m")
    p.add_argument("--seed", type=int, help="random seed of that tile (default: from config)")
    p.add_argument("--mode", choices=("prism", "voronoi3d"), help="cell partition (default: config)")
    p.add_argument("--colliders", choices=("mesh", "sphere", "hybrid"), help="collider setup")
    p.add_argument("--export", metavar="FILE.glb", help="write the tile as glTF binary")
    p.add_argument("--cache-dir", help="template library folder (default: config paths.cache_dir)")
    p.add_argument("--rebuild", action="store_true", help="rebuild templates even if cached")
    p.add_argument("--out", default="out", help="folder for the plot (default: out)")


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    overrides = {k: v for k, v in (("cells", args.mode), ("colliders", args.colliders)) if v}
    settings = cfg.fracture.model_copy(update=overrides)
    console = Console()
    if args.thickness is not None:
        try:
            check_thickness(args.thickness)
        except ValueError as exc:
            raise UserError(f"--thickness: {exc}") from None
        if args.seed is not None and not 0 <= args.seed < MAX_SEED:
            raise UserError(f"--seed {args.seed}: a seed is an integer from 0 to 2**64 - 1")
        seed = args.seed if args.seed is not None else template_seed(settings.seed, args.thickness, 0)
        t0 = time.perf_counter()
        tile = build_tile(args.thickness, seed, settings, cfg.ice_material)
        rows = [(tile, 0, time.perf_counter() - t0, "built")]
        if args.export:
            export_glb(tile, args.export)
            console.print(f"wrote {args.export} ({tile.n_cells} cells)")
    else:
        cache = Path(args.cache_dir) if args.cache_dir else writable_dir(
            resolve_path(args.config, cfg.paths.cache_dir), "paths.cache_dir")
        jobs = [(h, v) for h in field_tile_classes(cfg, args.config)[1].tolist() if h > 0.0  # none for open water
                for v in range(settings.variants)]
        rows = []
        with Progress(console=console, transient=True) as progress:
            task = progress.add_task("pre-fracturing tiles", total=len(jobs))
            for h, v in jobs:
                t0 = time.perf_counter()
                tile, source = library_template(cache, h, v, settings, cfg.ice_material, args.rebuild)
                rows.append((tile, v, time.perf_counter() - t0, source))
                progress.advance(task)
        console.print(f"template library: {cache}")
        plot = Path(args.out) / "prefracture.png"
        plot_templates([r[0] for r in rows if r[1] == 0], plot)
        console.print(f"plan views: {plot}")
    console.print(results_table(rows, settings.cells, settings.colliders))
    return 0


def results_table(rows: list[tuple[TileTemplate, int, float, str]], mode: str, colliders: str) -> Table:
    table = Table(title=f"pre-fractured tiles ({mode} cells, {colliders} colliders)")
    for col in ("h, m", "variant", "cells", "mean area, m²", "mean mass, t", "spheres", "time, ms",
                "source"):
        table.add_column(col, justify="right")
    for tile, variant, seconds, source in rows:
        table.add_row(
            f"{tile.thickness:.2f}", str(variant), str(tile.n_cells),
            f"{plan_areas(tile.geometry).mean():.2f}", f"{tile.mass.mean() / 1000:.2f}",
            f"{int(tile.is_sphere.sum())}", f"{seconds * 1e3:.1f}", source,
        )
    return table

