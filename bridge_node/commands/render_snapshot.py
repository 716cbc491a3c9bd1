"""``icebridge render-snapshot``: the configured channels at one moment of the default
exercise, as PNGs (to set up a bridge's projectors). The exercise is first run, as fast as
it goes, for ``--time`` simulated seconds so there is a broken channel to see. With
``--classes``, each channel's class mask too."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.progress import Progress

from bridge_node.links.traffic_picture import TRAFFIC_DTYPE
from bridge_node.node.config import NodeConfig, load_config
from bridge_node.common.errors import UserError
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.open_channels import open_channels
from bridge_node.stream.world_view import WorldView
from sim_core.world import WorldEvents, WorldModel, snapshot, step

DT = 1 / 30


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--time", type=float, default=120.0, help="simulated seconds before the snapshot (default 120)")
    p.add_argument("--out", default="out", help="folder for the PNGs (default: out)")
    p.add_argument("--classes", action="store_true",
                   help="also write each channel's class mask (sky, water, level ice, crack, broken and submerged "
                        "floe, own ship, other vessel) as NAME_classes.png, with classes_legend.png")


def other_ships(cfg: NodeConfig, model: WorldModel, events: WorldEvents) -> np.ndarray:
    """The other own ships (``[[ships]]``) as the traffic rows (``TRAFFIC_DTYPE``) the
    renderer draws: in a run the stream carries them so, from each ship's traffic picture."""
    rows = [(ship.mmsi, r.outputs.east, r.outputs.north, r.outputs.heading, r.outputs.speed_over_ground,
             m.particulars.length, m.particulars.beam) for ship, r, m in zip(cfg.ships, events.others, model.ships[1:])]
    return np.array(rows, dtype=TRAFFIC_DTYPE).reshape(-1)


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    if not 0.0 <= args.time <= 3600.0:
        raise UserError(f"--time {args.time} s is outside the allowed range [0, 3600]")
    console = Console()
    with Progress(console=console, transient=True) as progress:
        model = build_world(cfg, args.config, progress)
        data = start_world(model, cfg, args.config)
        steps = round(args.time / DT)
        task = progress.add_task(f"running the exercise to t = {args.time:g} s", total=steps)
        for _ in range(steps):
            step(model, data, DT)
            progress.advance(task)
    channels = open_channels(cfg.render, model)
    view = WorldView()
    events = snapshot(model, data)
    view.apply(events)
    view.traffic = other_ships(cfg, model, events)
    channels.renderer.build_all(view)
    t0 = time.perf_counter()
    channels.render(view)
    ms = (time.perf_counter() - t0) * 1e3
    paths = channels.save_png(Path(args.out), "snapshot_")
    for t, path in zip([t for t in channels.targets if t.channel.output == "png"], paths):
        c = t.channel
        console.print(f"{c.name}: yaw {c.yaw_deg:+.0f} deg, pitch {c.pitch_deg:+.0f} deg, hfov {c.hfov_deg:.0f} deg, "
                      f"{c.width}x{c.height} -> {path}")
    console.print(f"{len(channels.targets)} channels in {ms:.0f} ms (first frame, uploads included)")
    if args.classes:
        masks = channels.save_class_pngs(view, Path(args.out), "snapshot_")
        console.print(f"class masks: {', '.join(str(p) for p in masks)}")
    return 0
