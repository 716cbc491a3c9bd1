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

from bridge_node.config import load_config
from bridge_node.errors import UserError
from bridge_node.ice_plots import draw_floes, save_figure
from bridge_node.world_setup import build_world, start_world
from sim_core.ice_scene import SceneSettings
from sim_core.transit_experiment import TransitSeries, run_transit
from sim_core.world import WorldData, WorldModel

PAPER_PLATEAU = (2800, 3200)  # live fragments with the paper's reverse replacement


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
        data = start_world(model, cfg)
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


def plot_series(s: TransitSeries, reverse: bool, path: Path) -> None:
    """Fragments and step time against distance (paper Fig. 18 and 19)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    ax.plot(s.distance, s.live, label="live fragments (simulated)")
    ax.plot(s.distance, s.frozen, label="frozen fragments (channel astern)")
    ax.axhspan(*PAPER_PLATEAU, color="0.85", label="paper's plateau with reverse replacement")
    ax.set_ylabel("fragments")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    bx.plot(s.distance, s.step_ms, lw=0.5, color="0.4", label="world step")
    window = max(1, len(s.step_ms) // 100)
    bx.plot(s.distance, np.convolve(s.step_ms, np.ones(window) / window, mode="same"), color="C3",
            label=f"running mean ({window} steps)")
    bx.set_ylabel("step time, ms")
    bx.set_xlabel("distance travelled, m")
    bx.legend(fontsize=8)
    bx.grid(alpha=0.3)
    fig.suptitle(f"Transit, reverse replacement {'on (tiles frozen)' if reverse else 'off'}")
    fig.tight_layout()
    save_figure(fig, path)


def plot_channel(model: WorldModel, data: WorldData, path: Path) -> None:
    """Plan view of the placed tiles: the broken channel, live and frozen."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    st = data.ice.state
    broken = np.nonzero(st.cause != 0)[0]
    if len(broken) == 0:
        return
    lo, hi = st.xy[broken].min(axis=0) - 30.0, st.xy[broken].max(axis=0) + 30.0
    fig, ax = plt.subplots(figsize=(4.0, min(12.0, 1.5 + 4.0 * (hi[1] - lo[1]) / max(hi[0] - lo[0], 1.0))))
    near = np.nonzero(np.all((st.xy >= lo) & (st.xy <= hi), axis=1))[0]
    draw_floes(ax, model.ice, st, near)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    ax.set_title("broken channel (grey: frozen astern)", fontsize=9)
    save_figure(fig, path)
