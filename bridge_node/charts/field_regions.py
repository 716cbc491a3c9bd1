"""The field's ice regions as an exercise lays them: the chart's, then the config's over them."""
from __future__ import annotations

from pathlib import Path

import shapely

from bridge_node.charts.sigrid3 import ChartError, chart_regions, read_chart
from bridge_node.common.errors import UserError
from sim_core.regimes.floe_layout import RegimeModel, compile_regimes
from sim_core.regimes.regime import IceRegion


def configured_regions(cfg, chart: Path | None) -> list[IceRegion]:
    """The regions of a node config (``NodeConfig``): its chart's (``chart``: the file
    ``ice_field.chart`` names, found), then its ``[[ice_field.regions]]``."""
    lat0, lon0 = cfg.exercise.origin_latitude_deg, cfg.exercise.origin_longitude_deg
    regions = chart_regions(read_chart(chart), lat0, lon0) if chart is not None else []
    return regions + [r.region(lat0, lon0) for r in cfg.ice_field.regions]


def regions_not_in_the_world(cfg) -> list[str]:
    """The names of a node config's regions that the ice world does not lay out yet: floe
    fields (neither level ice nor ice free), land and no data."""
    if not (cfg.ice_field.chart or cfg.ice_field.regions):
        return []
    chart = Path(cfg.ice_field.chart) if cfg.ice_field.chart else None
    return [r.name for r in configured_regions(cfg, chart)
            if r.kind in ("land", "no_data") or (r.regime.types and not r.regime.level)]


def chart_field(path: Path) -> tuple[list[IceRegion], shapely.Geometry, tuple[float, float]]:
    """A chart alone as a field: its regions in the local frame of the south-west corner of
    its bounds, the field (those bounds, m) and the origin (latitude, longitude, degrees)."""
    features = read_chart(path)
    lon0, lat0, _, _ = shapely.total_bounds([f.geometry for f in features])
    if abs(lat0) > 89.0:
        raise ChartError(f"{path}: reaches latitude {lat0:.2f}; the local frame holds to 89 deg")
    regions = chart_regions(features, float(lat0), float(lon0))
    return regions, shapely.box(*shapely.total_bounds([r.polygon for r in regions])), (float(lat0), float(lon0))


def regime_model(regions: list[IceRegion], field: shapely.Geometry, seed: int, where: str) -> RegimeModel:
    """The compiled regimes; UserError naming ``where`` if no region lies in the field."""
    if not regions or not any(shapely.intersects(r.polygon, field) for r in regions):
        raise UserError(f"{where}: no ice region lies in the field (ice_field.chart or [[ice_field.regions]])")
    return compile_regimes(regions, field, seed)
