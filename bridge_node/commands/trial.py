"""``icebridge trial turning|zigzag|crash-stop``: standard manoeuvring trials of a ship.

Prints the results with the IMO MSC.137(76) limits they are judged against, writes a track
plot PNG, and with ``--json`` prints one JSON object instead of the table.
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from rich.console import Console
from rich.table import Table

from bridge_node.node.config import load_config, load_ship
from bridge_node.common.errors import UserError
from bridge_node.reports.trials import plot_track
from sim_core.ship.model import compile_ship
from sim_core.studies.trials import (
    KNOT,
    TrialResult,
    crash_stop_trial,
    imo_limits,
    turning_trial,
    zigzag_trial,
)

MAX_ICE_H = 3.0  # m: Lindqvist's method is used up to here
MIN_SPEED_KN = 1.0  # kn: slower, a trial's manoeuvre takes days and its numbers lose meaning


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("kind", choices=("turning", "zigzag", "crash-stop"), help="which trial")
    p.add_argument("--ship", help="ship name (config/ships/NAME.toml; default: the config's ship)")
    p.add_argument("--rudder", type=float, help="rudder angle, deg (turning: 35, + starboard; zigzag: 10)")
    p.add_argument("--speed", type=float, help="approach speed, kn (default: the ship's service speed)")
    p.add_argument("--ice", type=float, default=0.0, help="level-ice thickness, m (default 0: open water)")
    p.add_argument("--json", action="store_true", help="print the results as one JSON object")
    p.add_argument("--out", default="out", help="folder for the track plot (default: out)")


def _check(name: str, value: float, lo: float, hi: float, lo_open: bool = False) -> None:
    ok = math.isfinite(value) and (value > lo if lo_open else value >= lo) and value <= hi
    if not ok:
        bracket = "(" if lo_open else "["
        raise UserError(f"{name} {value} is outside the allowed range {bracket}{lo}, {hi}]")


def criteria(result: TrialResult, length: float) -> list[tuple[str, float, float]]:
    """(name, value, IMO limit) for the criteria this trial can be judged on."""
    lim = imo_limits(length, result.speed)
    m, deg = result.metrics, round(math.degrees(abs(result.rudder)))
    if result.kind == "turning":
        out = [("advance_L", m["advance_L"], lim["advance_L"]),
               ("tactical_diameter_L", m["tactical_diameter_L"], lim["tactical_diameter_L"])]
        if deg == 10:
            out.append(("initial_turning_L", m["initial_turning_L"], lim["initial_turning_L"]))
        return out
    if result.kind == "zigzag" and deg == 10:
        return [("first_overshoot_deg", m["first_overshoot_deg"], lim["zigzag10_first_overshoot_deg"]),
                ("second_overshoot_deg", m["second_overshoot_deg"], lim["zigzag10_second_overshoot_deg"])]
    if result.kind == "zigzag" and deg == 20:
        return [("first_overshoot_deg", m["first_overshoot_deg"], lim["zigzag20_first_overshoot_deg"])]
    if result.kind == "crash-stop":
        return [("track_reach_L", m["track_reach_L"], lim["track_reach_L"])]
    return []


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    particulars = load_ship(args.ship or cfg.ship.name, args.config, "--ship" if args.ship else "ship.name")
    model = compile_ship(particulars, cfg.ice_material)
    speed_kn = particulars.service_speed_kn if args.speed is None else args.speed
    _check("--speed", speed_kn, MIN_SPEED_KN, 30.0)
    _check("--ice", args.ice, 0.0, MAX_ICE_H)
    limit = particulars.rudder.max_angle_deg
    speed = speed_kn * KNOT
    if args.kind == "turning":
        rudder = 35.0 if args.rudder is None else args.rudder
        _check("--rudder", abs(rudder), 0.0, limit, lo_open=True)
        result = turning_trial(model, speed, math.radians(rudder), args.ice)
    elif args.kind == "zigzag":
        rudder = 10.0 if args.rudder is None else args.rudder
        _check("--rudder", rudder, 0.0, limit, lo_open=True)
        result = zigzag_trial(model, speed, math.radians(rudder), args.ice)
    else:
        result = crash_stop_trial(model, speed, args.ice)
    plot = Path(args.out) / f"trial_{args.kind}_{particulars.name}.png"
    plot_track(result, model.L, plot)
    checks = criteria(result, model.L)
    summary = result.as_dict()
    summary["imo"] = {name: {"value": round(v, 4), "limit": round(lim, 4), "pass": bool(v <= lim)}
                      for name, v, lim in checks}
    summary["plot"] = str(plot)
    if args.json:
        print(json.dumps(summary))
        return 0
    console = Console()
    table = Table(title=f"{args.kind} trial: {particulars.name}, {result.speed / KNOT:.1f} kn, "
                        f"{'open water' if args.ice == 0 else f'{args.ice} m level ice'}")
    table.add_column("result")
    table.add_column("value", justify="right")
    table.add_column("IMO limit", justify="right")
    limits = {name: (lim, v <= lim) for name, v, lim in checks}
    for key, value in result.metrics.items():
        if key in limits:
            lim, ok = limits[key]
            note = f"{lim:.2f} {'pass' if ok else 'FAIL'}"
        else:
            note = ""
        table.add_row(key, f"{value:.3f}" if isinstance(value, float) else str(value), note)
    console.print(table)
    console.print(f"track plot: {plot}")
    return 0

