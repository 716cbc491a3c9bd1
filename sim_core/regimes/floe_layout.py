"""Floe fields laid out from ice regimes: floes of each type's WMO size at its partial
concentration, with open water between them.

Why by hand: no library lays out a floe field to an egg code. Published floe-field
generators place floes by trial and error (they jam above about 0.75 concentration), so
this one tessellates instead. Each ice type is a layer. Its floes are the Voronoi cells of a
jittered grid whose spacing sets the floe size; each cell is shrunk about its centroid by
``s``, which leaves the area fraction ``s**2`` as ice and the rest as leads between the
floes. The first layer (the largest floes) tiles the region, so ``s**2`` is its partial
concentration. A later layer keeps only the cells that lie wholly in the water the earlier
layers leave, and its ``s`` is calibrated once, on a reference patch (or, where its floes
are far smaller than the leads, by estimate), to give its partial concentration there;
where its floes are too large to fill the leads so, they are made smaller, within their
WMO size range. A floe's size is its mean caliper diameter (Rothrock & Thorndike 1984,
"Measuring the sea ice floe size distribution", JGR 89(C4) 6477), which for a convex
polygon is its perimeter over pi (Cauchy); a Voronoi cell of unit density has a mean
perimeter of 4, so the spacing for a target size D at shrink s is pi D / (4 s).

The grid is anchored to the field and its jitter hashed from (seed, region, layer, grid
node), so a window's floes do not depend on which windows were laid before: a floe belongs
to the window that holds its grid point. Floes are clipped to their region, so a region's
border is an ice edge.

Laid for the world's tiles (``compile_regimes`` given the tile side), a region's layout
repeats: every layer's spacing divides a square of a few whole tiles, and its grid nodes
are hashed modulo that square, so the floes repeat with it. Tiles laid from the square's
windows then continue one another's floes across every tile edge, whichever of them lie
side by side (``pack_tiles``). The repeat holds three of the largest floes across, or at
least two (``FLOES_PER_REPEAT``), within ``REPEAT_TILES`` (the tile templates it costs); a
region whose largest floes are too large for that does not repeat.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import shapely
from scipy.spatial import Voronoi

from sim_core.regimes.regime import IceRegion, effective_polygons

JITTER = 0.8  # grid points move up to +-0.4 spacing: cell sizes spread over about 2x
MAX_SHRINK = 0.985  # the narrowest lead, as a share of the cell: floes never start in contact
SIZE_SPREAD = 1.5  # the smallest of a layer's floes are about its median size over this
CALIBRATION_CELLS = 200  # a later layer's reference patch is at most this many of its cells across
FLOES_PER_REPEAT = (3, 2)  # the largest floes across a repeating layout's square: wanted, and at least
REPEAT_TILES = (4, 8)  # tiles across that square, fewest and most (its templates: the square of it)
Window = tuple[float, float, float, float]  # x0, y0, x1, y1, m


@dataclass(frozen=True)
class Layer:
    """One ice type of one region as laid out: grid spacing (m), shrink of its cells, the
    hash salt of its grid, its nominal thickness (m), and the grid nodes across the layout's
    repeat (0: it does not repeat)."""

    region: int
    ice_type: int
    spacing: float
    shrink: float
    salt: int
    thickness: float
    period: int = 0


@dataclass(frozen=True)
class RegimeModel:
    """Static floe-field data: the regions, the part of the field each holds (effective
    polygons, m), the layers of each (largest floes first), and, laid for tiles, the tile
    side (m; 0: not) and how many tiles across each region's layout repeats (0: it does not)."""

    regions: tuple[IceRegion, ...]
    polygons: tuple[shapely.Geometry, ...]
    layers: tuple[tuple[Layer, ...], ...]
    tile_side: float
    repeat: tuple[int, ...]


