"""Measurement: what the centre channel shows of the breaking ahead of the stem.

The default exercise is run to --time (120 s); the centre channel's class mask is drawn,
and each pixel's view ray is followed to the water plane. Of the pixels whose ground point
lies ahead of the stem and within 100 m of it (issue 28's measure), it prints the share
that shows ice (level ice, crack, broken or submerged floe) at all, and of those the share
of cracks and broken floes; and, from the world itself, how far ahead of the stem the
cracked cells reach and how much of the 100 m the bow hides (the nearest ground point in the
ship's path ahead of the stem that any pixel shows).
Run: .venv/bin/python benchmarks/bench_bow_view.py [--time S]
"""
from __future__ import annotations

import argparse
import math
import os

import numpy as np

from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, create_context
from bridge_node.render.classes import CLASS_INDEX, class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.stream.world_view import WorldView
from sim_core.ice.floes import FloeStatus
from sim_core.world import snapshot, step

AHEAD_M = 100.0
DT = 1.0 / 60.0


def ground_points(view_proj: np.ndarray, eye: np.ndarray, width: int, height: int, z: float) -> np.ndarray:
    """World (x, y) of each pixel's ray at height z (NaN where the ray does not come down):
    (height, width, 2), top row first."""
    ys, xs = np.mgrid[0:height, 0:width]
    ndc = np.stack([(xs + 0.5) / width * 2 - 1, 1 - (ys + 0.5) / height * 2, np.ones_like(xs, float),
                    np.ones_like(xs, float)], axis=-1)
    far = ndc @ np.linalg.inv(view_proj).T
    ray = far[..., :3] / far[..., 3:] - eye
    t = (z - eye[2]) / ray[..., 2]
    out = eye[:2] + ray[..., :2] * t[..., None]
    out[~(t > 0)] = np.nan
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--time", type=float, default=120.0)
    args = ap.parse_args()
    cfg = load_config(None)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(round(args.time / DT)):
        step(model, data, DT)
    view = WorldView()
    view.apply(snapshot(model, data))
    centre = next(c for c in cfg.render.channels if c.name == "centre")
    cs = ChannelSet(SceneRenderer(create_context(), model, cfg.render), [centre])
    cs.renderer.update(view)
    target = cs.targets[0]
    mask = target.class_image(cs.renderer, view)
    cam = cs.renderer.draw(view, centre, target.blend, classes=True)  # the same camera
    cls = class_of_pixels(mask)
    s = data.ship
    heading = np.array([math.sin(s.eta[5]), math.cos(s.eta[5])])
    stem = np.array([s.eta[1], s.eta[0]]) + heading * model.ship.particulars.length / 2 - data.ice_frame.offset
    ground = ground_points(cam.view_proj, cam.eye, centre.width, centre.height, cs.renderer.slab_z) - stem
    along = ground @ heading
    zone = (along >= 0) & (np.hypot(ground[..., 0], ground[..., 1]) <= AHEAD_M)
    ice = np.isin(cls, [CLASS_INDEX[n] for n in ("level_ice", "crack", "broken_floe", "submerged_floe")])
    broken = np.isin(cls, [CLASS_INDEX[n] for n in ("crack", "broken_floe")])
    seen = zone & ice
    st = data.ice.state
    rows = np.flatnonzero((st.crack[:st.n] != 0) & (st.status[:st.n] == FloeStatus.INTACT))
    reach = float(((st.home[rows] - stem) @ heading).max()) if len(rows) else math.nan
    lateral = np.abs(ground @ np.array([heading[1], -heading[0]]))
    path = zone & ice & (lateral < model.ship.particulars.beam / 2)  # straight ahead, the ship's path
    nearest = float(np.nanmin(np.where(path, along, np.nan))) if path.any() else math.inf
    print(f"cores {os.cpu_count()}; default exercise at {args.time:g} s, centre channel {centre.width}x{centre.height}")
    print(f"  ice pixels within {AHEAD_M:g} m ahead of the stem: {seen.sum()} "
          f"(in the ship's path the nearest shown lies {nearest:.1f} m ahead of the stem: the bow hides the rest)")
    print(f"  cracks and broken floes among them: {np.count_nonzero(seen & broken)} "
          f"({np.count_nonzero(seen & broken) / max(seen.sum(), 1):.1%})")
    print(f"  cracked intact cells in the world: {len(rows)}, the farthest {reach:.1f} m ahead of the stem")


if __name__ == "__main__":
    main()
