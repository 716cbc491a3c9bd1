"""``icebridge run``: the node. Links -> orders -> ship -> ice world -> outputs, in real time.

Shows a live status line; at the end prints a summary and writes the ship's track and the
tick times as plots. With ``--frames-every S`` it also renders the projector channels
every S simulated seconds to PNG frames (offscreen; a frame costs the loop its render
time). Ctrl-C (or SIGTERM) ends the run cleanly.
"""
from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.live import Live

from bridge_node.config import load_config, new_session_dir
from bridge_node.errors import UserError
from bridge_node.ice_plots import save_figure
from bridge_node.link_hub import LinkHub
from bridge_node.realtime_loop import LoopStats, run_realtime
from bridge_node.render_snapshot_command import open_renderer
from bridge_node.world_setup import build_world, start_world, warm_up
from sim_core.floe_state import FREE, FROZEN
from sim_core.manoeuvring_trials import KNOT


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--rate", type=float, default=None, help="world steps per second (default: config)")
    p.add_argument("--no-record", action="store_true", help="do not record the link traffic")
    p.add_argument("--json", action="store_true", help="end with one JSON summary")
    p.add_argument("--out", default="out", help="folder for the plots and frames (default: out)")
    p.add_argument("--frames-every", type=float, default=None, metavar="S",
                   help="also render the projector channels every S simulated seconds to OUT/frames/ (PNG)")


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    if args.duration is not None and not 0.0 < args.duration <= 7 * 86400.0:
        raise UserError(f"--duration {args.duration} s is outside the allowed range (0, 604800]")
    rate = args.rate if args.rate is not None else cfg.realtime.rate_hz
    if not 5.0 <= rate <= 120.0:
        raise UserError(f"--rate {rate} Hz is outside the allowed range [5, 120]")
    if args.frames_every is not None and not 0.1 <= args.frames_every <= 3600.0:
        raise UserError(f"--frames-every {args.frames_every} s is outside the allowed range [0.1, 3600]")
    console = Console(stderr=args.json)
    with console.status("loading the exercise"):
        model = build_world(cfg, args.config)
        warm_up(model, cfg)
        data = start_world(model, cfg)
    record = None
    if not args.no_record:
        record = new_session_dir(cfg, args.config)
    hub = LinkHub(cfg, args.config, record)
    origin = (math.radians(cfg.exercise.origin_latitude_deg), math.radians(cfg.exercise.origin_longitude_deg))
    shown = [0.0]
    channels = open_renderer(cfg, model) if args.frames_every is not None else None
    frames = {"next": 0.0, "written": 0}
    hub.open()
    try:
        with Live(console=console, refresh_per_second=4, transient=True) as live:
            def on_tick(d, events, out) -> None:
                if channels is not None and d.time >= frames["next"]:
                    frames["next"] += args.frames_every
                    channels.render(d)
                    channels.save_png(Path(args.out) / "frames", f"t{d.time:08.2f}_")
                    frames["written"] += 1
                now = time.monotonic()
                if now - shown[0] > 0.25:
                    shown[0] = now
                    st = d.ice.state
                    live.update(
                        f"t {d.time:7.1f} s | N {out.north:8.1f} m E {out.east:8.1f} m | hdg "
                        f"{math.degrees(out.heading):5.1f} deg | {out.speed_over_ground / KNOT:4.1f} kn | "
                        f"rudder {math.degrees(out.rudder_angle):+5.1f} | live floes {st.count(FREE)} | "
                        f"frozen {st.count(FROZEN)} | alarms {len(hub.active_alarms)}")
            stats = run_realtime(model, data, hub, rate, args.duration, origin, on_tick)
    finally:
        links = [link.health().as_dict() for link in hub.links]
        hub.close()
    out = Path(args.out)
    plot = out / "run.png"
    plot_run(stats, plot)
    summary = stats.summary() | {
        "rate_hz": rate, "live_floes": data.ice.state.count(FREE), "frozen_floes": data.ice.state.count(FROZEN),
        "north_m": round(float(data.ship.eta[0]), 1), "east_m": round(float(data.ship.eta[1]), 1),
        "speed_kn": round(float(data.ship.nu[0]) / KNOT, 2), "alarms": [a.text for a in hub.active_alarms.values()],
        "links": links, "plot": str(plot), "frames_rendered": frames["written"],
        "record": str(record) if record else None,
    }
    if args.json:
        print(json.dumps(summary))
        return 0
    for key, value in summary.items():
        console.print(f"{key}: {value}")
    return 0


def plot_run(stats: LoopStats, path: Path) -> None:
    """Track (north against east) and tick wall time against simulated time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.5))
    if stats.track:
        tr = np.array(stats.track)
        ax.plot(tr[:, 2], tr[:, 1], "-", color="C0")
        ax.plot(tr[-1, 2], tr[-1, 1], "o", color="C3", label="end")
        ax.legend(fontsize=8)
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("ship's track")
    ax.grid(alpha=0.3)
    t = np.arange(1, len(stats.step_ms) + 1) * (stats.sim_s / max(stats.ticks, 1))
    bx.plot(t, stats.step_ms, lw=0.5, color="0.4")
    bx.axhline(1e3 * stats.sim_s / max(stats.ticks, 1), color="C3", ls="--", label="tick period")
    bx.set_xlabel("simulated time, s")
    bx.set_ylabel("tick wall time, ms")
    bx.set_title(f"{stats.ticks} ticks, {stats.overruns} overruns")
    bx.legend(fontsize=8)
    bx.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)
