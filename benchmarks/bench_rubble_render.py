"""Benchmark: what brash and ridges cost the projector channels.

The ready exercises ``config/exercises/ridge_field.toml`` and ``brash_channel.toml``, each
against the same exercise without its ridges or brash (their level ice alone), frames
interleaved in one process so that the machine's load falls on both alike: three channels
at 1280x720 (port, centre, starboard of the default channels) looking at the ice from the
start position, offscreen on EGL (here Mesa's llvmpipe). Also: the first frame (the sails
of every tile within ``render.sail_distance_m`` built), and the sails' tiles and
triangles. Prints medians and p99 of the frame time, the ratio rubble/none, and the core
count.
Run: .venv/bin/python benchmarks/bench_rubble_render.py [--frames N]
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, create_context
from bridge_node.render.renderer import SceneRenderer
from bridge_node.stream.world_view import WorldView
from sim_core.world import snapshot

EXERCISES = ("ridge_field", "brash_channel")
REPO = Path(__file__).resolve().parent.parent


def channels_of(cfg, config_path):
    """The exercise's world and a channel set of its first three channels (png, 1280x720)."""
    model = build_world(cfg, config_path)
    data = start_world(model, cfg)
    chosen = [c.model_copy(update={"output": "png", "width": 1280, "height": 720}) for c in cfg.render.channels[:3]]
    view = WorldView()
    view.apply(snapshot(model, data))
    return ChannelSet(SceneRenderer(CTX, model, cfg.render.model_copy(update={"channels": chosen})), chosen), view


def without_rubble(cfg):
    """The config with its ridge fields gone and its brash regions turned to level ice."""
    regions = [r for r in cfg.ice_field.regions if not r.region(0.0, 0.0).rubble_only]
    field = cfg.ice_field.model_copy(update={"ridges": [], "regions": regions})
    return cfg.model_copy(update={"ice_field": field})


def frame_ms(cs: ChannelSet, view: WorldView) -> float:
    t0 = time.perf_counter()
    cs.render(view)
    return (time.perf_counter() - t0) * 1e3


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--frames", type=int, default=30)
    args = p.parse_args()
    print(f"{os.cpu_count()} CPUs; {args.frames} frames each, interleaved")
    for name in EXERCISES:
        path = str(REPO / "config" / "exercises" / f"{name}.toml")
        cfg = load_config(path)
        rubble, rubble_view = channels_of(cfg, path)
        plain, plain_view = channels_of(without_rubble(cfg), path)
        first = frame_ms(rubble, rubble_view), frame_ms(plain, plain_view)
        times = np.array([(frame_ms(rubble, rubble_view), frame_ms(plain, plain_view)) for _ in range(args.frames)])
        sails = rubble.renderer.sails.tiles
        triangles = sum(count for _, _, count in sails.values()) // 3
        med, p99 = np.median(times, axis=0), np.percentile(times, 99, axis=0)
        print(f"{name}: first frame {first[0]:.0f} ms (without: {first[1]:.0f} ms); sails: {len(sails)} tiles, "
              f"{triangles} triangles")
        print(f"  frame median {med[0]:.1f} ms against {med[1]:.1f} ms (ratio {med[0] / med[1]:.2f}), "
              f"p99 {p99[0]:.1f} against {p99[1]:.1f} ms (ratio {p99[0] / p99[1]:.2f})")


CTX = create_context()

if __name__ == "__main__":
    main()
