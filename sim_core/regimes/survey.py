"""A survey of a laid-out field: per region, the concentration measured in the floes laid
and the floe sizes against the WMO ranges (``icebridge field``).

A region is laid out whole where its expected floe count fits a budget, else on a square
patch about a point inside it, as large as the budget allows. Floes are laid over the
surveyed area grown by a few floe sizes, so floes reaching in from outside it count.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from sim_core.regimes.floe_layout import FloeLayout, Layer, RegimeModel, joined, lay_out
from sim_core.regimes.measure import caliper_diameter, ice_area
from sim_core.regimes.regime import IceType

FLOE_BUDGET = 60_000  # floes laid per region at most
POINTS_PER_WINDOW = 20_000  # grid points a window's smallest layer holds at most


@dataclass(frozen=True)
class TypeSurvey:
    """One ice type as laid: floes counted, their size (m) at the 5th, 50th and 95th
    percentile, the share of uncut floes within the WMO size range, thickness laid (m)."""

    ice: IceType
    floes: int
    size_percentiles: tuple[float, float, float]
    within_range: float
    thickness: float


@dataclass(frozen=True)
class RegionSurvey:
    """One region: its area in the field (m2), the area surveyed (m2, and whether that is the
    whole region), the measured concentration (tenths), its types, and the floes laid."""

    region: int
    area: float
    surveyed: shapely.Geometry
    whole: bool
    concentration: float
    types: tuple[TypeSurvey, ...]
    layout: FloeLayout
    note: str = ""  # why the laid concentration may differ from the chart's


def survey_region(model: RegimeModel, r: int, budget: int = FLOE_BUDGET) -> RegionSurvey:
    """Lay out and measure region r of the model."""
    polygon, layers = model.polygons[r], model.layers[r]
    area = float(polygon.area)
    if not layers or area <= 0.0:  # level ice (not laid as floes) or ice free
        regime = model.regions[r].regime
        return RegionSurvey(r, area, polygon, True, regime.total if regime.level else 0.0, (), joined([]))
    expected = area * sum(_floes_per_m2(layer, model) for layer in layers)
    surveyed, whole = polygon, expected <= budget
    if not whole:
        side = math.sqrt(area * budget / expected)
        centre = shapely.point_on_surface(polygon)
        surveyed = shapely.intersection(polygon, shapely.box(centre.x - side / 2, centre.y - side / 2,
                                                             centre.x + side / 2, centre.y + side / 2))
    layout = _laid_over(model, r, surveyed, layers)
    types = tuple(_type_survey(model, r, k, layout, surveyed) for k in range(len(model.regions[r].regime.types)))
    concentration = 10.0 * ice_area(layout, r, surveyed) / surveyed.area
    return RegionSurvey(r, area, surveyed, whole, concentration, types, layout,
                        _note(area, layers, model.regions[r].regime.total - concentration))


def _note(area: float, layers: tuple[Layer, ...], shortfall: float) -> str:
    """Why a region's laid concentration may differ from its chart's, if it may."""
    if area < 4.0 * max(layer.spacing for layer in layers) ** 2:
        return "smaller than a few of its floes: its concentration cannot be laid"
    if shortfall > 0.5:
        return ("laid short: the smaller types' floes, kept within their WMO size and apart, do not fill the "
                "leads the larger ones leave")
    return ""


def _floes_per_m2(layer: Layer, model: RegimeModel) -> float:
    ice = model.regions[layer.region].regime.types[layer.ice_type]
    return ice.concentration / 10.0 / (layer.shrink * layer.spacing) ** 2


def _laid_over(model: RegimeModel, r: int, surveyed: shapely.Geometry, layers: tuple[Layer, ...]) -> FloeLayout:
    """The region's floes that touch the surveyed area, each layer laid in windows sized to
    its floes over the area grown by a few of them."""
    parts = []
    for k, layer in enumerate(layers):
        margin = 1.5 * layer.spacing
        x0, y0, x1, y1 = np.asarray(shapely.bounds(surveyed)) + [-margin, -margin, margin, margin]
        side = max(100.0, math.sqrt(POINTS_PER_WINDOW) * layer.spacing)
        parts += [lay_out(model, (x, y, min(x + side, x1), min(y + side, y1)), region=r, layer=k)
                  for x in np.arange(x0, x1, side) for y in np.arange(y0, y1, side)]
    layout = joined(parts)
    keep = shapely.intersects(layout.polygon, surveyed)
    return FloeLayout(*(a[keep] for a in (layout.polygon, layout.region, layout.ice_type, layout.thickness,
                                           layout.clipped)))


def _type_survey(model: RegimeModel, r: int, k: int, layout: FloeLayout, surveyed: shapely.Geometry) -> TypeSurvey:
    ice = model.regions[r].regime.types[k]
    rows = (layout.ice_type == k) & shapely.contains(surveyed, shapely.point_on_surface(layout.polygon))
    uncut = rows & ~layout.clipped
    size = caliper_diameter(layout.polygon[uncut]) if uncut.any() else np.full(1, np.nan)
    low, high = ice.size_range.low, ice.size_range.high
    within = float(np.mean((size >= low) & (size <= high))) if uncut.any() else float("nan")
    p5, p50, p95 = (float(v) for v in np.percentile(size, [5, 50, 95]))
    return TypeSurvey(ice, int(rows.sum()), (p5, p50, p95), within, ice.stage_range.nominal)
