"""``icebridge experiment breaking``: the paper's breaking experiments (§3.1, §3.2) as numbers.

Steams the ship straight through breakable ice for every combination of thickness, collider
setup and speed; prints channel width, conduction-band width and broken cells per
combination; writes a plan view per combination and a summary plot; ``--json`` prints the
table as one JSON object instead.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from rich.console import Console
from rich.progress import Progress
from rich.table import Table

from bridge_node.node.config import load_config, load_ship
from bridge_node.node.errors import UserError
from bridge_node.reports.breaking import plot_breaking_run, plot_breaking_summary
from sim_core.fracture.colliders import COLLIDER_SETUPS
from sim_core.fracture.fragment_count import check_thickness
from sim_core.frames.units import KNOT
from sim_core.studies.breaking import BreakingRun, run_breaking


def _floats(text: str, name: str) -> list[float]:
    try:
        values = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise UserError(f"{name} {text!r}: expected comma-separated numbers") from None
    if not values:
        raise UserError(f"{name}: no values given")
    return values


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--thickness", default="0.2,0.5,1.0", help="ice thicknesses, m (comma-separated)")
    p.add_argument("--colliders", default="mesh,sphere,hybrid", help="collider setups (comma-separated)")
    p.add_argument("--speed", default="3,8", help="ship speeds, kn (comma-separated)")
    p.add_argument("--tile-side", type=float, default=None, help="tile side, m (default: config)")
    p.add_argument("--strip-tiles", type=int, default=2, help="tiles along the track (default 2)")
    p.add_argument("--json", action="store_true", help="print the results as one JSON object")
    p.add_argument("--out", default="out", help="folder for the pictures (default: out)")


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    ship = load_ship(cfg.ship.name, args.config)
    thicknesses = _floats(args.thickness, "--thickness")
    speeds = _floats(args.speed, "--speed")
    setups = [s.strip() for s in args.colliders.split(",") if s.strip()]
    for h in thicknesses:
        try:
            check_thickness(h)
        except ValueError as exc:
            raise UserError(f"--thickness: {exc}") from None
    for v in speeds:
        if not (0.5 <= v <= 20.0):
            raise UserError(f"--speed {v} kn is outside the allowed range [0.5, 20]")
    unknown = [s for s in setups if s not in COLLIDER_SETUPS]
    if unknown or not setups:
        raise UserError(f"--colliders {args.colliders!r}: allowed: {', '.join(COLLIDER_SETUPS)}")
    if not 1 <= args.strip_tiles <= 10:
        raise UserError(f"--strip-tiles {args.strip_tiles} is outside the allowed range [1, 10]")
    side = args.tile_side or cfg.fracture.tile_side
    if not 30.0 <= side <= 400.0:
        raise UserError(f"--tile-side {side} is outside the allowed range [30, 400] m")

    combos = [(h, c, v) for h in thicknesses for c in setups for v in speeds]
    runs: list[BreakingRun] = []
    console = Console(stderr=args.json)
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("breaking experiments", total=len(combos))
        for h, c, v in combos:
            runs.append(run_breaking(h, c, v * KNOT, ship_length=ship.length, beam=ship.beam, tile_side=side,
                                     strip_tiles=args.strip_tiles, seed=cfg.fracture.seed,
                                     material=cfg.ice_material, hull_friction=cfg.ice_material.hull_friction))
            progress.advance(task)
    out = Path(args.out)
    pictures = [plot_breaking_run(r, out) for r in runs]
    summary = out / "breaking_summary.png"
    plot_breaking_summary(runs, summary)
    if args.json:
        print(json.dumps({"runs": [r.as_dict() | {"picture": str(p)} for r, p in zip(runs, pictures)],
                          "summary_plot": str(summary)}))
        return 0
    table = Table(title=f"breaking experiment: {ship.name} (beam {ship.beam:.0f} m), "
                        f"{args.strip_tiles} x {side:.0f} m tiles")
    for col in ("h, m", "setup", "speed, kn", "channel, m", "band, m", "broken", "cells", "step, ms"):
        table.add_column(col, justify="right")
    for r in runs:
        d = r.as_dict()
        table.add_row(f"{r.thickness:.2f}", r.colliders, f"{d['speed_kn']:.1f}", f"{r.channel_width:.1f}",
                      f"{r.band_width:.2f}", str(r.broken), str(r.cells), f"{r.step_ms:.2f}")
    console.print(table)
    console.print(f"pictures: {out}/breaking_*.png; summary: {summary}")
    return 0