@dataclass(frozen=True)
class FloeLayout:
    """Floes of a window, one row each: polygon (x east, y north, m, counter-clockwise),
    region index, ice-type index in its region's regime, thickness m, and whether the
    region's border cut it."""

    polygon: np.ndarray
    region: np.ndarray
    ice_type: np.ndarray
    thickness: np.ndarray
    clipped: np.ndarray

    def __len__(self) -> int:
        return len(self.polygon)


def compile_regimes(regions: list[IceRegion], area: shapely.Geometry, seed: int,
                    tile_side: float | None = None) -> RegimeModel:
    """The layers of every region within the area (the field, m), calibrated once; given
    the world's ``tile_side`` (m), each region's layout repeats in whole tiles where its
    floes allow (``repeat_tiles``)."""
    polygons = effective_polygons(regions, area)
    side = tile_side or 0.0
    nominal = [_nominal_layers(region) for region in regions]
    repeat = tuple(repeat_tiles(layers[0][1] if layers else 0.0, side) for layers in nominal)
    layers = tuple(_region_layers(r, region, seed, nominal[r], repeat[r] * side) for r, region in enumerate(regions))
    return RegimeModel(tuple(regions), tuple(polygons), layers, side, repeat)


def repeat_tiles(spacing: float, tile_side: float) -> int:
    """Tiles across the square a layout repeats in, for its largest floes' grid ``spacing``
    (m; 0: no floes) and the tile side (m; 0: not laid for tiles): enough for the wanted
    ``FLOES_PER_REPEAT`` floes within ``REPEAT_TILES``, else for the fewest; 0 (no repeat)
    where they are too large even for that."""
    if spacing <= 0.0 or tile_side <= 0.0:
        return 0
    fewest, most = REPEAT_TILES
    for floes in FLOES_PER_REPEAT:
        tiles = max(math.ceil(floes * spacing / tile_side), fewest)
        if tiles <= most:
            return tiles
    return 0


def _nominal_layers(region: IceRegion) -> list[tuple[int, float, float]]:
    """The region's layers as its regime sets them, largest floes first: each one's ice
    type (index in the regime), grid spacing (m) and shrink; none for level ice or ice free."""
    regime = region.regime
    if regime.level or not regime.types:
        return []
    out, water = [], 1.0
    for k in sorted(range(len(regime.types)), key=lambda i: -regime.types[i].size_range.nominal):
        ice = regime.types[k]
        shrink = math.sqrt(min(ice.concentration / 10.0 / water, MAX_SHRINK**2))
        size = math.sqrt(ice.size_range.low * ice.size_range.high)
        out.append((k, math.pi * size / (4.0 * shrink), shrink))
        water = max(water - ice.concentration / 10.0, 1e-3)
    return out


def _region_layers(r: int, region: IceRegion, seed: int, nominal: list[tuple[int, float, float]],
                   period: float) -> tuple[Layer, ...]:
    """The region's layers, from its ``nominal`` ones (``_nominal_layers``), their spacings
    dividing ``period`` (m; 0: the layout does not repeat), the later ones calibrated."""
    layers: list[Layer] = []
    water = 1.0
    for k, spacing, shrink in nominal:
        ice = region.regime.types[k]
        salt = (seed * 1_000_003 + r * 101 + k) & 0xFFFFFFFF
        d, nodes = _fitted(spacing, period)
        layer = Layer(r, k, d, shrink, salt, ice.stage_range.nominal, nodes)
        if layers:
            layer = _calibrated(layer, layers, ice.concentration / 10.0, water, ice.size_range.low, period)
        layers.append(layer)
        water = max(water - ice.concentration / 10.0, 1e-3)
    return tuple(layers)


def _fitted(spacing: float, period: float, more_than: int = 0) -> tuple[float, int]:
    """The grid spacing nearest ``spacing`` (m) that divides ``period`` (m; 0: any), with
    the nodes across the period (0 without one); more than ``more_than`` nodes."""
    if period <= 0.0:
        return spacing, 0
    nodes = max(round(period / spacing), more_than + 1)
    return period / nodes, nodes


