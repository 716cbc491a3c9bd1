"""The sails of the ridges near the eye as rubble: triangles, built per tile when a tile
comes within ``sail_distance_m`` of the eye and dropped when it leaves, so a field of any
size costs only the ridges near the ship. Beyond that distance a sail is a few pixels high
and the environment pass draws it flat (``rubble_look``), as it does a tile whose sails
are not built yet: a frame builds the nearest tiles first, for at most ``BUILD_BUDGET_S``,
so that coming into a ridge field (a row of tiles entering the distance, or the first
frame) does not hold a frame up.

A sail is a jagged crest along its ridge line, its height varying block by block between
45 % and 100 % of the sail height and its crest wandering across the line, on a base four
times the sail height wide (``rubble_look.SAIL_BASE``): flat-shaded faces, each a block's
face, snow-white or the blue-green of fresh broken ice. The blocks of a tile are the same
each time it is built (seeded by the tile), so a sail does not change when the ship comes back.
"""
from __future__ import annotations

import math
import time

import moderngl
import numpy as np
import shapely

from bridge_node.render.rubble_look import SAIL_BASE
from sim_core.regimes.rubble import RubbleModel

BLOCK_LENGTH = 2.0  # m along the crest
BUILD_BUDGET_S = 0.003  # s of sail building a frame
SNOW = np.array([0.92, 0.94, 0.96])
FRESH = np.array([0.70, 0.85, 0.88])  # as the environment pass's FRESH_ICE
FRESH_SHARE = 0.15  # of the faces


def sail_triangles(line: np.ndarray, sail_height: float, base_z: float, seed: int) -> np.ndarray:
    """The sail along one polyline of a ridge.

    Parameters
    ----------
    line : (k, 2) the ridge line's points (x east, y north), m
    sail_height : m above ``base_z``
    base_z : m, the level ice's top
    seed : of the blocks' random heights, offsets and colours

    Returns
    -------
    (n, 9) float32 vertices of triangles: position (m), unit normal (up), colour (0-1).
    """
    ls = shapely.LineString(line)
    n_blocks = max(1, math.ceil(ls.length / BLOCK_LENGTH))
    at = shapely.line_interpolate_point(ls, np.linspace(0.0, ls.length, n_blocks + 1))
    p = shapely.get_coordinates(at)
    t = np.gradient(p, axis=0)
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-9)
    across = np.column_stack([-t[:, 1], t[:, 0]])
    rng = np.random.default_rng(seed)
    half = 0.5 * SAIL_BASE * sail_height
    crest_xy = p + across * rng.uniform(-0.2, 0.2, (len(p), 1)) * half
    crest = np.column_stack([crest_xy, base_z + sail_height * rng.uniform(0.45, 1.0, len(p))])
    sides = [np.column_stack([p + s * across * rng.uniform(0.85, 1.15, (len(p), 1)) * half, np.full(len(p), base_z)])
             for s in (-1.0, 1.0)]
    tris = []
    for base in sides:
        tris.append(np.stack([base[:-1], base[1:], crest[1:]], axis=1))
        tris.append(np.stack([base[:-1], crest[1:], crest[:-1]], axis=1))
    tris = np.concatenate(tris)  # (n, 3 corners, 3)
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normal *= np.where(normal[:, 2:] < 0.0, -1.0, 1.0) / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-9)
    fresh = rng.random(len(tris)) < FRESH_SHARE
    colour = np.where(fresh[:, None], FRESH, SNOW) * rng.uniform(0.7, 1.0, (len(tris), 1))
    per_vertex = np.concatenate([tris, np.repeat(normal[:, None], 3, axis=1),
                                 np.repeat(colour[:, None], 3, axis=1)], axis=2)
    return per_vertex.reshape(-1, 9).astype("f4")


class SailMeshes:
    """The sails' triangles of the tiles near the eye, drawn with the ship program (whose
    vertices are position, normal and colour)."""

    def __init__(self, ctx: moderngl.Context, program: moderngl.Program, rubble: RubbleModel, base_z: float,
                 distance: float) -> None:
        self.ctx, self.program, self.rubble, self.base_z, self.distance = ctx, program, rubble, base_z, distance
        self.lines = [r.lines() for r in rubble.ridges]
        self.tiles: dict[int, tuple[moderngl.Buffer, moderngl.VertexArray, int]] = {}
        self.built = np.zeros(len(rubble.ridge_tile), dtype=bool)  # by tile: in ``tiles``

    def update(self, eye: np.ndarray, budget_s: float = BUILD_BUDGET_S) -> None:
        """Build the tiles within the sail distance of the eye (x, y m), nearest first, for
        at most ``budget_s``; drop those beyond 1.2 times it."""
        r = self.rubble
        if not r.ridges:
            return
        lo = np.floor((eye[:2] - self.distance) / r.side).astype(int).clip(0, [r.nx - 1, r.ny - 1])
        hi = np.floor((eye[:2] + self.distance) / r.side).astype(int).clip(0, [r.nx - 1, r.ny - 1])
        j, i = np.mgrid[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1]
        tiles = (j * r.nx + i).ravel()
        tiles = tiles[(r.ridge_tile[tiles] >= 0) & ~self.built[tiles]]
        gap = self._gaps(tiles, eye)
        start = time.perf_counter()
        for k in np.argsort(gap)[:np.count_nonzero(gap <= self.distance)].tolist():
            if time.perf_counter() - start > budget_s:
                break
            tile = int(tiles[k])
            self._build(tile, tile % r.nx, tile // r.nx)
        built = np.fromiter(self.tiles, dtype=np.int64, count=len(self.tiles))
        for tile in built[self._gaps(built, eye) > 1.2 * self.distance].tolist():
            self._free(self.tiles.pop(tile))
            self.built[tile] = False

    def _gaps(self, tiles: np.ndarray, eye: np.ndarray) -> np.ndarray:
        """Distance (m) from the eye (x, y) to each tile's square (n,)."""
        side = self.rubble.side
        lo = np.column_stack([tiles % self.rubble.nx, tiles // self.rubble.nx]) * side
        gap = np.maximum(np.maximum(lo - eye[:2], eye[:2] - lo - side), 0.0)
        return np.hypot(gap[:, 0], gap[:, 1])

    def _build(self, tile: int, i: int, j: int) -> None:
        k = int(self.rubble.ridge_tile[tile])
        side, ridges = self.rubble.side, self.rubble.ridges[k]
        inside = shapely.intersection(self.lines[k], shapely.box(i * side, j * side, (i + 1) * side, (j + 1) * side))
        parts = [shapely.get_coordinates(g) for g in shapely.get_parts(inside) if g.geom_type == "LineString"]
        parts = [c for c in parts if len(c) >= 2 and np.linalg.norm(c[-1] - c[0]) > 0.1]
        self.built[tile] = True
        if not parts:
            self.tiles[tile] = (None, None, 0)
            return
        verts = np.concatenate([sail_triangles(c, ridges.sail_height, self.base_z, tile * 16 + n)
                                for n, c in enumerate(parts)])
        buf = self.ctx.buffer(verts.tobytes())
        vao = self.ctx.vertex_array(self.program, [(buf, "3f 3f 3f", "in_pos", "in_normal", "in_colour")])
        self.tiles[tile] = (buf, vao, len(verts))

    def render(self) -> None:
        """Draw the built tiles' sails (the program's uniforms set by the caller)."""
        for _, vao, count in self.tiles.values():
            if count:
                vao.render(vertices=count)

    @staticmethod
    def _free(entry: tuple) -> None:
        buf, vao, count = entry
        if count:
            vao.release()
            buf.release()
