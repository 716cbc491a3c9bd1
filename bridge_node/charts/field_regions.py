"""The field's ice regions as an exercise lays them: the chart's, then the config's over them."""
from __future__ import annotations

from pathlib import Path

import shapely

from bridge_node.charts.sigrid3 import chart_regions, read_chart
from bridge_node.common.errors import UserError
from sim_core.regimes.floe_layout import RegimeModel, compile_regimes
from sim_core.regimes.regime import IceRegion
from sim_core.regimes.rubble import RidgeField
from sim_core.scene.field import IceFieldSettings


def configured_regions(ice_field: IceFieldSettings, origin_deg: tuple[float, float]) -> list[IceRegion]:
    """The regions of a config's ``[ice_field]`` in the local frame of the exercise's origin
    (latitude, longitude, degrees): its chart's (``chart``, the file as the config loader
    found it), then its ``[[ice_field.regions]]``."""
    lat0, lon0 = origin_deg
    regions = chart_regions(read_chart(Path(ice_field.chart)), lat0, lon0) if ice_field.chart else []
    return regions + [r.region(lat0, lon0) for r in ice_field.regions]


def configured_ridges(ice_field: IceFieldSettings, origin_deg: tuple[float, float]) -> tuple[RidgeField, ...]:
    """The ridge fields of a config's ``[ice_field]`` in the local frame of the exercise's
    origin (latitude, longitude, degrees)."""
    return tuple(r.ridges(*origin_deg) for r in ice_field.ridges)


def regions_not_in_the_world(ice_field: IceFieldSettings, origin_deg: tuple[float, float]) -> list[str]:
    """The names of the regions that the ice world does not lay out: land and no data
    (level ice, open water, floe fields and brash it lays)."""
    return [r.name for r in configured_regions(ice_field, origin_deg) if not r.in_the_world]


def chart_field(path: Path) -> tuple[list[IceRegion], shapely.Geometry, tuple[float, float]]:
    """A chart alone as a field: its regions in the local frame of the south-west corner of
    its bounds, the field (those bounds, m) and the origin (latitude, longitude, degrees)."""
    features = read_chart(path)  # every feature within MAX_LATITUDE
    lon0, lat0, _, _ = shapely.total_bounds([f.geometry for f in features])
    regions = chart_regions(features, float(lat0), float(lon0))
    return regions, shapely.box(*shapely.total_bounds([r.polygon for r in regions])), (float(lat0), float(lon0))


def regime_model(regions: list[IceRegion], field: shapely.Geometry, seed: int, where: str,
                 tile_side: float) -> RegimeModel:
    """The compiled regimes, laid as the world lays them on tiles of ``tile_side`` (m);
    UserError naming ``where`` if no region lies in the field."""
    if not regions or not any(shapely.intersects(r.polygon, field) for r in regions):
        raise UserError(f"{where}: no ice region lies in the field (ice_field.chart or [[ice_field.regions]])")
    return compile_regimes(regions, field, seed, tile_side)
