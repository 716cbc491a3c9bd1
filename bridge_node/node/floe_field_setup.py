"""The floe fields of a configured exercise: the tiles whose centres lie in a floe-field
region (a chart's or the config's) take a thickness class of their own, laid from that
region's pack templates (``sim_core.regimes.pack_tiles``), built when the world is."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely

from bridge_node.charts.field_regions import configured_regions
from bridge_node.common.errors import UserError
from bridge_node.library.templates import library_pack_template
from bridge_node.node.config import NodeConfig
from sim_core.fracture.tile_template import TileTemplate
from sim_core.regimes.floe_layout import compile_regimes
from sim_core.regimes.pack_tiles import template_count
from sim_core.regimes.regime import IceRegion, tile_regions
from sim_core.scene.field import tile_counts

MAX_CLASSES = 256  # tile classes are bytes


@dataclass(frozen=True)
class FieldRegions:
    """A field's ice regions (local frame) and the index (ny, nx) of the region holding each
    tile's centre (-1: none; None: the field has no regions)."""

    regions: list[IceRegion]
    index: np.ndarray | None


def field_regions(cfg: NodeConfig) -> FieldRegions:
    """The configured field's ice regions (its chart's, then its own; the chart read once)
    and the region holding each tile's centre (``tile_regions``); none without either."""
    if not (cfg.ice_field.chart or cfg.ice_field.regions):
        return FieldRegions([], None)
    regions = configured_regions(cfg.ice_field, cfg.exercise.origin_deg())
    nx, ny = tile_counts(cfg.ice_field, cfg.fracture.tile_side)
    return FieldRegions(regions, tile_regions(regions, nx, ny, cfg.fracture.tile_side))


@dataclass(frozen=True)
class FloeFieldClasses:
    """A field's tile classes (ny, nx) and class thicknesses (m) with its floe fields'
    classes added, and each added class's templates, name (its egg code's label) and the
    tiles across the square its templates repeat in (0: they are variants)."""

    tile_class: np.ndarray
    class_h: np.ndarray
    templates: list[list[TileTemplate]]
    names: list[str]
    repeat: list[int]


def lay_floe_fields(cfg: NodeConfig, config_path: str | None, laid: FieldRegions, tile_class: np.ndarray,
                    class_h: np.ndarray, beam: float, cache: Path) -> FloeFieldClasses:
    """The field's tile classes and class thicknesses with a class added per regime (egg
    code) of the floe-field regions that hold a tile's centre, laid from the first such
    region (``pack_tiles.template_count`` templates, from the template library in ``cache``;
    floes wider than the ship's ``beam``, m, pre-fractured). A class's thickness is its
    thickest floes'."""
    regions, index = laid.regions, laid.index
    packs = [] if index is None else [r for r, region in enumerate(regions) if region.floe_field and np.any(index == r)]
    if not packs:
        return FloeFieldClasses(tile_class, class_h, [], [], [])
    side = cfg.fracture.tile_side
    nx, ny = tile_counts(cfg.ice_field, side)
    regimes = compile_regimes(regions, shapely.box(0.0, 0.0, nx * side, ny * side), cfg.fracture.seed, side)
    tile_class, classes = np.array(tile_class, dtype=np.uint8), {}  # regime -> its class's first region
    for r in packs:  # regions of one egg code share a class and its templates
        classes.setdefault(regions[r].regime, r)
    if len(class_h) + len(classes) > MAX_CLASSES:
        raise UserError(f"{config_path or 'default config'}: ice_field: {len(class_h)} thickness classes and "
                        f"{len(classes)} floe-field regimes; at most {MAX_CLASSES} in all (raise class_step)")
    first = list(classes.values())
    for r in packs:
        tile_class[index == r] = len(class_h) + first.index(classes[regions[r].regime])
    templates = [[library_pack_template(cache, regimes, r, v, cfg.fracture, cfg.ice_material, beam)
                  for v in range(template_count(regimes, r, cfg.fracture.variants))] for r in first]
    thickness = [max(t.thickness for t in variants) for variants in templates]
    return FloeFieldClasses(tile_class, np.concatenate([class_h, thickness]), templates,
                            [regions[r].regime.label() for r in first], [regimes.repeat[r] for r in first])
