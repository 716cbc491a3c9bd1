"""The paper's breaking experiments (§3.1, §3.2) as numbers, and the speed dependence.

A ship is pushed at constant speed, straight, through a strip of breakable tiles. The
result is judged from where the broken cells sat in the level ice (their ``home``). Over the
middle half of the strip, the share of cells broken is taken in lateral bins either side of
the track. The **channel** reaches out to where that share first falls below 1/2. The
**conduction band** is the cracking that pushes from other floes caused, not the hull
itself. Its width is the area of such cells beyond the hull's side (B/2 off the track), per
metre of track and per side: the integral of their share from B/2 outward. A field cracked
right across reads as the whole half-width less B/2.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from sim_core.fracture.tile_template import FractureSettings, build_tile, template_seed
from sim_core.frames.hull_contour import waterline_contour
from sim_core.frames.units import KNOT
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import IceDynamicsSettings, IceModel, compile_ice_model
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.tiles import IceData, new_ice_data, place_tile
from sim_core.material import IceMaterial

BIN = 2.0  # m, lateral bin of the broken-share profile
CHANNEL_SHARE = 0.5


@dataclass
class BreakingRun:
    """One experiment: settings, measured widths (m), counts, timing, and the final field."""

    thickness: float
    colliders: str
    speed: float  # m/s
    channel_width: float
    band_width: float
    broken: int
    cells: int
    mean_resistance: float  # N, mean contact force against the hull's motion
    step_ms: float  # median wall time of one ice step
    profile: np.ndarray = field(repr=False, default=None)  # (bins, 3): |y|, broken share, pushed share
    model: IceModel = field(repr=False, default=None)
    data: IceData = field(repr=False, default=None)

    def as_dict(self) -> dict:
        return {"thickness_m": self.thickness, "colliders": self.colliders,
                "speed_kn": round(self.speed / KNOT, 2), "channel_width_m": round(self.channel_width, 2),
                "band_width_m": round(self.band_width, 2), "broken_cells": self.broken, "cells": self.cells,
                "mean_resistance_kN": round(self.mean_resistance / 1e3, 1), "step_ms": round(self.step_ms, 2)}


def broken_profile(home: np.ndarray, cause: np.ndarray, centre_x: float, y0: float, y1: float,
                   half_width: float) -> np.ndarray:
    """Per lateral bin, both sides folded: (bins, 3) of |lateral| (m), share of cells broken
    by anything, share broken by contact (conduction)."""
    sel = (home[:, 1] >= y0) & (home[:, 1] <= y1)
    lateral = np.abs(home[sel, 0] - centre_x)
    edges = np.arange(0.0, half_width + BIN, BIN)
    total, _ = np.histogram(lateral, edges)
    broken, _ = np.histogram(lateral[cause[sel] != 0], edges)
    pushed, _ = np.histogram(lateral[cause[sel] == BreakCause.CONTACT], edges)
    n = np.maximum(total, 1)
    return np.column_stack([0.5 * (edges[:-1] + edges[1:]), broken / n, pushed / n])


def channel_and_band(profile: np.ndarray, half_beam: float) -> tuple[float, float]:
    """Channel width (m, both sides) and conduction-band width beyond the hull side (m)."""
    y, f, pushed = profile[:, 0], profile[:, 1], profile[:, 2]
    below = np.nonzero(f < CHANNEL_SHARE)[0]
    if len(below) == 0:
        half = y[-1] + 0.5 * BIN
    elif below[0] == 0:
        half = 0.0
    else:
        i = below[0]
        half = y[i - 1] + (f[i - 1] - CHANNEL_SHARE) / (f[i - 1] - f[i]) * (y[i] - y[i - 1])
    lo = y - 0.5 * BIN
    overlap = np.clip(y + 0.5 * BIN - np.maximum(lo, half_beam), 0.0, BIN)  # bin length beyond B/2
    return 2.0 * float(half), float((pushed * overlap).sum())


def run_breaking(thickness: float, colliders: str, speed: float, *, ship_length: float = 150.0,
                 beam: float = 24.0, tile_side: float = 100.0, strip_tiles: int = 2, dt: float = 1 / 30,
                 seed: int = 20231025, material: IceMaterial | None = None,
                 dynamics: IceDynamicsSettings | None = None, hull_friction: float = 0.1) -> BreakingRun:
    """Push a hull (length, beam in m) at speed (m/s) north through a strip of breakable
    tiles of the given thickness (m) and collider setup; measure channel and band."""
    material = material or IceMaterial()
    settings = FractureSettings(tile_side=tile_side, colliders=colliders, cells="prism")
    template = build_tile(thickness, template_seed(seed, thickness, 0), settings, material)
    model = compile_ice_model([template], material, dynamics)
    data = new_ice_data(model, waterline_contour(ship_length, beam), hull_friction)
    for k in range(strip_tiles):
        place_tile(model, data, 0, (0.0, k * tile_side), quarter_turns=k)
    length = strip_tiles * tile_side
    centre_x = 0.5 * tile_side
    y = -5.0 - 0.5 * ship_length
    stop = length + 0.3 * ship_length + 5.0 - 0.5 * ship_length
    step_times, resistance = [], []
    while y < stop:
        hull = HullMotion(np.array([centre_x, y]), 0.5 * math.pi, np.array([0.0, speed]), 0.0)
        t0 = time.perf_counter()
        report = ice_step(model, data, hull, dt)
        step_times.append(time.perf_counter() - t0)
        resistance.append(-report.hull_force[1])
        y += speed * dt
    st = data.state
    broken = st.status != FloeStatus.INTACT
    profile = broken_profile(st.home, st.cause, centre_x, 0.25 * length, 0.75 * length, 0.5 * tile_side)
    channel, band = channel_and_band(profile, 0.5 * beam)
    return BreakingRun(thickness, colliders, speed, float(channel), float(band), int(broken.sum()), st.n,
                       float(np.mean(resistance)), float(np.median(step_times) * 1e3), profile, model, data)
