"""``icebridge trial turning|zigzag|crash-stop|hv``: standard manoeuvring trials of a ship,
and its h-v curve in level ice.

Prints the results with the IMO MSC.137(76) limits they are judged against (the h-v curve:
the attainable speed at full power against thickness, and where the ship sticks), writes a
plot PNG, and with ``--json`` prints one JSON object instead of the table.
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from rich.console import Console
from rich.table import Table

from bridge_node.node.config import load_config, load_ship
from bridge_node.common.errors import UserError
from bridge_node.reports.trials import plot_hv, plot_track
from sim_core.ship.model import ShipModel, compile_ship
from sim_core.studies.hv_curve import MAX_THICKNESS, hv_curve, sticking_thickness
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
HV_STEP = 0.1  # m: the h-v table's thickness step


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("kind", choices=("turning", "zigzag", "crash-stop", "hv"),
                   help="which trial (hv: attainable speed in level ice against thickness, at full power)")
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
    if args.kind == "hv":
        return _hv_trial(model, args)
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



def _hv_trial(model: ShipModel, args: argparse.Namespace) -> int:
    """The h-v curve from open water to beyond the sticking thickness, every HV_STEP m."""
    given = [name for name, value in (("--rudder", args.rudder), ("--speed", args.speed)) if value is not None]
    if given or args.ice:
        raise UserError(f"{', '.join(given + (['--ice'] if args.ice else []))}: not used by the hv trial, which runs "
                        "at full power through every thickness")
    ship = model.particulars.name
    sticks_at = sticking_thickness(model)
    top = min(MAX_THICKNESS, 1.2 * sticks_at)
    thickness = np.round(np.arange(0.0, top + HV_STEP, HV_STEP), 3)
    speed = hv_curve(model, np.minimum(thickness, MAX_THICKNESS))
    plot = Path(args.out) / f"trial_hv_{ship}.png"
    plot_hv(thickness, speed, sticks_at, ship, plot)
    rpm = model.rps_ahead_max * 60.0
    ice_class = model.particulars.ice.ice_class
    summary = {"kind": "hv", "ship": ship, "ice_class": ice_class, "full_ahead_rpm": round(rpm, 1),
               "sticking_thickness_m": sticks_at if math.isfinite(sticks_at) else None,
               "curve": [{"thickness_m": float(h), "speed_kn": round(float(v) / KNOT, 3)}
                         for h, v in zip(thickness, speed)], "plot": str(plot)}
    if args.json:
        print(json.dumps(summary))
        return 0
    table = Table(title=f"h-v curve: {ship} (ice class {ice_class}), full ahead ({rpm:.0f} rpm), level ice")
    table.add_column("thickness, m", justify="right")
    table.add_column("speed, kn", justify="right")
    for row in summary["curve"]:
        table.add_row(f"{row['thickness_m']:.2f}", f"{row['speed_kn']:.2f}")
    console = Console()
    console.print(table)
    console.print(f"sticks in level ice of {sticks_at:.2f} m" if math.isfinite(sticks_at)
                  else f"makes way through {MAX_THICKNESS:g} m, the method's limit")
    console.print(f"plot: {plot}")
    return 0
