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

from rich.console import Console
from rich.live import Live

from bridge_node.links.hub import LinkHub
from bridge_node.node.config import load_config, new_session_dir
from bridge_node.node.errors import UserError
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import build_world, start_world, warm_up
from bridge_node.render.open_channels import open_channels
from bridge_node.render.world_view import WorldView
from bridge_node.reports.run import plot_run
from sim_core.frames.units import KNOT
from sim_core.world import WorldEvents, snapshot


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--rate", type=float, default=None, help="world steps per second (default: config)")
    p.add_argument("--no-record", action="store_true", help="do not record the link traffic")
    p.add_argument("--json", action="store_true", help="end with one JSON summary")
    p.add_argument("--out", default="out", help="folder for the plots and frames (default: out)")
    p.add_argument("--frames-every", type=float, default=None, metavar="S",
                   help="also render the projector channels every S simulated seconds to OUT/frames/ (PNG)")


class _Frames:
    """Projector frames every ``every`` simulated seconds, from the published events."""

    def __init__(self, cfg, model, every: float, folder: Path) -> None:
        self.channels, self.every, self.folder = open_channels(cfg, model), every, folder
        self.view = WorldView()
        self.next, self.written = 0.0, 0

    def __call__(self, events: WorldEvents) -> None:
        self.view.apply(events)
        if events.time >= self.next:
            self.next += self.every
            self.channels.render(self.view)
            self.channels.save_png(self.folder, f"t{events.time:08.2f}_")
            self.written += 1


def status_line(events: WorldEvents, alarms: int) -> str:
    """One line of the live display: time, position, heading, speed, rudder, floes, alarms."""
    s = events.ship
    return (f"t {events.time:7.1f} s | N {s.north:8.1f} m E {s.east:8.1f} m | hdg {math.degrees(s.heading):5.1f} deg"
            f" | {s.speed_over_ground / KNOT:4.1f} kn | rudder {math.degrees(s.rudder_angle):+5.1f} | live floes "
            f"{events.floes_free} | frozen {events.floes_frozen} | alarms {alarms}")


def _check(args: argparse.Namespace, rate: float) -> None:
    if args.duration is not None and not 0.0 < args.duration <= 7 * 86400.0:
        raise UserError(f"--duration {args.duration} s is outside the allowed range (0, 604800]")
    if not 5.0 <= rate <= 120.0:
        raise UserError(f"--rate {rate} Hz is outside the allowed range [5, 120]")
    if args.frames_every is not None and not 0.1 <= args.frames_every <= 3600.0:
        raise UserError(f"--frames-every {args.frames_every} s is outside the allowed range [0.1, 3600]")


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    rate = args.rate if args.rate is not None else cfg.realtime.rate_hz
    _check(args, rate)
    console = Console(stderr=args.json)
    with console.status("loading the exercise"):
        model = build_world(cfg, args.config)
        warm_up(model, cfg)
        data = start_world(model, cfg)
    record = None if args.no_record else new_session_dir(cfg, args.config)
    frames = _Frames(cfg, model, args.frames_every, Path(args.out) / "frames") if args.frames_every else None
    last: list[WorldEvents] = [snapshot(model, data)]
    shown = [0.0]
    with LinkHub(cfg.links, cfg.arbitration, record) as hub, \
            Live(console=console, refresh_per_second=4, transient=True) as live:
        def on_events(events: WorldEvents) -> None:
            last[0] = events
            if frames:
                frames(events)
            if time.monotonic() - shown[0] > 0.25:
                shown[0] = time.monotonic()
                live.update(status_line(events, len(hub.active_alarms)))
        stats = run_realtime(model, data, hub, rate, args.duration, on_events)
        links = [link.health().as_dict() for link in hub.links]
        alarms = [a.text for a in hub.active_alarms.values()]
    plot = plot_run(stats, Path(args.out) / "run.png")
    end = last[0].ship
    summary = stats.summary() | {
        "rate_hz": rate, "live_floes": last[0].floes_free, "frozen_floes": last[0].floes_frozen,
        "north_m": round(end.north, 1), "east_m": round(end.east, 1),
        "speed_kn": round(end.speed_longitudinal / KNOT, 2), "alarms": alarms,
        "links": links, "plot": str(plot), "frames_rendered": frames.written if frames else 0,
        "record": str(record) if record else None,
    }
    if args.json:
        print(json.dumps(summary))
        return 0
    for key, value in summary.items():
        console.print(f"{key}: {value}")
    return 0
