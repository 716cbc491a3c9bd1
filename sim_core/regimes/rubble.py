"""Ice rubble the world does not lay out as bodies: brash (and pancakes) in a region, and
ridge fields. The hull meets them through published resistance models
(``sim_core.ship.rubble_resistance``); the renderer draws them from the same data.

A **ridge field** is a polygon holding parallel ridges: lines in a direction, ``spacing`` m
apart, each with a sail height, a keel depth and a keel width. Its keel has a triangular
cross-section, the usual idealisation of a first-year ridge keel: full depth on the ridge's
line, none at half the width either side. Brash and ridge fields lie per tile, as the
regions lie: a tile takes the region, and the ridge field, holding its centre (later ridge
fields over earlier).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from sim_core.regimes.regime import IceRegion


@dataclass(frozen=True)
class RidgeField:
    """Parallel ridges over a polygon (x east, y north, m): through ``anchor`` (m) in the
    direction ``direction`` (rad, counter-clockwise from east), ``spacing`` m apart; sail
    height, keel depth and keel width in m; the keel rubble's angle of internal friction
    (rad), cohesion (Pa) and porosity."""

    name: str
    polygon: shapely.Geometry
    anchor: tuple[float, float]
    direction: float
    spacing: float
    width: float
    sail_height: float
    keel_depth: float
    friction_angle: float
    cohesion: float
    porosity: float

    @property
    def normal(self) -> tuple[float, float]:
        """Unit vector across the ridges."""
        return -math.sin(self.direction), math.cos(self.direction)

    def lines(self) -> shapely.Geometry:
        """The ridge lines clipped to the polygon (a MultiLineString, possibly empty)."""
        (x0, y0, x1, y1), (nx, ny) = self.polygon.bounds, self.normal
        ax, ay = self.anchor
        reach = math.hypot(x1 - x0, y1 - y0) + math.hypot(ax - x0, ay - y0)
        tx, ty = math.cos(self.direction), math.sin(self.direction)
        k = np.arange(-math.ceil(reach / self.spacing), math.ceil(reach / self.spacing) + 1)
        cx, cy = ax + k * self.spacing * nx, ay + k * self.spacing * ny
        ends = np.stack([np.column_stack([cx - reach * tx, cy - reach * ty]),
                         np.column_stack([cx + reach * tx, cy + reach * ty])], axis=1)
        return shapely.intersection(shapely.MultiLineString(list(ends)), self.polygon)


def keel_depth_at(ridges: RidgeField, x: float, y: float) -> float:
    """Keel depth (m) of the field's ridges under the point (x, y) m: 0 between them (the
    caller knows the point lies in the field)."""
    nx, ny = ridges.normal
    across = (x - ridges.anchor[0]) * nx + (y - ridges.anchor[1]) * ny
    off = abs((across + 0.5 * ridges.spacing) % ridges.spacing - 0.5 * ridges.spacing)
    return max(0.0, ridges.keel_depth * (1.0 - 2.0 * off / ridges.width))


@dataclass(frozen=True)
class RubbleModel:
    """Static rubble of a field of nx x ny tiles of ``side`` m: the share of each tile
    (n_tiles,) covered with brash and its thickness H_M (m), the ridge fields and the one
    holding each tile (n_tiles,; -1: none). Build with ``compile_rubble``."""

    nx: int
    ny: int
    side: float
    brash_share: np.ndarray
    brash_thickness: np.ndarray
    ridges: tuple[RidgeField, ...]
    ridge_tile: np.ndarray
    has_brash: bool  # some tile has brash

    @property
    def empty(self) -> bool:
        """Whether the field has neither brash nor ridges (the step then looks nothing up)."""
        return not self.ridges and not self.has_brash


def tile_rubble(regions: list[IceRegion], index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Brash share (0-1) and thickness H_M (m) of each tile (ny, nx) from the region holding
    its centre (``index`` from ``regime.tile_regions``; -1: none, no brash)."""
    per_region = np.array([r.rubble for r in regions] + [(0.0, 0.0)], dtype=float).reshape(-1, 2)
    return per_region[index, 0], per_region[index, 1]


def compile_rubble(regions: list[IceRegion], index: np.ndarray | None, ridges: tuple[RidgeField, ...],
                   nx: int, ny: int, side: float) -> RubbleModel:
    """The rubble of a field from its regions (and their tile index, None: no regions) and
    its ridge fields."""
    share, thickness = np.zeros(nx * ny), np.zeros(nx * ny)
    if index is not None and regions:
        s, h = tile_rubble(regions, index)
        share, thickness = s.ravel(), h.ravel()
    x, y = np.meshgrid((np.arange(nx) + 0.5) * side, (np.arange(ny) + 0.5) * side)
    ridge_tile = np.full(nx * ny, -1, dtype=np.int64)
    for k, r in enumerate(ridges):
        ridge_tile[shapely.contains_xy(r.polygon, x.ravel(), y.ravel())] = k
    return RubbleModel(nx, ny, side, share, thickness, tuple(ridges), ridge_tile, bool(np.any(share > 0.0)))


def rubble_at(model: RubbleModel, x: float, y: float) -> tuple[float, float, RidgeField | None, float]:
    """At the point (x, y) m: the brash share and thickness (m), and the ridge field of its
    tile with its keel depth there (m; None and 0 where no ridge field lies, or off the field)."""
    i, j = math.floor(x / model.side), math.floor(y / model.side)
    if not (0 <= i < model.nx and 0 <= j < model.ny):
        return 0.0, 0.0, None, 0.0
    tile = j * model.nx + i
    k = int(model.ridge_tile[tile])
    ridges = model.ridges[k] if k >= 0 else None
    depth = keel_depth_at(ridges, x, y) if ridges is not None else 0.0
    return float(model.brash_share[tile]), float(model.brash_thickness[tile]), ridges if depth > 0.0 else None, depth