def _calibrated(layer: Layer, earlier: list[Layer], fraction: float, water: float, low_size: float,
                period: float) -> Layer:
    """The later layer with the shrink that gives it its area fraction among the earlier
    layers' floes. Where its cells are too large to fill the leads to that fraction even at
    the largest shrink, its spacing is made smaller (still dividing ``period``, m), as long
    as its smallest floes stay in the WMO size range (above ``low_size``, m); short of that
    the layer stays under its fraction, and the survey shows it."""
    trial = layer
    while True:
        available = _available_share(trial, earlier, water)
        shrink = math.sqrt(fraction / available) if available > 0.0 else math.inf
        size = min(shrink, MAX_SHRINK) * 4.0 * trial.spacing / math.pi  # mean caliper diameter, m
        if shrink <= MAX_SHRINK or 0.8 * size < SIZE_SPREAD * low_size:
            return dataclasses.replace(trial, shrink=min(shrink, MAX_SHRINK))
        spacing, nodes = _fitted(0.8 * trial.spacing, period, trial.period)
        trial = dataclasses.replace(trial, spacing=spacing, period=nodes)


def _available_share(layer: Layer, earlier: list[Layer], water: float) -> float:
    """Share of the area in which the layer's cells lie wholly in the water the earlier
    layers leave (``water``, their complement). Measured on a reference patch (unbounded by
    any region) four of the largest earlier cells across, where that holds few enough of the
    layer's cells; else, the floes being far smaller than the leads, estimated: the water
    less a band half a cell wide along the earlier floes' edges (edge length per area
    ``4 s / d`` for cells of spacing d shrunk by s)."""
    if 4.0 * earlier[0].spacing <= CALIBRATION_CELLS * layer.spacing:
        side = max(4.0 * earlier[0].spacing, 30.0 * layer.spacing)
        patch = (0.0, 0.0, side, side)
        return float(shapely.area(_free_cells(_cells(patch, layer), earlier, patch)).sum()) / side**2
    edges = sum(4.0 * e.shrink / e.spacing for e in earlier)
    return max(water - edges * 0.56 * layer.spacing, 0.0)


def lay_out(model: RegimeModel, window: Window, region: int | None = None, layer: int | None = None) -> FloeLayout:
    """The floes whose grid points lie in the window (m), of every region or of one, of
    every layer or of one (by its place in the region's layers, largest floes first)."""
    parts = []
    for r, layers in enumerate(model.layers):
        polygon = model.polygons[r]
        if not layers or region not in (None, r):
            continue
        reach = 2.0 * max(e.spacing for e in layers)  # a cell reaches this far from its grid point
        x0, y0, x1, y1 = window
        if not shapely.intersects(polygon, shapely.box(x0 - reach, y0 - reach, x1 + reach, y1 + reach)):
            continue
        shapely.prepare(polygon)
        for k, laid in enumerate(layers):
            if layer not in (None, k):
                continue
            cells = _free_cells(_cells(window, laid), layers[:k], window)
            floes, clipped = _clip(_shrunk(cells, laid.shrink), polygon)
            n = len(floes)
            parts.append((floes, np.full(n, r), np.full(n, laid.ice_type), np.full(n, laid.thickness), clipped))
    return joined([FloeLayout(shapely.orient_polygons(p[0]), *p[1:]) for p in parts])


def joined(layouts: list[FloeLayout]) -> FloeLayout:
    """One layout of the floes of several."""
    if not layouts:
        return FloeLayout(np.zeros(0, dtype=object), *(np.zeros(0, dtype=t) for t in (int, int, float, bool)))
    return FloeLayout(*(np.concatenate(c) for c in zip(*(
        (f.polygon, f.region, f.ice_type, f.thickness, f.clipped) for f in layouts))))


