"""World points in a placed tile's template frame: the tile's frame (its south-west corner
at the origin), turned back by the quarter turns the tile was laid with about its centre.
Compiled, for the kernels that look up a template's cells from world positions."""
from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def template_point(x, y, p, template, corner, turns, sides):
    """A world point (m) in the frame of placement p's template (its tile's, turned back by
    its quarter turns about the tile's centre)."""
    half = 0.5 * sides[template[p]]
    q = (-turns[p]) % 4
    c, s = (1, 0, -1, 0)[q], (0, 1, 0, -1)[q]
    rx, ry = x - corner[p, 0] - half, y - corner[p, 1] - half
    return c * rx - s * ry + half, s * rx + c * ry + half


@numba.njit(cache=True)
def template_box(x0, y0, x1, y1, p, template, corner, turns, sides):
    """The bounds (x0, y0, x1, y1; m) in placement p's template frame of the world box
    [x0, x1] x [y0, y1] (m)."""
    lo_x = lo_y = np.inf
    hi_x = hi_y = -np.inf
    for wx, wy in ((x0, y0), (x1, y0), (x0, y1), (x1, y1)):
        lx, ly = template_point(wx, wy, p, template, corner, turns, sides)
        lo_x, hi_x, lo_y, hi_y = min(lo_x, lx), max(hi_x, lx), min(lo_y, ly), max(hi_y, ly)
    return lo_x, lo_y, hi_x, hi_y
