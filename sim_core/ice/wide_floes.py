"""The static index of a floe field's wide floes: which template cells make up each floe
wider than the beam (``TileTemplate.floe``), and where each floe lies in its template.

A wide floe is laid as the paper's pre-fracture cut to the floe (§2.1, intact cells held
together). ``sim_core.ice.compound_floes`` moves its intact cells as one body once a hull
comes near; this index tells it which cells those are and which floes a hull is near.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from sim_core.csr import offsets
from sim_core.fracture.tile_template import TileTemplate
from sim_core.ice.tile_frame import template_box


@dataclass(frozen=True)
class WideFloes:
    """Every template's wide floes, by global floe index f (numbered template by template).

    ``template_floes`` (n_templates + 1,): each template's first floe; ``cells_start``
    (F + 1,) and ``cells`` (C,): each floe's cells as offsets in its template, ascending;
    ``box`` (F, 4): each floe's bounds in its template's frame, [x0, y0, x1, y1] m;
    ``of_cell`` (G,): each global cell's floe, -1 for cells of none.
    """

    template_floes: np.ndarray
    of_cell: np.ndarray
    cells_start: np.ndarray
    cells: np.ndarray
    box: np.ndarray


def compile_wide_floes(templates: tuple[TileTemplate, ...] | list[TileTemplate]) -> WideFloes:
    """Index the wide floes of the templates (``TileTemplate.floes``)."""
    per_template, cells, boxes, of_cell = [], [], [], []
    for t in templates:
        floe = t.floes
        count = int(floe.max(initial=-1)) + 1
        of_cell.append(np.where(floe >= 0, sum(per_template) + floe, -1))
        per_template.append(count)
        order = np.argsort(floe, kind="stable")
        order = order[floe[order] >= 0]
        cells.append(order)
        g = t.geometry
        at = floe[np.repeat(np.arange(t.n_cells), np.diff(g.foot_start))]  # each outline point's floe
        on, x, y = at >= 0, g.footprint[:, 0], g.footprint[:, 1]
        box = np.column_stack([np.full((count, 2), np.inf), np.full((count, 2), -np.inf)])
        for col, reduce, values in ((0, np.minimum, x), (1, np.minimum, y), (2, np.maximum, x), (3, np.maximum, y)):
            reduce.at(box[:, col], at[on], values[on])
        boxes.append(box)
    sizes = np.concatenate([np.bincount(t.floes[t.floes >= 0], minlength=n) for t, n in zip(templates, per_template)]) \
        if templates else np.zeros(0, np.int64)
    return WideFloes(template_floes=offsets(np.array(per_template, dtype=np.int64)),
                     of_cell=np.concatenate(of_cell).astype(np.int64) if of_cell else np.zeros(0, np.int64),
                     cells_start=offsets(sizes.astype(np.int64)),
                     cells=np.concatenate(cells).astype(np.int64) if cells else np.zeros(0, np.int64),
                     box=np.vstack(boxes) if boxes else np.zeros((0, 4)))


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
