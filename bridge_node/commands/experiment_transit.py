"""``icebridge experiment transit``: a straight transit through the configured field.

Prints and plots live fragments, frozen fragments and step time against distance travelled
(the paper's Fig. 18 and 19), plus a plan view of the channel; ``--json`` prints the series
and a summary instead.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.progress import Progress
from rich.table import Table

from bridge_node.node.config import load_config
from bridge_node.common.errors import UserError
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.reports.transit import PAPER_PLATEAU, plot_channel, plot_series
from sim_core.scene.scene import SceneSettings
from sim_core.studies.transit import run_transit


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--distance", type=float, default=1500.0, help="distance to travel, m (default 1500)")
    p.add_argument("--no-reverse", action="store_true", help="no reverse replacement (nothing frozen)")
    p.add_argument("--dt", type=float, default=1 / 30, help="world step, s (default 1/30)")
    p.add_argument("--json", action="store_true", help="print the series and a summary as one JSON object")
    p.add_argument("--out", default="out", help="folder for the plots (default: out)")


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    if not 10.0 <= args.distance <= 50_000.0:
        raise UserError(f"--distance {args.distance} m is outside the allowed range [10, 50000]")
    if not 0.005 <= args.dt <= 0.2:
        raise UserError(f"--dt {args.dt} s is outside the allowed range [0.005, 0.2]")
    reverse = not args.no_reverse
    cfg = cfg.model_copy(update={"scene": SceneSettings(**(cfg.scene.model_dump() | {"reverse_replacement": reverse}))})
    console = Console(stderr=args.json)
    with Progress(console=console, transient=True) as progress:
        model = build_world(cfg, args.config, progress)
        data = start_world(model, cfg, args.config)
        task = progress.add_task(f"transit, {'with' if reverse else 'without'} reverse replacement",
                                 total=args.distance)
        series = run_transit(model, data, args.distance, args.dt, lambda d: progress.update(task, completed=d))
    out = Path(args.out)
    suffix = "" if reverse else "_no_reverse"
    plot = out / f"transit{suffix}.png"
    plot_series(series, reverse, plot)
    plan = out / f"transit_channel{suffix}.png"
    plot_channel(model, data, plan)
    summary = series.summary(reverse) | {"paper_plateau": list(PAPER_PLATEAU), "plot": str(plot),
                                         "plan_view": str(plan)}
    if args.json:
        print(json.dumps({"summary": summary, "series": {
            "distance_m": np.round(series.distance, 2).tolist(), "live": series.live.tolist(),
            "frozen": series.frozen.tolist(), "live_tiles": series.live_tiles.tolist(),
            "step_ms": np.round(series.step_ms, 3).tolist()}}))
        return 0
    table = Table(title=f"transit: {cfg.ship.name}, {cfg.ice_field.thickness} m ice, "
                        f"reverse replacement {'on' if reverse else 'off'}")
    for col in ("distance, m", "live", "frozen", "breakable tiles", "step, ms (median of the span)"):
        table.add_column(col, justify="right")
    marks = np.linspace(0.0, series.distance[-1], 11)[1:]
    lo = 0
    for d in marks:
        hi = int(np.searchsorted(series.distance, d, side="right"))
        if hi <= lo:
            continue
        table.add_row(f"{d:.0f}", str(series.live[hi - 1]), str(series.frozen[hi - 1]),
                      str(series.live_tiles[hi - 1]), f"{np.median(series.step_ms[lo:hi]):.2f}")
        lo = hi
    console.print(table)
    console.print(f"live-fragment plateau over the last third: {summary['plateau_live_min']}..."
                  f"{summary['plateau_live_max']} (paper: {PAPER_PLATEAU[0]}..{PAPER_PLATEAU[1]}); "
                  f"step median {summary['step_ms_median']} ms, p99 {summary['step_ms_p99']} ms")
    console.print(f"plots: {plot}, {plan}")
    return 0

