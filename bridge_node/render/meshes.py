"""Static GPU geometry of a world: template cells as triangles and as cell rasters (the
ships' mesh is in ``ship_mesh``)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw
from scipy import ndimage

from sim_core.csr import gather_ranges
from sim_core.scene.scene import tile_layout
from sim_core.world import WorldModel


def cell_vertices(model: WorldModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangles of every template cell, wound counter-clockwise from outside: (position 3f,
    normal 3f) per vertex, each cell's tops first, then its sides and its bottom (drawn
    with the sides, near the eye: a floe turned up on edge or over shows its underside;
    culled, as back faces, while it floats flat). Returns the vertices, each global cell's
    first vertex (G + 1,) and its first side vertex (G,)."""
    ice = model.ice
    tris = ice.tris.copy()
    owner = np.repeat(np.arange(len(ice.mass)), np.diff(ice.tri_start))
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    inward = (n * tris.mean(axis=1)).sum(axis=1) < 0.0  # the centroid is the origin
    n[inward] *= -1.0
    tris[inward] = tris[inward][:, ::-1]
    side = n[:, 2] < 0.5  # sides and bottoms
    order = np.lexsort((side, owner))  # by cell, tops before sides
    tris, n, owner, side = tris[order], n[order], owner[order], side[order]
    out = np.zeros((len(tris) * 3, 6), dtype="f4")
    out[:, :3] = tris.reshape(-1, 3)
    out[:, 3:] = np.repeat(n, 3, axis=0)
    cells = len(ice.mass)
    start = np.concatenate([[0], np.cumsum(3 * np.bincount(owner, minlength=cells))])
    side_start = start[:-1] + 3 * np.bincount(owner[~side], minlength=cells)
    return out, start, side_start


# A vertex of a template's cells: position about the cell's centroid (m), outward normal,
# and the cell's index in the template (28 bytes).
CELL_VERTEX = np.dtype([("pos", "f4", 3), ("normal", "f4", 3), ("cell", "i4")])


@dataclass(frozen=True)
class TemplateMesh:
    """One template's cells as indexed triangles, made once and shared by every tile laid
    with it: distinct vertices (``CELL_VERTEX``; a vertex shared by a cell's triangles is
    kept once, so that llvmpipe shades it once), and the corners of each cell's triangles as
    vertex indices (uint16 where the vertices allow, else uint32): cell c's tops are
    ``index[start[c]:side_start[c]]``, its sides ``index[side_start[c]:start[c + 1]]``."""

    vertices: np.ndarray
    index: np.ndarray
    start: np.ndarray  # (n_cells + 1,)
    side_start: np.ndarray  # (n_cells,)

    def corners(self, cells: np.ndarray, sides: bool) -> np.ndarray:
        """Vertex indices of the tops (or the sides) of the given cells, in order."""
        a = self.side_start[cells] if sides else self.start[cells]
        b = self.start[cells + 1] if sides else self.side_start[cells]
        return self.index[gather_ranges(a, b)]


def template_meshes(model: WorldModel) -> list[TemplateMesh]:
    """Each template's ``TemplateMesh``, from ``cell_vertices``."""
    corners, start, side_start = cell_vertices(model)
    out = []
    for k, t in enumerate(model.ice.templates):
        g0, g1 = int(model.ice.template_start[k]), int(model.ice.template_start[k + 1])
        a = int(start[g0])
        data = np.zeros(int(start[g1]) - a, dtype=CELL_VERTEX)
        data["pos"], data["normal"] = corners[a:start[g1], :3], corners[a:start[g1], 3:]
        data["cell"] = np.repeat(np.arange(g1 - g0), np.diff(start[g0:g1 + 1]))
        _, first, inverse = np.unique(data.view(f"V{CELL_VERTEX.itemsize}"), return_index=True, return_inverse=True)
        order = np.argsort(first)  # distinct vertices in the order they first occur
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        index = rank[inverse.ravel()].astype(np.uint16 if len(order) <= 1 << 16 else np.uint32)
        out.append(TemplateMesh(data[first[order]], index, start[g0:g1 + 1] - a, side_start[g0:g1] - a))
    return out


def floe_field_layouts(model: WorldModel, tiles: np.ndarray, classes: np.ndarray) -> dict[int, int]:
    """Of these tiles (flat indices) of these classes, those of floe-field classes, and each
    one's template | quarter turns << 16 as the scene lays it: until simulated, such a tile
    is drawn from its template's raster, its floes where the template lays them."""
    scene = model.scene
    loose = np.array([len(t) > 0 and bool(model.ice.floe_field[t].all()) for t in scene.class_templates], dtype=bool)
    out = {}
    for tile, klass in zip(tiles.tolist(), classes.tolist()) if len(loose) else ():
        if loose[klass]:
            template, turns = tile_layout(scene, tile, klass)
            out[tile] = template | (turns << 16)
    return out


def cell_rasters(model: WorldModel, size: int) -> np.ndarray:
    """Per template, which cell covers each pixel of the tile: (templates * size, size)
    uint16, 1 + the cell's index within its template, 0 in the cracks between cells."""
    ice = model.ice
    out = []
    for k, t in enumerate(ice.templates):
        img = Image.new("I", (size, size), 0)
        draw = ImageDraw.Draw(img)
        scale = size / t.side
        g0 = ice.template_start[k]
        for c in range(t.n_cells):
            g = g0 + c
            ring = ice.outline[ice.outline_start[g]:ice.outline_start[g + 1]] + ice.centroid[g, :2]
            draw.polygon([tuple(p) for p in ring * scale], fill=c + 1)
        out.append(np.asarray(img, dtype=np.int64).astype(np.uint16))
    return np.vstack(out)


def rim_rasters(cells: np.ndarray, size: int, width_px: float) -> np.ndarray:
    """For each pixel of stacked cell rasters ((templates * size, size), 1 + cell, 0 in
    cracks), the nearest other cell within `width_px` (1 + its index; 0: none) and the
    distance to it in 1/256 px: (templates * size, size, 2) uint16. With the neighbour's
    status, the environment pass darkens the rim of level ice along open water."""
    out = np.zeros(cells.shape + (2,), dtype=np.uint16)
    for k in range(cells.shape[0] // size):
        lab = cells[k * size:(k + 1) * size].astype(np.int64)
        # across: at each pixel on a boundary, the other (non-crack) cell beside it
        across = np.zeros_like(lab)
        padded = np.pad(lab, 1)  # no wrapping: outside the tile is no cell
        for di, dj in ((0, 1), (2, 1), (1, 0), (1, 2)):
            other = padded[di:di + size, dj:dj + size]
            take = (other != lab) & (other != 0)
            across = np.where(take, np.maximum(across, other), across)
        edge = (across != 0) | (lab == 0)
        dist, (i, j) = ndimage.distance_transform_edt(~edge, return_indices=True)
        at_edge = np.where(lab[i, j] != lab, lab[i, j], across[i, j])
        near = (dist < width_px) & (at_edge != lab) & (at_edge != 0) & (lab != 0)
        out[k * size:(k + 1) * size, :, 0] = np.where(near, at_edge, 0)
        out[k * size:(k + 1) * size, :, 1] = np.minimum(dist * 256, 65535)
    return out
