"""Tile templates of a floe field: the floes of a region's regime on one tile, each floe a
cell that starts loose (a free floe), with open water between them.

A floe-field region's tiles are laid from a few such templates (variants, turned by
quarter turns, as level ice's templates are), so the scene, the stream, freezing and
thawing treat a pack tile as any other tile. Each variant is a tile-sized window of the
region's layout (``floe_layout.lay_out``, unbounded by the region's polygon) at a place of
its own, so variants differ; a floe the window's edge cuts is cut there, so a straight
lead runs along tile edges.

Why by hand: a template is this project's own format (``TileTemplate``); the floes come
from ``floe_layout``, their prisms from ``voronoi_cells.extrude_polygons``.

Not laid: types whose floes are under ``MIN_FLOE_SIZE`` (brash and pancake ice), which
would be tens of thousands of bodies a tile; their share shows as open water.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import shapely

from sim_core.fracture.tile_template import TileTemplate
from sim_core.fracture.voronoi_cells import CellGeometry, extrude_polygons, polygon_area_centroid
from sim_core.material import IceMaterial
from sim_core.regimes.floe_layout import RegimeModel, lay_out
from sim_core.regimes.regime import MIN_FLOE_SIZE
from sim_core.csr import offsets

MIN_FLOE_AREA = 0.5  # m2: slivers the tile's edge cuts off smaller than this are dropped
VARIANT_STRIDE = 1.0e6  # m between the windows of a region's variants (far beyond any layout's reach)


def laid_layers(model: RegimeModel, region: int) -> list[int]:
    """The region's layers (largest floes first) the world lays as bodies: those whose WMO
    size range starts at ``MIN_FLOE_SIZE`` or more."""
    regime = model.regions[region].regime
    return [k for k, layer in enumerate(model.layers[region])
            if regime.types[layer.ice_type].size_range.low >= MIN_FLOE_SIZE]


def pack_template(model: RegimeModel, region: int, variant: int, side: float,
                  material: IceMaterial | None = None) -> TileTemplate:
    """The floes of a region's regime on a tile of ``side`` m, as a template whose cells
    start loose.

    Parameters
    ----------
    model : the compiled regimes (``floe_layout.compile_regimes``).
    region : the region's index in it; a floe field (not level ice, not ice free).
    variant : which window of the region's layout (a different floe pattern each).
    side : tile side, m.

    Returns
    -------
    A prism ``TileTemplate`` in the tile's frame ([0, side]^2, m): one cell per floe with its
    type's thickness (``cell_thickness``), mesh colliders, ``loose`` set.
    """
    material = material or IceMaterial()
    unbounded = dataclasses.replace(model, polygons=tuple(
        shapely.box(-1e9, -1e9, 1e9, 1e9) if k == region else p for k, p in enumerate(model.polygons)))
    x0 = VARIANT_STRIDE * (1 + variant)
    window = (x0, x0, x0 + side, x0 + side)
    floes, thickness = [], []
    for k in laid_layers(model, region):
        laid = lay_out(unbounded, window, region, k)
        cut = shapely.clip_by_rect(laid.polygon, *window)
        keep = (shapely.get_type_id(cut) == 3) & (shapely.area(cut) >= MIN_FLOE_AREA)  # 3: a polygon
        floes += list(shapely.orient_polygons(cut[keep]))
        thickness += laid.thickness[keep].tolist()
    return _template(floes, np.array(thickness), (x0, x0), side, material, model, region, variant)


def _template(floes: list, thickness: np.ndarray, corner: tuple[float, float], side: float,
              material: IceMaterial, model: RegimeModel, region: int, variant: int) -> TileTemplate:
    """Prisms of the floes (shapely polygons, m, their window's corner at ``corner``)."""
    rings = [np.asarray(f.exterior.coords)[:-1] - corner for f in floes]
    foot_start = offsets(np.array([len(r) for r in rings], dtype=np.int64))
    poly = np.vstack(rings) if rings else np.zeros((0, 2))
    area, centre = polygon_area_centroid(poly, foot_start)
    verts, vert_start, tris, tri_start = extrude_polygons(poly, foot_start, 1.0)
    verts[:, 2] *= np.repeat(thickness, np.diff(vert_start))  # each floe its own type's thickness
    n = len(rings)
    centroid = np.column_stack([centre, 0.5 * thickness]) if n else np.zeros((0, 3))
    geometry = CellGeometry(verts=verts, vert_start=vert_start, tris=tris, tri_start=tri_start, footprint=poly,
                            foot_start=foot_start, volume=area * thickness, centroid=centroid,
                            adj_pairs=np.zeros((0, 2), np.int32), adj_area=np.zeros(0))
    cell = np.repeat(np.arange(n), np.diff(vert_start))
    enclosing = np.zeros(n)
    np.maximum.at(enclosing, cell, np.linalg.norm(verts - centroid[cell], axis=1))
    return TileTemplate(side=side, thickness=float(thickness.max(initial=0.0)), mode="prism",
                        seed=model.layers[region][0].salt * 16 + variant, seeds=centroid.copy(), geometry=geometry,
                        mass=geometry.volume * material.density, is_sphere=np.zeros(n, dtype=bool),
                        sphere_radius=enclosing, cell_thickness=thickness, loose=True)
