"""``icebridge experiment breaking``: the paper's breaking experiments (§3.1, §3.2) as numbers.

Steams the ship straight through breakable ice for every combination of thickness, collider
setup and speed, once per seed; prints, as medians over the seeds, the conduction cracking
per 100 m of channel (cells broken by contact, their plan area), the channel width (m and
beams) and the conduction-band width (m and mean piece diameters); writes a plan view per
combination (its first seed) and a summary plot; ``--json`` prints every seed's figures and
the medians as one JSON object instead.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from bridge_node.node.config import load_config, load_ship
from bridge_node.common.errors import UserError
from bridge_node.reports.breaking import plot_breaking_run, plot_breaking_summary
from sim_core.fracture.colliders import COLLIDER_SETUPS
from sim_core.fracture.fragment_count import check_thickness
from sim_core.frames.units import KNOT
from sim_core.studies.breaking import BreakingMedians, run_breaking

MAX_SEEDS = 50
# table columns of the medians: heading, BreakingRun metric, format
_COLUMNS = (("contact\n/100 m", "contact_count", ".1f"), ("area\nm2/100 m", "contact_area", ".0f"),
            ("channel\nm", "channel_width", ".1f"), ("channel\n/beam", "channel_beams", ".2f"),
            ("band\nm", "band_width", ".2f"), ("band\n/piece", "band_pieces", ".2f"),
            ("piece\nm", "piece_diameter", ".2f"), ("step\nms", "step_ms", ".2f"))


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
    p.add_argument("--seeds", type=int, default=3,
                   help="pre-fracture seeds per combination, from the config's fracture.seed (default 3)")
    p.add_argument("--tile-side", type=float, default=None, help="tile side, m (default: config)")
    p.add_argument("--strip-tiles", type=int, default=2, help="tiles along the track (default 2)")
    p.add_argument("--json", action="store_true", help="print the results as one JSON object")
    p.add_argument("--out", default="out", help="folder for the pictures (default: out)")


def _checked(args: argparse.Namespace, cfg) -> tuple[list[float], list[float], list[str], float]:
    """The thicknesses (m), speeds (kn), collider setups and tile side (m) asked for;
    UserError for any outside its range."""
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
    if not 1 <= args.seeds <= MAX_SEEDS:
        raise UserError(f"--seeds {args.seeds} is outside the allowed range [1, {MAX_SEEDS}]")
    side = cfg.fracture.tile_side if args.tile_side is None else args.tile_side
    if not 30.0 <= side <= 400.0:
        raise UserError(f"--tile-side {side} is outside the allowed range [30, 400] m")
    return thicknesses, speeds, setups, side


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    ship = load_ship(cfg.ship.name, args.config)
    thicknesses, speeds, setups, side = _checked(args, cfg)
    seeds = [cfg.fracture.seed + k for k in range(args.seeds)]
    combos = [(h, c, v) for h in thicknesses for c in setups for v in speeds]
    results: list[BreakingMedians] = []
    console = Console(stderr=args.json)
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True) as progress:
        task = progress.add_task("breaking experiments", total=len(combos) * len(seeds))
        for h, c, v in combos:
            runs = []
            for k, seed in enumerate(seeds):
                progress.update(task, description=f"h {h:g} m, {c}, {v:g} kn, seed {k + 1}/{len(seeds)}")
                runs.append(run_breaking(h, c, v * KNOT, ship_length=ship.length, beam=ship.beam, tile_side=side,
                                         strip_tiles=args.strip_tiles, seed=seed, material=cfg.ice_material,
                                         dynamics=cfg.ice_dynamics, hull_friction=cfg.ice_material.hull_friction))
                progress.advance(task)
            results.append(BreakingMedians(runs))
    out = Path(args.out)
    pictures = [plot_breaking_run(m.runs[0], out) for m in results]
    summary = out / "breaking_summary.png"
    plot_breaking_summary(results, summary)
    if args.json:
        print(json.dumps({"seeds": seeds, "tile_side_m": side, "strip_tiles": args.strip_tiles,
                          "beam_m": ship.beam,
                          "configurations": [m.as_dict() | {"picture": str(p)} for m, p in zip(results, pictures)],
                          "summary_plot": str(summary)}))
        return 0
    table = Table(title=f"breaking experiment: {ship.name} (beam {ship.beam:.0f} m), "
                        f"{args.strip_tiles} x {side:.0f} m tiles, medians of {len(seeds)} seeds")
    for col in ("h\nm", "setup", "speed\nkn", *(head for head, _, _ in _COLUMNS)):
        table.add_column(col, justify="right", no_wrap=True)
    for m in results:
        table.add_row(f"{m.thickness:.2f}", m.colliders, f"{m.speed / KNOT:.1f}",
                      *(format(m.median(metric), spec) for _, metric, spec in _COLUMNS))
    console.print(table)
    console.print("contact: cells broken by contact (not by the hull) per 100 m of channel, over the middle half "
                  "of the strip; area: their plan area; band: per side; piece: mean piece diameter")
    console.print(f"seeds {', '.join(map(str, seeds))}; pictures (first seed): {out}/breaking_*.png; "
                  f"summary: {summary}")
    return 0
