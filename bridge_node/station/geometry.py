"""What the page needs once to draw the exercise: the field's extent and tile grid, every
template cell's plan outline and home centroid, the open-water tiles, the own ship's
waterline outline, and the local-plane scale of the latitude/longitude grid. Sent to each browser when it connects."""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely

from bridge_node.links.convoy import ConvoySettings
from bridge_node.station.wire import pack
from sim_core.csr import offsets
from sim_core.frames.geodesy import radii
from sim_core.regimes.regime import IceRegion, effective_polygons
from sim_core.scene.scene import SceneModel
from sim_core.world import WorldModel


def geometry_message(model: WorldModel, ship_name: str, rate_hz: float, regions: list[IceRegion] = (),
                     convoy: ConvoySettings | None = None, fleet: Sequence[str] = ()) -> bytes:
    """The ``geometry`` message: JSON for the field, ship (``ship_name``), the names of all
    own ships, the first first (``fleet``; unset: the ship alone), templates and the
    station's update rate (``rate_hz``, Hz); arrays of every
    global cell's outline points (x, y about its centroid, m), outline starts (G + 1) and
    centroid in its template's tile frame (x, y, m), the open-water tiles (``water_runs``), the
    tiles of brash alone (``brash_runs``), and
    the ice regions as they lie on the field (``regions`` in the header: name, egg code, kind,
    label point; their outline rings' points ``region_xy``, ring starts and owners), and the
    ridge lines' points ``ridge_xy`` and line starts ``ridge_start``; the exercise's ice
    classes (``ice_names``, ``ice_kinds``) and its convoy (``convoy``: the MMSIs of the ships
    ahead and astern and the alarm's distance, or null)."""
    ice, scene, ship = model.ice, model.scene, model.ship.particulars
    lat0, lon0 = model.origin
    m, n = radii(lat0)
    templates = [{"start": int(ice.template_start[k]), "cells": int(t.n_cells), "side": float(t.side)}
                 for k, t in enumerate(ice.templates)]
    header = {
        "type": "geometry",
        "field": {"nx": int(scene.nx), "ny": int(scene.ny), "side": float(scene.side)},
        "origin": {"latitude_deg": math.degrees(lat0), "longitude_deg": math.degrees(lon0),
                   "m_per_deg_lat": m * math.pi / 180.0, "m_per_deg_lon": n * math.cos(lat0) * math.pi / 180.0},
        "ship": {"name": ship_name, "length": float(ship.length), "beam": float(ship.beam),
                 "hull": np.round(model.contour, 3).tolist()},
        "fleet": list(fleet) or [ship_name],
        "searchlights": len(model.searchlights),
        "templates": templates,
        "ice_names": list(scene.class_names), "ice_kinds": ice_kinds(model),
        "rate_hz": rate_hz,
        "convoy": convoy.model_dump() if convoy is not None else None,
    }
    header["regions"], rings = region_outlines(list(regions), shapely.box(0.0, 0.0, scene.nx * scene.side,
                                                                          scene.ny * scene.side))
    arrays = {"outline": ice.outline[:, :2], "outline_start": ice.outline_start.astype(np.int64),
              "centroid": ice.centroid[:, :2], "water_runs": water_runs(scene),
              "brash_runs": brash_runs(model)} | rings | ridge_lines(model)
    return pack(header, arrays)


def ice_kinds(model: WorldModel) -> list[str]:
    """How the map draws each ice class: "water" (thickness 0), "pack" (a floe field's
    templates) or "ice" (level ice)."""
    scene, floe_field = model.scene, model.ice.floe_field
    return ["water" if h <= 0.0 else "pack" if len(t) and bool(floe_field[t].all()) else "ice"
            for h, t in zip(scene.class_thickness, scene.class_templates)]


def laid_runs(retiled: dict[int, int], nx: int, ny: int) -> list[list[int]]:
    """The tiles the instructor gave other ice (tile -> class) as runs along the tile rows:
    [row, first column, tiles, class] each."""
    if not retiled:
        return []
    tiles, classes = np.array(list(retiled), dtype=np.int64), np.array(list(retiled.values()), dtype=np.int64)
    out = []
    for k in np.unique(classes).tolist():
        mask = np.zeros(nx * ny, dtype=bool)
        mask[tiles[(classes == k) & (tiles < nx * ny)]] = True
        out += [[*run, k] for run in tile_runs(mask.reshape(ny, nx)).reshape(-1, 3).tolist()]
    return out


def ridge_lines(model: WorldModel) -> dict[str, np.ndarray]:
    """The ridge fields' lines: points (x, y, m, flattened) and line starts (lines + 1)."""
    lines = [shapely.get_coordinates(line) for r in model.rubble.ridges for line in shapely.get_parts(r.lines())]
    return {"ridge_xy": np.concatenate(lines).ravel() if lines else np.zeros(0),
            "ridge_start": offsets(np.array([len(p) for p in lines], dtype=np.int64))}


def water_runs(scene: SceneModel) -> np.ndarray:
    """The field's open-water tiles (thickness 0: an ice-free region, or brash alone) as
    runs along the tile rows (``tile_runs``)."""
    return tile_runs((scene.class_thickness[scene.tile_class] <= 0.0).reshape(scene.ny, scene.nx))


def brash_runs(model: WorldModel) -> np.ndarray:
    """The field's tiles of brash alone (open water to the ice world, brash on it) as runs
    along the tile rows (``tile_runs``)."""
    scene, rubble = model.scene, model.rubble
    brash = (rubble.brash_share > 0.0) & (scene.class_thickness[scene.tile_class] <= 0.0)
    return tile_runs(brash.reshape(scene.ny, scene.nx))


def tile_runs(mask: np.ndarray) -> np.ndarray:
    """The tiles of a mask (ny, nx) as runs along the tile rows, flattened (row, first
    column, tiles) triples: a lake of thousands of tiles is a few numbers."""
    edges = np.diff(np.pad(mask.astype(np.int8), ((0, 0), (1, 1))), axis=1)
    rows, starts = np.nonzero(edges == 1)
    _, stops = np.nonzero(edges == -1)
    return np.column_stack([rows, starts, stops - starts]).astype(np.int64).ravel()



def region_outlines(regions: list[IceRegion], field: shapely.Geometry) -> tuple[list[dict], dict[str, np.ndarray]]:
    """The regions' part of the field as the page draws them: per region its name, egg code,
    kind and a point inside it for the label (m); and the outline rings (exterior and holes)
    of every part: points (x, y, m, flattened), ring starts (rings + 1) and the region each
    ring belongs to."""
    meta, points, owner = [], [], []
    for k, polygon in enumerate(effective_polygons(regions, field)):
        region = regions[k]
        at = shapely.point_on_surface(polygon) if not polygon.is_empty else None
        meta.append({"name": region.name, "regime": region.regime.label(), "kind": region.kind,
                     "label": None if at is None else [round(at.x, 1), round(at.y, 1)]})
        for ring in shapely.get_rings(shapely.get_parts(polygon)):
            points.append(shapely.get_coordinates(ring))
            owner.append(k)
    counts = np.array([len(p) for p in points], dtype=np.int64)
    return meta, {"region_xy": np.concatenate(points).ravel() if points else np.zeros(0),
                  "region_start": offsets(counts), "region_owner": np.array(owner, dtype=np.int64)}