def _free_cells(cells: np.ndarray, earlier: tuple[Layer, ...] | list[Layer], window: Window) -> np.ndarray:
    """The cells that touch no floe of the earlier layers (laid over the window grown by
    their reach, so floes owned by neighbouring windows count too)."""
    if not earlier or not len(cells):
        return cells
    reach = 2.0 * max(layer.spacing for layer in earlier) + 2.0 * max(_reach(cells), 0.0)
    x0, y0, x1, y1 = window
    grown = (x0 - reach, y0 - reach, x1 + reach, y1 + reach)
    floes = [_shrunk(_free_cells(_cells(grown, e), earlier[:i], grown), e.shrink) for i, e in enumerate(earlier)]
    tree = shapely.STRtree(np.concatenate(floes))
    hit = np.zeros(len(cells), dtype=bool)
    hit[tree.query(cells, predicate="intersects")[0]] = True
    return cells[~hit]


def _reach(cells: np.ndarray) -> float:
    bounds = shapely.bounds(cells)
    return float(np.max(np.maximum(bounds[:, 2] - bounds[:, 0], bounds[:, 3] - bounds[:, 1])))


def _cells(window: Window, layer: Layer) -> np.ndarray:
    """Voronoi cells (shapely polygons) of the layer's grid points inside the window."""
    d = layer.spacing
    x0, y0, x1, y1 = window
    i = np.arange(math.floor(x0 / d) - 2, math.ceil(x1 / d) + 2)
    j = np.arange(math.floor(y0 / d) - 2, math.ceil(y1 / d) + 2)
    ii, jj = (a.ravel() for a in np.meshgrid(i, j))
    if layer.period:  # a repeating layout: a node jitters as its twin in the first square does
        u, v = _hash_uniform(ii % layer.period, jj % layer.period, layer.salt)
    else:
        u, v = _hash_uniform(ii, jj, layer.salt)
    points = np.column_stack([(ii + 0.5 + JITTER * (u - 0.5)) * d, (jj + 0.5 + JITTER * (v - 0.5)) * d])
    owned = np.flatnonzero((points[:, 0] >= x0) & (points[:, 0] < x1) & (points[:, 1] >= y0) & (points[:, 1] < y1))
    if not len(owned):
        return np.zeros(0, dtype=object)
    vor = Voronoi(points)
    regions = [vor.regions[vor.point_region[p]] for p in owned]
    counts = np.array([len(reg) for reg in regions])
    rings = shapely.linearrings(vor.vertices[np.concatenate(regions)], indices=np.repeat(np.arange(len(owned)), counts))
    return shapely.polygons(rings)


def _shrunk(cells: np.ndarray, shrink: float) -> np.ndarray:
    """Cells scaled by ``shrink`` about their centroids."""
    if not len(cells):
        return cells
    coords, index = shapely.get_coordinates(shapely.get_exterior_ring(cells), return_index=True)
    centre = shapely.get_coordinates(shapely.centroid(cells))[index]
    return shapely.polygons(shapely.linearrings(centre + shrink * (coords - centre), indices=index))


def _clip(floes: np.ndarray, polygon: shapely.Geometry) -> tuple[np.ndarray, np.ndarray]:
    """Floes cut to the region's polygon (a floe it splits becomes several); which were cut."""
    inside = shapely.contains(polygon, floes)
    cut = shapely.get_parts(shapely.intersection(floes[~inside], polygon))
    cut = cut[(shapely.get_type_id(cut) == 3) & (shapely.area(cut) > 1e-6)]
    return (np.concatenate([floes[inside], cut]),
            np.concatenate([np.zeros(int(inside.sum()), dtype=bool), np.ones(len(cut), dtype=bool)]))


def _hash_uniform(i: np.ndarray, j: np.ndarray, salt: int) -> tuple[np.ndarray, np.ndarray]:
    """Two uniform numbers in [0, 1) per grid node, from SplitMix64's finaliser."""
    z = (i.astype(np.int64).astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
         ^ j.astype(np.int64).astype(np.uint64) * np.uint64(0xC2B2AE3D27D4EB4F) ^ np.uint64(salt))
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z ^= z >> np.uint64(31)
    return ((z >> np.uint64(40)).astype(np.float64) / 2**24,
            ((z >> np.uint64(16)) & np.uint64(0xFFFFFF)).astype(np.float64) / 2**24)
