"""Ships in line through level ice: what a follower meets in the channel its leader broke.

The convoy's premise: an icebreaker ahead opens a channel, and the ships astern meet
broken ice, not level ice, so their ice resistance falls to a fraction of what they would
meet alone (the channel resistance of broken ice, e.g. the FSICR's brash-channel term, is
a small share of a level-ice resistance). Here several hulls of one size are pushed at one
constant speed, straight, north along the same track through a strip of breakable tiles,
each a given distance astern of the one ahead, in one ice world (``ice_step`` with every
hull). The result is each hull's mean ice resistance (the contact force against its
motion) over the steps in which its reference point is in the middle half of the strip,
where the run-in and run-out do not count.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim_core.fracture.tile_template import FractureSettings, build_tile, template_seed
from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice.model import compile_ice_model
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.tiles import add_hull, new_ice_data, place_tile
from sim_core.material import IceMaterial


@dataclass(frozen=True)
class LineAhead:
    """The run: the strip (thickness m, tile side m, tiles), the ships (length, beam m;
    speed m/s; distances m between the reference points of each ship and the next astern,
    one fewer than the ships), the step (s) and the fracture seed."""

    thickness: float = 0.5
    tile_side: float = 50.0
    strip_tiles: int = 6
    ship_length: float = 60.0
    beam: float = 12.0
    speed: float = 2.5
    gaps: tuple[float, ...] = ()
    dt: float = 1 / 30
    seed: int = 20231025
    hull_friction: float = 0.1


def run_line_ahead(run: LineAhead) -> np.ndarray:
    """Push the ships of ``run`` through the strip; returns each ship's mean ice resistance
    (N, by its place in the line, leader first) over the middle half of the strip.

    Returns
    -------
    (n,) float: N, the mean contact force against each hull's motion.
    """
    material = IceMaterial()
    settings = FractureSettings(tile_side=run.tile_side, colliders="hybrid", cells="prism")
    template = build_tile(run.thickness, template_seed(run.seed, run.thickness, 0), settings, material)
    model = compile_ice_model([template], material)
    contour = waterline_contour(run.ship_length, run.beam)
    data = new_ice_data(model, contour, run.hull_friction)
    for _ in run.gaps:
        add_hull(data, contour, run.hull_friction)
    for k in range(run.strip_tiles):
        place_tile(model, data, 0, (0.0, k * run.tile_side), quarter_turns=k)
    length = run.strip_tiles * run.tile_side
    astern = np.concatenate([[0.0], np.cumsum(run.gaps)])  # m, each ship behind the leader
    x, velocity = 0.5 * run.tile_side, np.array([0.0, run.speed])
    lead_y = -5.0 - 0.5 * run.ship_length  # the leader's stem 5 m short of the ice
    window = (0.25 * length, 0.75 * length)
    sums, counts = np.zeros(len(astern)), np.zeros(len(astern))
    while lead_y - astern[-1] < length + 0.5 * run.ship_length:
        ys = lead_y - astern
        hulls = [HullMotion(np.array([x, y]), 0.5 * math.pi, velocity, 0.0) for y in ys.tolist()]
        report = ice_step(model, data, hulls, run.dt)
        inside = (ys >= window[0]) & (ys <= window[1])
        sums[inside] -= report.hull_force[inside, 1]
        counts[inside] += 1
        lead_y += run.speed * run.dt
    return sums / np.maximum(counts, 1)
