"""The static index of a floe field's wide floes: which template cells make up each floe
wider than the beam (``TileTemplate.floe``), and where each floe lies in its template.

A wide floe is laid as the paper's pre-fracture cut to the floe (§2.1, intact cells held
together). ``sim_core.ice.compound_floes`` moves its intact cells as one body once a hull
comes near; this index tells it which cells those are and which floes a hull is near.

Only a floe's rim goes into the contact engine: a cell whose outline meets no edge of its
floe's outline (``inner``) is held back, since nothing can touch it through the cells
around it, until one of its ``mates`` (the floe's cells that may touch it) leaves the floe.
A woken floe of a few hundred metres then moves a tenth of its cells' shapes, and the
engine's broad phase (every moving shape re-indexed, and every pair of its neighbours on
the same body met and turned down, each step) costs a tenth as much.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from scipy.spatial import cKDTree

from sim_core.csr import offsets
from sim_core.fracture.tile_template import TileTemplate
from sim_core.ice.tile_frame import template_box

VERTEX_GRID = 1e-4  # m: the pieces' points are matched on this grid (``_inner_cells``)
MATE_GAP = 0.05  # m: cells whose enclosing circles come this near may touch (``_mate_pairs``)


@dataclass(frozen=True)
class WideFloes:
    """Every template's wide floes, by global floe index f (numbered template by template).

    ``template_floes`` (n_templates + 1,): each template's first floe; ``cells_start``
    (F + 1,) and ``cells`` (C,): each floe's cells as offsets in its template, ascending;
    ``box`` (F, 4): each floe's bounds in its template's frame, [x0, y0, x1, y1] m;
    ``of_cell`` (G,): each global cell's floe, -1 for cells of none; ``inner`` (G,): a wide
    floe's cell off its floe's outline; ``mates_start`` (G + 1,) and ``mates`` (M,): each
    cell's mates, global cells of its floe whose enclosing circles come within
    ``MATE_GAP`` of its own (empty for cells of no wide floe).
    """

    template_floes: np.ndarray
    of_cell: np.ndarray
    cells_start: np.ndarray
    cells: np.ndarray
    box: np.ndarray
    inner: np.ndarray
    mates_start: np.ndarray
    mates: np.ndarray


def compile_wide_floes(templates: tuple[TileTemplate, ...] | list[TileTemplate]) -> WideFloes:
    """Index the wide floes of the templates (``TileTemplate.floes``), their rims and mates."""
    per_template, cells, boxes, of_cell, inner, mates = [], [], [], [], [], []
    g0 = 0
    for t in templates:
        floe = t.floes
        count = int(floe.max(initial=-1)) + 1
        of_cell.append(np.where(floe >= 0, sum(per_template) + floe, -1))
        per_template.append(count)
        order = np.argsort(floe, kind="stable")
        cells.append(order[floe[order] >= 0])
        boxes.append(_floe_boxes(t, count))
        inner.append(_inner_cells(t))
        mates.append(g0 + _mate_pairs(t))
        g0 += t.n_cells
    sizes = np.concatenate([np.bincount(t.floes[t.floes >= 0], minlength=n) for t, n in zip(templates, per_template)]) \
        if templates else np.zeros(0, np.int64)
    pairs = np.vstack(mates) if mates else np.zeros((0, 2), np.int64)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    return WideFloes(template_floes=offsets(np.array(per_template, dtype=np.int64)),
                     of_cell=np.concatenate(of_cell).astype(np.int64) if of_cell else np.zeros(0, np.int64),
                     cells_start=offsets(sizes.astype(np.int64)),
                     cells=np.concatenate(cells).astype(np.int64) if cells else np.zeros(0, np.int64),
                     box=np.vstack(boxes) if boxes else np.zeros((0, 4)),
                     inner=np.concatenate(inner) if inner else np.zeros(0, bool),
                     mates_start=offsets(np.bincount(pairs[:, 0], minlength=g0).astype(np.int64)),
                     mates=pairs[:, 1].copy())


def _floe_boxes(t: TileTemplate, count: int) -> np.ndarray:
    """Each of the template's count wide floes' bounds (count, 4) [x0, y0, x1, y1], m."""
    g = t.geometry
    at = t.floes[np.repeat(np.arange(t.n_cells), np.diff(g.foot_start))]  # each outline point's floe
    on, x, y = at >= 0, g.footprint[:, 0], g.footprint[:, 1]
    box = np.column_stack([np.full((count, 2), np.inf), np.full((count, 2), -np.inf)])
    for col, reduce, values in ((0, np.minimum, x), (1, np.minimum, y), (2, np.maximum, x), (3, np.maximum, y)):
        reduce.at(box[:, col], at[on], values[on])
    return box


def _inner_cells(t: TileTemplate) -> np.ndarray:
    """The template's wide floes' cells (n,) bool with no point on their floe's outline.

    The pieces of one floe are the pre-fracture's Voronoi cells cut to it, so two pieces
    that meet share the edge between them, point for point (coordinates rounded to
    ``VERTEX_GRID``). An edge that one piece of the floe has and no other lies on the
    floe's outline (or where two pieces do not meet exactly, a T-junction or a dropped
    sliver: their cells then count as rim too, which only costs their shapes). A cell is
    inner if none of its points is an end of such an edge. Shapely's union of the pieces
    would give the outline too, at a hundred times the cost for thousand-cell floes."""
    g, floe = t.geometry, t.floes
    owner = np.repeat(np.arange(t.n_cells), np.diff(g.foot_start))
    wide = floe[owner] >= 0
    if not wide.any():
        return np.zeros(t.n_cells, bool)
    point = np.arange(len(owner))
    after = np.where(point + 1 == g.foot_start[owner + 1], g.foot_start[owner], point + 1)  # the ring's next point
    _, vertex = np.unique(np.round(g.footprint / VERTEX_GRID).astype(np.int64), axis=0, return_inverse=True)
    vertex = vertex.ravel()
    n_v = int(vertex.max()) + 1
    at = floe[owner].astype(np.int64) * n_v + vertex  # a point of a floe
    lo, hi = np.minimum(at, at[after]), np.maximum(at, at[after])
    edge = (lo * n_v + hi % n_v)[wide]
    _, which, count = np.unique(edge, return_inverse=True, return_counts=True)
    once = count[which.ravel()] == 1
    outline = np.union1d(lo[wide][once], hi[wide][once])
    rim = np.zeros(t.n_cells, bool)
    rim[owner[np.isin(at, outline)]] = True
    return (floe >= 0) & ~rim


def _mate_pairs(t: TileTemplate) -> np.ndarray:
    """Ordered pairs (k, 2) of template cells of one wide floe whose enclosing circles (the
    template's ``sphere_radius`` about each centroid) come within ``MATE_GAP``: the cells
    that may touch each other, both ways."""
    wide = np.flatnonzero(t.floes >= 0)
    if not len(wide):
        return np.zeros((0, 2), np.int64)
    centre, radius = t.geometry.centroid[wide, :2], t.sphere_radius[wide]
    pairs = cKDTree(centre).query_pairs(2.0 * float(radius.max()) + MATE_GAP, output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    near = np.hypot(*(centre[i] - centre[j]).T) < radius[i] + radius[j] + MATE_GAP
    keep = near & (t.floes[wide[i]] == t.floes[wide[j]])
    i, j = wide[i[keep]], wide[j[keep]]
    return np.column_stack([np.concatenate([i, j]), np.concatenate([j, i])]).astype(np.int64)


def held_back(wide: WideFloes, g0: int, intact: np.ndarray) -> np.ndarray:
    """Which cells (n,) bool of a tile of the template whose first global cell is g0, its
    cells intact (n,) bool, to hold out of the contact space: inner cells, intact, none of
    whose mates is gone (a mate lies in the same template)."""
    n = len(intact)
    start, stop = wide.mates_start[g0:g0 + n], wide.mates_start[g0 + 1:g0 + n + 1]
    if not len(intact) or start[0] == stop[-1]:
        return np.zeros(n, bool)
    gone = ~intact[wide.mates[start[0]:stop[-1]] - g0]
    bared = np.bincount(np.repeat(np.arange(n), stop - start)[gone], minlength=n) > 0
    return wide.inner[g0:g0 + n] & intact & ~bared


@numba.njit(cache=True)
def floes_near(placements, template, corner, turns, sides, template_floes, box, lo_x, lo_y, hi_x, hi_y):
    """The wide floes of the placements (k,) whose bounds (``WideFloes.box``) meet the world
    box [lo, hi] (m): (placement, global floe) pairs, as two arrays (``tile_frame``)."""
    n = 0
    for p in placements:
        t = template[p]
        n += template_floes[t + 1] - template_floes[t]
    out_p, out_f = np.empty(n, np.int64), np.empty(n, np.int64)
    n = 0
    for p in placements:
        t = template[p]
        if template_floes[t + 1] == template_floes[t]:
            continue
        x0, y0, x1, y1 = template_box(lo_x, lo_y, hi_x, hi_y, p, template, corner, turns, sides)
        for f in range(template_floes[t], template_floes[t + 1]):
            if box[f, 0] <= x1 and box[f, 2] >= x0 and box[f, 1] <= y1 and box[f, 3] >= y0:
                out_p[n], out_f[n] = p, f
                n += 1
    return out_p[:n], out_f[:n]
