"""The field report (``icebridge field``): per region the concentration measured in the
floes laid against the chart's, floe sizes against the WMO ranges, ice types; and a top
view of the field with the regions outlined and the ridges drawn."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import shapely
from matplotlib.collections import PolyCollection
from rich.table import Table

from bridge_node.reports.figures import plt, save_figure
from sim_core.regimes.floe_layout import RegimeModel
from sim_core.regimes.rubble import RidgeField
from sim_core.regimes.survey import RegionSurvey

RIDGE_COLOUR = "#e040c0"


def survey_json(model: RegimeModel, surveys: list[RegionSurvey], picture: Path) -> dict:
    """The report as one JSON-ready object."""
    return {"picture": str(picture), "regions": [_region_json(model, s) for s in surveys]}


def _region_json(model: RegimeModel, s: RegionSurvey) -> dict:
    region = model.regions[s.region]
    return {
        "name": region.name, "kind": region.kind, "regime": region.regime.label(), "level_ice": region.regime.level,
        "area_km2": round(s.area / 1e6, 4), "surveyed_km2": round(s.surveyed.area / 1e6, 4), "whole": s.whole,
        "concentration_chart": region.regime.total, "concentration_laid": round(s.concentration, 3), "note": s.note,
        "repeat_m": _repeat_m(model, s.region),
        "types": [{
            "concentration": t.ice.concentration, "stage": t.ice.stage_range.name, "stage_code": t.ice.stage,
            "thickness_range_m": [t.ice.stage_range.low, t.ice.stage_range.high], "thickness_laid_m": t.thickness,
            "floe_size": t.ice.size_range.name, "floe_size_code": t.ice.floe_size,
            "size_range_m": [t.ice.size_range.low, t.ice.size_range.high], "floes": t.floes,
            "size_p5_p50_p95_m": [_finite(v) for v in t.size_percentiles], "share_within_range": _finite(t.within_range),
        } for t in s.types],
    }


def _repeat_m(model: RegimeModel, region: int) -> float | None:
    """The side (m) of the square the region's floes repeat in, as the world lays them on
    its tiles (``floe_layout``); None where they do not repeat."""
    return model.repeat[region] * model.tile_side or None


def _finite(v: float) -> float | None:
    return None if not math.isfinite(v) else round(v, 3)


def survey_table(model: RegimeModel, surveys: list[RegionSurvey]) -> Table:
    """The report as a rich table: one row per ice type (one per region without types)."""
    table = Table(title="Ice field: the chart and the floes laid")
    for name, justify in [("region", "left"), ("area km²", "right"), ("surveyed", "right"), ("C chart", "right"),
                          ("C laid", "right"), ("ice type", "left"), ("floes", "right"),
                          ("size p5/p50/p95 m", "right"), ("in WMO range", "right")]:
        table.add_column(name, justify=justify)
    for s in surveys:
        region = model.regions[s.region]
        head = [region.name, f"{s.area / 1e6:.3f}", "whole" if s.whole else f"{s.surveyed.area / 1e6:.3f} km²",
                f"{region.regime.total:g}/10", f"{s.concentration:.2f}/10" + (" *" if s.note else "")]
        if not s.types:
            table.add_row(*head, "level ice" if region.regime.level else region.kind.replace("_", " "), "", "", "")
        for k, t in enumerate(s.types):
            size = "/".join("-" if not math.isfinite(v) else f"{v:.3g}" for v in t.size_percentiles)
            share = "-" if not math.isfinite(t.within_range) else f"{100 * t.within_range:.0f} %"
            table.add_row(*(head if k == 0 else [""] * len(head)), t.ice.label(), str(t.floes), size, share)
    notes = [f"* {model.regions[s.region].name}: {s.note}" for s in surveys if s.note]
    notes += [f"{model.regions[s.region].name}: the floes repeat every {_repeat_m(model, s.region):g} m "
              f"(a square of {model.repeat[s.region]} x {model.repeat[s.region]} tiles)"
              for s in surveys if _repeat_m(model, s.region)]
    table.caption = "\n".join(notes) or None
    return table


def plot_field(model: RegimeModel, surveys: list[RegionSurvey], field: shapely.Geometry, path: Path,
               ridges: tuple[RidgeField, ...] = ()) -> None:
    """Top view of the field (the floes laid white on sea blue, regions outlined in orange
    and numbered, level ice pale, brash grey and dotted, what a sample left unlaid hatched,
    ridge lines magenta), and beside it a close view of the region with the smallest floes."""
    x0, y0, x1, y1 = field.bounds
    fig, (ax, zx) = plt.subplots(1, 2, figsize=(14, 7), gridspec_kw={"width_ratios": [2, 1]})
    for axis in (ax, zx):
        _draw(axis, model, surveys)
        axis.set_facecolor("#12355b")
        axis.set_aspect("equal")
        axis.set_xlabel("east, m")
        axis.set_ylabel("north, m")
    _outline(ax, field, "black", "-")
    for r, region in enumerate(model.regions):
        if not model.polygons[r].is_empty:
            at = shapely.point_on_surface(model.polygons[r])
            ax.annotate(str(r + 1), (at.x, at.y), color="#ff7f0e", fontsize=10, ha="center", va="center",
                        bbox={"fc": "black", "alpha": 0.6, "lw": 0})
    for r in ridges:
        for line in shapely.get_parts(shapely.intersection(r.lines(), field)):
            ax.plot(*np.asarray(line.coords).T, color=RIDGE_COLOUR, linewidth=1.2)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_title("ice field: floes laid from the regimes")
    _close_view(zx, model, surveys)
    lines = [f"{r + 1}  {region.name}: {region.regime.label()}" for r, region in enumerate(model.regions)]
    lines += [f"ridge field {r.name} (magenta): sail {r.sail_height:g} m, keel {r.keel_depth:g} m deep and "
              f"{r.width:g} m wide, every {r.spacing:g} m" for r in ridges]
    fig.text(0.01, 0.01, "\n".join(lines) + "\nhatched: not laid (the region was sampled); dotted grey: brash",
             fontsize=7, va="bottom")
    fig.tight_layout(rect=(0, 0.04 + 0.018 * len(lines), 1, 1))
    save_figure(fig, path, dpi=130)


def _draw(ax, model: RegimeModel, surveys: list[RegionSurvey]) -> None:
    for s in surveys:
        region, polygon = model.regions[s.region], model.polygons[s.region]
        if region.regime.level:
            _fill(ax, polygon, "#dfe8f0", None)
        elif region.rubble_only:
            _fill(ax, polygon, "#a9b6c2", "..")
        elif not s.whole:
            _fill(ax, shapely.difference(polygon, s.surveyed), "none", "//")
        if len(s.layout.polygon):
            rings = [np.asarray(p.exterior.coords) for p in s.layout.polygon]
            ax.add_collection(PolyCollection(rings, facecolors="#f2f6fa", edgecolors="#9fb3c8", linewidths=0.2))
        _outline(ax, polygon, "#ff7f0e", "-")


def _close_view(ax, model: RegimeModel, surveys: list[RegionSurvey]) -> None:
    """Zoom on the region with the smallest floes: three of its largest floes across."""
    laid = [(min(layer.spacing for layer in model.layers[s.region]), s) for s in surveys if len(s.layout.polygon)]
    if not laid:
        ax.set_title("no floes laid")
        return
    s = min(laid, key=lambda item: item[0])[1]
    at = shapely.point_on_surface(s.surveyed)
    half = 1.5 * max(layer.spacing for layer in model.layers[s.region])
    ax.set_xlim(at.x - half, at.x + half)
    ax.set_ylim(at.y - half, at.y + half)
    ax.set_title(f"close view: {model.regions[s.region].name}")


def _parts(geometry: shapely.Geometry) -> list[shapely.Polygon]:
    return [p for p in shapely.get_parts(geometry) if isinstance(p, shapely.Polygon) and not p.is_empty]


def _outline(ax, geometry: shapely.Geometry, colour: str, style: str) -> None:
    for p in _parts(geometry):
        x, y = p.exterior.xy
        ax.plot(x, y, color=colour, linestyle=style, linewidth=1.0)


def _fill(ax, geometry: shapely.Geometry, colour: str, hatch: str | None) -> None:
    for p in _parts(geometry):
        ax.fill(*p.exterior.xy, facecolor=colour, edgecolor="#5b7a99", hatch=hatch, linewidth=0)
