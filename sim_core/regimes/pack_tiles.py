"""Tile templates of a floe field: the floes of a region's regime on one tile, with open
water between them. Floes narrower than the ship's beam are a cell each that starts as a
free floe, one body the hull pushes aside or under; wider ones, which a ship's bow breaks
rather than pushes, are the paper's thickness-dependent pre-fracture (the level-ice template
of their thickness, §2.1) cut to the floe, cells that start intact and break free as level
ice does; each cell records its floe (``TileTemplate.floe``), so that the world can move the
floe's intact cells as one body (``sim_core.ice.compound_floes``).

A floe-field region's tiles are laid from a few such templates, so the scene, the stream,
freezing and thawing treat a pack tile as any other tile. Where the region's layout repeats
in a square of n x n tiles (``floe_layout``, laid for tiles), its templates are the n * n
windows of that square, and the scene lays each tile from the window its place in the
square gives (``sim_core.scene.scene.tile_layout``), unturned: the floes that reach over a
tile's edge are cut there, and the neighbouring tile continues them, so floes run on across
tile edges (a floe so cut is two pieces, flush: two bodies if narrower than the beam, two
parts of the pre-fracture if wider). Where it does not repeat (floes too large for a few
tiles' square), the templates are variants, windows far apart, turned by quarter turns as
level ice's templates are, and a floe ends in a straight edge at a tile edge.

Why by hand: a template is this project's own format (``TileTemplate``); the floes come
from ``floe_layout``, the pre-fracture from ``tile_template.build_tile``, the cuts from
shapely, the prisms from ``voronoi_cells.extrude_polygons``.

Not laid: types whose floes are under ``MIN_FLOE_SIZE`` (brash and pancake ice), which
would be tens of thousands of bodies a tile; their share shows as open water.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import shapely

from sim_core.fracture.tile_template import FractureSettings, TileTemplate, build_tile, template_seed
from sim_core.fracture.voronoi_cells import CellGeometry, extrude_polygons, polygon_area_centroid
from sim_core.material import IceMaterial
from sim_core.regimes.floe_layout import RegimeModel, lay_out
from sim_core.regimes.regime import MIN_FLOE_SIZE
from sim_core.csr import offsets

MIN_FLOE_AREA = 0.5  # m2: slivers the tile's edge cuts off smaller than this are dropped
VARIANT_STRIDE = 1.0e6  # m between the windows of a region's variants (far beyond any layout's reach)
BIG_FLOE_SIZE = 100.0  # m: floes this size and larger are pre-fractured, by default (the world: the ship's beam)


def laid_layers(model: RegimeModel, region: int) -> list[int]:
    """The region's layers (largest floes first) the world lays: those whose WMO size range
    starts at ``MIN_FLOE_SIZE`` or more."""
    regime = model.regions[region].regime
    return [k for k, layer in enumerate(model.layers[region])
            if regime.types[layer.ice_type].size_range.low >= MIN_FLOE_SIZE]


@dataclass
class _Cells:
    """A pack template's cells as they are gathered: plan polygons (shapely, window m),
    thickness m, Voronoi seed (x, y; window m) and whether each starts free."""

    polygons: list = field(default_factory=list)
    thickness: list = field(default_factory=list)
    seeds: list = field(default_factory=list)
    free: list = field(default_factory=list)
    floe: list = field(default_factory=list)
    floes: int = 0  # pre-fractured floes so far

    def add(self, polygons: np.ndarray, thickness: float, seeds: np.ndarray, free: bool,
            floe: np.ndarray | None = None) -> None:
        """Add cells; ``floe``: the index of each one's pre-fractured floe among those
        added with it (none: free floes)."""
        self.polygons += list(polygons)
        self.thickness += [thickness] * len(polygons)
        self.seeds += [tuple(p) for p in seeds]
        self.free += [free] * len(polygons)
        if floe is None:
            self.floe += [-1] * len(polygons)
            return
        self.floe += (self.floes + np.unique(floe, return_inverse=True)[1]).tolist()
        self.floes += len(np.unique(floe))


def template_count(model: RegimeModel, region: int, variants: int) -> int:
    """How many templates a floe-field region's tiles are laid from: the windows of the
    square its layout repeats in, else ``variants``."""
    return model.repeat[region] ** 2 or variants


def template_window(model: RegimeModel, region: int, index: int, side: float) -> tuple[float, float]:
    """South-west corner (m, the layout's frame) of a region's template ``index``: in a
    repeating layout, window (index % n, index // n) of its square of n x n tiles (side
    ``side``, m, the layout's tile side); else a variant's place of its own."""
    repeat = model.repeat[region]
    if not repeat:
        x0 = VARIANT_STRIDE * (1 + index)
        return x0, x0
    if not math.isclose(side, model.tile_side):
        raise ValueError(f"tile side {side} m: the regimes were laid for tiles of {model.tile_side} m")
    return (index % repeat) * side, (index // repeat) * side


def pack_template(model: RegimeModel, region: int, variant: int, fracture: FractureSettings | None = None,
                  material: IceMaterial | None = None, big_floe: float = BIG_FLOE_SIZE) -> TileTemplate:
    """The floes of a region's regime on a tile of ``fracture.tile_side`` m, as a template.

    Parameters
    ----------
    model : the compiled regimes (``floe_layout.compile_regimes``).
    region : the region's index in it; a floe field (not level ice, not ice free).
    variant : which window of the region's layout (``template_window``; up to
        ``template_count``).
    fracture : how level ice is pre-fractured (the big floes' cells); its tile side.
    big_floe : m: floes this size or larger (mean caliper diameter, before the tile cuts them)
        are pre-fractured; the world gives the ship's beam.

    Returns
    -------
    A prism ``TileTemplate`` in the tile's frame ([0, side]^2, m), ``floe_field`` set: a cell
    per floe under ``big_floe`` (``starts_free``), the pre-fracture's cells cut to each larger
    floe (intact, their floe's index in ``floe``), each its type's thickness
    (``cell_thickness``); mesh colliders.
    """
    fracture, material = fracture or FractureSettings(), material or IceMaterial()
    side = fracture.tile_side
    unbounded = dataclasses.replace(model, polygons=tuple(
        shapely.box(-1e9, -1e9, 1e9, 1e9) if k == region else p for k, p in enumerate(model.polygons)))
    x0, y0 = template_window(model, region, variant, side)
    window = (x0, y0, x0 + side, y0 + side)
    cells = _Cells()
    for k in laid_layers(model, region):
        layer = model.layers[region][k]
        reach = 2.0 * layer.spacing  # the floes of grid points this far out may reach into the window
        grown = (window[0] - reach, window[1] - reach, window[2] + reach, window[3] + reach)
        laid = lay_out(unbounded, grown, region, k).polygon
        big = shapely.length(laid) / math.pi >= big_floe  # mean caliper diameter (Rothrock & Thorndike 1984)
        cut = shapely.clip_by_rect(laid, *window)
        keep = (shapely.get_type_id(cut) == 3) & (shapely.area(cut) >= MIN_FLOE_AREA)
        floes = shapely.orient_polygons(cut[keep & ~big])
        cells.add(floes, layer.thickness, shapely.get_coordinates(shapely.centroid(floes)), True)
        if np.any(keep & big):
            level = build_tile(layer.thickness, template_seed(fracture.seed, layer.thickness, variant), fracture,
                               material)
            pieces, seeds, floe = _prefractured(shapely.orient_polygons(cut[keep & big]), level, (x0, y0))
            cells.add(pieces, layer.thickness, seeds, False, floe)
    return _template(cells, (x0, y0), side, material, _seed(model, region, variant))


def _seed(model: RegimeModel, region: int, variant: int) -> int:
    """A pack template's seed: its region's first layer's hash salt and the variant (fewer
    than 64: ``floe_layout.REPEAT_TILES`` squared at most)."""
    return model.layers[region][0].salt * 64 + variant


def _prefractured(floes: np.ndarray, level: TileTemplate,
                  corner: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The level template's cells (laid at corner, m) cut to the floes: the pieces (convex
    polygons, as both are convex), each one's cell's Voronoi seed (x, y; m) and its floe
    (index into floes)."""
    g = level.geometry
    cell_polygons = shapely.polygons(shapely.linearrings(
        g.footprint + corner, indices=np.repeat(np.arange(level.n_cells), np.diff(g.foot_start))))
    cell, floe = shapely.STRtree(cell_polygons).query(floes, predicate="intersects")[::-1]
    pieces = shapely.intersection(cell_polygons[cell], floes[floe])
    keep = (shapely.get_type_id(pieces) == 3) & (shapely.area(pieces) >= MIN_FLOE_AREA)
    return shapely.orient_polygons(pieces[keep]), level.seeds[cell[keep], :2] + corner, floe[keep]


def _template(cells: _Cells, corner: tuple[float, float], side: float, material: IceMaterial,
              seed: int) -> TileTemplate:
    """Prisms of the cells (their window's corner at ``corner``, m)."""
    thickness, n = np.array(cells.thickness, dtype=float), len(cells.polygons)
    rings = [np.asarray(f.exterior.coords)[:-1] - corner for f in cells.polygons]
    foot_start = offsets(np.array([len(r) for r in rings], dtype=np.int64))
    poly = np.vstack(rings) if rings else np.zeros((0, 2))
    area, centre = polygon_area_centroid(poly, foot_start)
    verts, vert_start, tris, tri_start = extrude_polygons(poly, foot_start, 1.0)
    verts[:, 2] *= np.repeat(thickness, np.diff(vert_start))  # each cell its own type's thickness
    centroid = np.column_stack([centre, 0.5 * thickness]) if n else np.zeros((0, 3))
    geometry = CellGeometry(verts=verts, vert_start=vert_start, tris=tris, tri_start=tri_start, footprint=poly,
                            foot_start=foot_start, volume=area * thickness, centroid=centroid,
                            adj_pairs=np.zeros((0, 2), np.int32), adj_area=np.zeros(0))
    owner = np.repeat(np.arange(n), np.diff(vert_start))
    enclosing = np.zeros(n)
    np.maximum.at(enclosing, owner, np.linalg.norm(verts - centroid[owner], axis=1))
    seeds = np.column_stack([np.array(cells.seeds).reshape(-1, 2) - corner, 0.5 * thickness])
    return TileTemplate(side=side, thickness=float(thickness.max(initial=0.0)), mode="prism", seed=seed,
                        seeds=seeds, geometry=geometry, mass=geometry.volume * material.density,
                        is_sphere=np.zeros(n, dtype=bool), sphere_radius=enclosing, cell_thickness=thickness,
                        floe_field=True, starts_free=np.array(cells.free, dtype=bool),
                        floe=np.array(cells.floe, dtype=np.int32))
