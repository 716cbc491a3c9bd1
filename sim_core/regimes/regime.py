"""Ice regimes as the WMO egg code gives them, and the regions of a field that carry them.

A regime is a total concentration and up to three ice types, each a partial concentration
(tenths), a stage of development and a floe size (WMO codes, ``wmo_codes``). A region is a
polygon in the exercise's local frame (x east, y north, m) with its regime. Later regions
lie over earlier ones, so a region drawn by the instructor covers the chart under it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import shapely

from sim_core.regimes import wmo_codes
from sim_core.regimes.wmo_codes import CodeRange

SUM_SLACK = 0.5  # tenths: 9+/10 (9.5) may hold partials of 6/10 and 4/10
MIN_FLOE_SIZE = 2.0  # m: the ice world lays floes of WMO size ranges from this up as bodies (ice cakes and up)


@dataclass(frozen=True)
class IceType:
    """One ice type of a regime: its partial concentration (tenths) and WMO codes."""

    concentration: float
    stage: int
    floe_size: int

    @property
    def stage_range(self) -> CodeRange:
        return wmo_codes.stage(self.stage)

    @property
    def size_range(self) -> CodeRange:
        return wmo_codes.floe_size(self.floe_size)

    def label(self) -> str:
        """``6/10 thick_first_year small_floe``."""
        return f"{self.concentration:g}/10 {self.stage_range.name} {self.size_range.name}"


@dataclass(frozen=True)
class IceRegime:
    """Total concentration (tenths) and the ice types, thickest first, whose partial
    concentrations add up to the total."""

    total: float
    types: tuple[IceType, ...]

    @property
    def level(self) -> bool:
        """Level ice: fast ice, or 10/10 giant floes: no floe edges in an exercise area."""
        return len(self.types) == 1 and (self.types[0].floe_size == wmo_codes.FAST_ICE or (
            self.types[0].floe_size == wmo_codes.GIANT_FLOE and self.total >= 10.0))

    @property
    def rubble_types(self) -> tuple[IceType, ...]:
        """The types of pieces under ``MIN_FLOE_SIZE`` (brash, pancakes): not laid as bodies,
        they resist the hull as brash does (``sim_core.regimes.rubble``)."""
        return tuple(t for t in self.types if t.floe_size != wmo_codes.FAST_ICE and t.size_range.low < MIN_FLOE_SIZE)

    def label(self) -> str:
        if not self.types:
            return "ice free"
        if len(self.types) == 1 and self.types[0].concentration == self.total:
            return self.types[0].label()
        return f"{self.total:g}/10: " + ", ".join(t.label() for t in self.types)


def make_regime(total: float, types: list[tuple[float | None, int, int]]) -> IceRegime:
    """A checked regime from a total (tenths) and (partial concentration or None, stage
    code, floe-size code) per type, thickest first. A lone type's missing concentration is
    the total; where the partials add up to less than the total, the thickest type takes
    the rest (as ice services leave traces out of the partials). ValueError naming the
    wrong value."""
    if not 0.0 <= total <= 10.0:
        raise ValueError(f"total concentration {total:g}/10 is outside 0-10/10")
    if total == 0.0:
        return IceRegime(0.0, ())
    if not types:
        raise ValueError(f"total concentration {total:g}/10 but no ice type (stage and floe size)")
    if len(types) > 3:
        raise ValueError(f"{len(types)} ice types; the egg code has at most three")
    given = [c for c, _, _ in types]
    if None in given and len(types) > 1:
        raise ValueError("a partial concentration is missing; only a lone ice type may leave it out")
    partials = [total] if given == [None] else [float(c) for c in given]
    for c, (_, s, f) in zip(partials, types):
        if not 0.0 < c <= 10.0:
            raise ValueError(f"partial concentration {c:g}/10 is outside (0, 10]/10")
        wmo_codes.stage(s)
        wmo_codes.floe_size(f)
    if sum(partials) > total + SUM_SLACK or sum(partials) > 10.0:
        raise ValueError(f"partial concentrations add up to {sum(partials):g}/10, more than the total "
                         f"{total:g}/10")
    partials[0] += max(0.0, total - sum(partials))
    regime = IceRegime(total, tuple(IceType(c, s, f) for c, (_, s, f) in zip(partials, types)))
    if any(t.floe_size == wmo_codes.FAST_ICE for t in regime.types) and not regime.level:
        raise ValueError("fast ice is level ice: it is the only ice type of its region")
    return regime


RegionKind = Literal["ice", "water", "land", "no_data"]


@dataclass(frozen=True)
class IceRegion:
    """A region of the field: its name (where it came from), polygon (x east, y north, m),
    kind (a chart's POLY_TYPE) and regime (ice free for water, land and no data)."""

    name: str
    polygon: shapely.Geometry
    kind: RegionKind
    regime: IceRegime
    brash_thickness: float | None = None  # m, H_M of its brash; None: its thickest brash type's nominal

    @property
    def in_the_world(self) -> bool:
        """Whether the ice world lays this region out: level ice, ice-free water, a floe
        field with floes of at least ``MIN_FLOE_SIZE``, or brash and pancakes alone (open
        water that resists as brash does); not land or no data."""
        return self.regime.level or (self.kind in ("ice", "water") and not self.regime.types) or self.floe_field \
            or self.rubble_only

    @property
    def rubble_only(self) -> bool:
        """Sea ice of pieces under ``MIN_FLOE_SIZE`` alone: brash or pancakes."""
        return self.kind == "ice" and bool(self.regime.types) and \
            len(self.regime.rubble_types) == len(self.regime.types)

    @property
    def rubble(self) -> tuple[float, float]:
        """The share of the region's area its brash and pancakes cover (0-1) and their
        thickness H_M (m): ``brash_thickness``, else the thickest such type's nominal."""
        types = self.regime.rubble_types if self.kind == "ice" else ()
        if not types:
            return 0.0, 0.0
        h = self.brash_thickness if self.brash_thickness is not None else types[0].stage_range.nominal
        return sum(t.concentration for t in types) / 10.0, h

    @property
    def floe_field(self) -> bool:
        """Whether the world lays this region as a floe field: sea ice that is not level, of
        which some type's floes are ``MIN_FLOE_SIZE`` across or more."""
        return self.kind == "ice" and not self.regime.level and any(
            t.size_range.low >= MIN_FLOE_SIZE for t in self.regime.types)


def effective_polygons(regions: list[IceRegion], area: shapely.Geometry) -> list[shapely.Geometry]:
    """Each region's part of the area that no later region covers: the regions as they lie."""
    out, above = [], shapely.Polygon()
    for region in reversed(regions):
        out.append(shapely.difference(shapely.intersection(region.polygon, area), above))
        above = shapely.union(above, region.polygon)
    return out[::-1]


def region_at(polygons: list[shapely.Geometry], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Index of the (effective) polygon holding each point (n,), -1 where none does."""
    index = np.full(np.shape(x), -1, dtype=np.int64)
    for i, polygon in enumerate(polygons):
        index[shapely.contains_xy(polygon, x, y)] = i
    return index


def tile_regions(regions: list[IceRegion], nx: int, ny: int, side: float) -> np.ndarray:
    """Index (ny, nx) of the region (as they lie, later over earlier) holding each tile's
    centre, of a field of nx x ny tiles of ``side`` m; -1 where none does."""
    field = shapely.box(0.0, 0.0, nx * side, ny * side)
    x, y = np.meshgrid((np.arange(nx) + 0.5) * side, (np.arange(ny) + 0.5) * side)
    return region_at(effective_polygons(regions, field), x, y)


def region_tile_thickness(regions: list[IceRegion], index: np.ndarray, max_thickness: float) -> np.ndarray:
    """Thickness (ny, nx) m of each tile of a field, from the region holding its centre
    (``index``, from ``tile_regions``): a level-ice region's stage (the middle of
    its range, at most ``max_thickness``), 0 for an ice-free region or one of brash alone
    (open water; the brash resists through ``sim_core.regimes.rubble``); NaN where
    no region lies, or one the ice world does not lay out as level ice (floe fields, laid
    from their own templates; land, no data), so that the field's own thickness profile
    holds there."""
    per_region = np.array([0.0 if r.rubble_only else np.nan if not r.in_the_world or r.floe_field else
                           min(r.regime.types[0].stage_range.nominal, max_thickness) if r.regime.level else 0.0
                           for r in regions] + [np.nan])
    return per_region[index]  # index -1 (no region) takes the last entry, NaN
