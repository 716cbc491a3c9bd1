"""The paper's breaking experiments (§3.1, §3.2) as numbers, and the speed dependence.

A ship is pushed at constant speed, straight, through a strip of breakable tiles. The
result is judged from where the broken cells sat in the level ice (their ``home``), over the
middle half of the strip.

- **Conduction cracking**, the amount §3.1 judges: the cells broken by contact (pushed by
  other floes, not touched by the hull), counted and their plan area summed, per 100 m of
  channel.
- **Channel**: in lateral bins either side of the track, the share of cells broken; the
  channel reaches out to where that share first falls below 1/2. Reported in metres and
  relative to the beam B.
- **Conduction band**: the area of contact-broken cells beyond the hull's side (B/2 off the
  track), per metre of track and per side: the integral of their share from B/2 outward. A
  field cracked right across reads as the whole half-width less B/2. Reported in metres and
  in mean piece diameters (the mean equivalent-circle diameter of the template's cells),
  since widths in metres follow piece size.

Single runs are noisy (one template per run), so a configuration is judged on the medians
over several seeds (``BreakingMedians``).
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
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
PER_LENGTH = 100.0  # m of channel the conduction figures are given per
# per-run metrics (attributes of BreakingRun): their JSON name and decimals
_JSON = {"contact_count": ("contact_cells_per_100m", 1), "contact_area": ("contact_area_m2_per_100m", 1),
         "channel_width": ("channel_width_m", 2), "channel_beams": ("channel_beams", 3),
         "band_width": ("band_width_m", 2), "band_pieces": ("band_pieces", 3),
         "piece_diameter": ("piece_diameter_m", 2), "broken": ("broken_cells", 1), "step_ms": ("step_ms", 2)}
METRICS = tuple(_JSON)


def _json_config(thickness: float, colliders: str, speed: float) -> dict:
    return {"thickness_m": thickness, "colliders": colliders, "speed_kn": round(speed / KNOT, 2)}


def _json_metrics(value: Callable[[str], float]) -> dict:
    return {key: round(value(metric), digits) for metric, (key, digits) in _JSON.items()}


@dataclass
class BreakingRun:
    """One experiment: settings, measured widths (m), conduction per 100 m, counts, timing,
    and the final field."""

    thickness: float  # m
    colliders: str
    speed: float  # m/s
    seed: int
    beam: float  # m
    channel_width: float  # m
    band_width: float  # m per side
    contact_count: float  # cells broken by contact per 100 m of channel
    contact_area: float  # their plan area, m2 per 100 m of channel
    piece_diameter: float  # mean equivalent-circle diameter of the template's cells, m
    broken: int
    cells: int
    mean_resistance: float  # N, mean contact force against the hull's motion
    step_ms: float  # median wall time of one ice step
    profile: np.ndarray = field(repr=False, default=None)  # (bins, 3): |y|, broken share, pushed share
    model: IceModel = field(repr=False, default=None)
    data: IceData = field(repr=False, default=None)

    @property
    def channel_beams(self) -> float:
        """Channel width over the beam."""
        return self.channel_width / self.beam

    @property
    def band_pieces(self) -> float:
        """Band width in mean piece diameters."""
        return self.band_width / self.piece_diameter

    def as_dict(self) -> dict:
        return (_json_config(self.thickness, self.colliders, self.speed) | {"seed": self.seed}
                | _json_metrics(lambda m: getattr(self, m))
                | {"cells": self.cells, "mean_resistance_kN": round(self.mean_resistance / 1e3, 1)})


@dataclass
class BreakingMedians:
    """The runs of one configuration (thickness, colliders, speed) over several seeds."""

    runs: list[BreakingRun]

    def __post_init__(self) -> None:
        keys = {(r.thickness, r.colliders, r.speed) for r in self.runs}
        if len(keys) != 1:
            raise ValueError(f"runs of one configuration expected, got {len(keys)}")

    @property
    def thickness(self) -> float:
        return self.runs[0].thickness

    @property
    def colliders(self) -> str:
        return self.runs[0].colliders

    @property
    def speed(self) -> float:
        return self.runs[0].speed

    def median(self, metric: str) -> float:
        """Median over the seeds of a ``METRICS`` name."""
        return float(np.median([getattr(r, metric) for r in self.runs]))

    def as_dict(self) -> dict:
        return (_json_config(self.thickness, self.colliders, self.speed) | {"seeds": [r.seed for r in self.runs]}
                | {"median": _json_metrics(self.median), "runs": [r.as_dict() for r in self.runs]})


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


def conduction_per_length(home: np.ndarray, cause: np.ndarray, plan_area: np.ndarray, y0: float,
                          y1: float) -> tuple[float, float]:
    """Cells broken by contact with their home between y0 and y1 (m along the track), and
    their plan area (m2), both per ``PER_LENGTH`` m of track."""
    pushed = (cause == BreakCause.CONTACT) & (home[:, 1] >= y0) & (home[:, 1] <= y1)
    scale = PER_LENGTH / (y1 - y0)
    return float(pushed.sum() * scale), float(plan_area[pushed].sum() * scale)


def run_breaking(thickness: float, colliders: str, speed: float, *, ship_length: float = 150.0,
                 beam: float = 24.0, tile_side: float = 100.0, strip_tiles: int = 2, dt: float = 1 / 30,
                 seed: int = 20231025, material: IceMaterial | None = None,
                 dynamics: IceDynamicsSettings | None = None, hull_friction: float = 0.1) -> BreakingRun:
    """Push a hull (length, beam in m) at speed (m/s) north through a strip of breakable
    tiles of the given thickness (m) and collider setup, pre-fractured from seed; measure
    channel, band and conduction cracking."""
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
        report = ice_step(model, data, (hull,), dt)
        step_times.append(time.perf_counter() - t0)
        resistance.append(-report.hull_force[0, 1])
        y += speed * dt
    st = data.state
    y0, y1 = 0.25 * length, 0.75 * length
    profile = broken_profile(st.home, st.cause, centre_x, y0, y1, 0.5 * tile_side)
    channel, band = channel_and_band(profile, 0.5 * beam)
    count, area = conduction_per_length(st.home, st.cause, model.plan_area[st.gcell], y0, y1)
    diameter = float(np.sqrt(4.0 * model.plan_area / math.pi).mean())
    return BreakingRun(thickness, colliders, speed, seed, beam, channel, band, count, area, diameter,
                       int((st.status != FloeStatus.INTACT).sum()), st.n, float(np.mean(resistance)),
                       float(np.median(step_times) * 1e3), profile, model, data)


def run_breaking_seeds(thickness: float, colliders: str, speed: float, seeds: list[int], **options) -> BreakingMedians:
    """``run_breaking`` once per seed; options as for ``run_breaking``."""
    return BreakingMedians([run_breaking(thickness, colliders, speed, seed=s, **options) for s in seeds])
