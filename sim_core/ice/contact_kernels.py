"""The contact space's numba kernels over arrays: the contacts of a step by floe row
(``Contacts``), the hull's overlap with intact cells by separating axes, the free floes'
poses scattered back to the rows, and a contact on a tile's static body traced to its cell
through a grid of the templates' Voronoi seeds (the cell holding a point has the nearest
seed)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from sim_core.ice.chipmunk_bodies import BOND0, HULL0, HULL_ROW0, INTACT_IN, NOT_A_FLOE, ROW0, TILE0
from sim_core.ice.model import IceModel
from sim_core.ice.tile_frame import template_box, template_point

SEEDS_PER_BUCKET = 4  # mean Voronoi seeds per bucket of a template's seed grid


@dataclass(frozen=True)
class Contacts:
    """Contacts of the last step, one entry per touching pair: rows of bodies a and b
    (``HULL_ROW0 - k`` for the k-th hull, ``NOT_A_FLOE`` for anything else that is not a floe), the impulse on a
    (N s, world), the unit normal from a to b, and the mean contact point (world m)."""

    a: np.ndarray  # (k,) int64
    b: np.ndarray  # (k,) int64
    impulse: np.ndarray  # (k, 2)
    normal: np.ndarray  # (k, 2)
    point: np.ndarray  # (k, 2)

    def with_hull(self, hull: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Contacts with the given hull (by index): the other body's row, the impulse on
        the hull (N s) and the contact point (m); those with the hull as body a first."""
        return hull_contacts(self.a, self.b, self.impulse, self.point, HULL_ROW0 - hull)


@numba.njit(cache=True)
def hull_contacts(a, b, impulse, point, hull_row):
    """``Contacts.with_hull`` of the contacts' rows a, b (k,), impulses on a and points
    (k, 2), for the hull whose contacts have the row hull_row."""
    n = 0
    for k in range(len(a)):
        n += (a[k] == hull_row) + (b[k] == hull_row)
    other, on_hull, at = np.empty(n, np.int64), np.empty((n, 2)), np.empty((n, 2))
    n = 0
    for side in range(2):
        for k in range(len(a)):
            if (a[k] if side == 0 else b[k]) == hull_row:
                sign = 1.0 if side == 0 else -1.0
                other[n] = b[k] if side == 0 else a[k]
                on_hull[n, 0], on_hull[n, 1] = sign * impulse[k, 0], sign * impulse[k, 1]
                at[n, 0], at[n, 1] = point[k, 0], point[k, 1]
                n += 1
    return other, on_hull, at


@numba.njit(cache=True)
def separated(p: np.ndarray, q: np.ndarray) -> bool:
    """True if convex polygons p (n, 2) and q (m, 2) are apart along an edge normal of p."""
    n = p.shape[0]
    for i in range(n):
        nx, ny = p[(i + 1) % n, 1] - p[i, 1], p[i, 0] - p[(i + 1) % n, 0]
        lo_p = hi_p = nx * p[0, 0] + ny * p[0, 1]
        for k in range(1, n):
            d = nx * p[k, 0] + ny * p[k, 1]
            lo_p, hi_p = min(lo_p, d), max(hi_p, d)
        lo_q = hi_q = nx * q[0, 0] + ny * q[0, 1]
        for k in range(1, q.shape[0]):
            d = nx * q[k, 0] + ny * q[k, 1]
            lo_q, hi_q = min(lo_q, d), max(hi_q, d)
        if lo_q > hi_p or hi_q < lo_p:
            return True
    return False


@numba.njit(cache=True)
def hull_overlaps(near, present, status, gcell, xy, yaw, outline, outline_start, extent, hull, hull_xy, hull_c,
                   hull_s, box, template, corner, turns, row_start, row_count, sides, pad, bucket0, per_side, size, first,
                   entries):
    """Rows of intact cells in the space, of the placements ``near``, whose outline
    overlaps the hull polygon (world m). present holds those placements'
    ``TileBodies.in_space`` one after another. Only the cells whose seed lies in a bucket of
    the seed grid (``seed_grid``) that the hull's bounds reach, widened by the template's
    pad (m: the farthest a cell's outline lies from its seed), are looked at; the hull's
    body-frame box [x0, x1, y0, y1] screens them first."""
    out = np.empty(len(present), np.int64)
    n_out = 0
    offset = 0
    x0, x1 = hull[:, 0].min(), hull[:, 0].max()
    y0, y1 = hull[:, 1].min(), hull[:, 1].max()
    for p in near:
        t = template[p]
        n, h = per_side[t], size[t]
        lo_x, lo_y, hi_x, hi_y = template_box(x0, y0, x1, y1, p, template, corner, turns, sides)
        i0, i1 = max(int((lo_x - pad[t]) // h), 0), min(int((hi_x + pad[t]) // h), n - 1)
        j0, j1 = max(int((lo_y - pad[t]) // h), 0), min(int((hi_y + pad[t]) // h), n - 1)
        for bj in range(j0, j1 + 1):
            for bi in range(i0, i1 + 1):
                k = bucket0[t] + bi + n * bj
                for e in range(first[k], first[k + 1]):
                    cell = entries[e]
                    j = row_start[p] + cell
                    if present[offset + cell] & INTACT_IN == 0 or status[j] != 0:
                        continue
                    g = gcell[j]
                    dx, dy = xy[j, 0] - hull_xy[0], xy[j, 1] - hull_xy[1]
                    u, v, r = hull_c * dx + hull_s * dy, -hull_s * dx + hull_c * dy, extent[g]
                    if u < box[0] - r or u > box[1] + r or v < box[2] - r or v > box[3] + r:
                        continue
                    a, b = outline_start[g], outline_start[g + 1]
                    cy, sy = math.cos(yaw[j]), math.sin(yaw[j])
                    ring = np.empty((b - a, 2))
                    for i in range(b - a):
                        ox, oy = outline[a + i, 0], outline[a + i, 1]
                        ring[i, 0] = xy[j, 0] + cy * ox - sy * oy
                        ring[i, 1] = xy[j, 1] + sy * ox + cy * oy
                    if not separated(hull, ring) and not separated(ring, hull):
                        out[n_out] = j
                        n_out += 1
        offset += row_count[p]
    return out[:n_out]


@numba.njit(cache=True)
def scatter_free(ids, f, status, resting, xy, yaw, vel, yaw_rate):
    """Write the pose and velocity rows f (n, 6) of floe bodies with these ids into the
    arrays, but not of rows already frozen (bodies of a tile still leaving the space) or
    resting (their static bodies report no velocity). Returns the rows written and their
    bodies' places in ids."""
    out, at = np.empty(len(ids), np.int64), np.empty(len(ids), np.int64)
    n = 0
    for k in range(len(ids)):
        if ids[k] >= ROW0 and ids[k] < TILE0:
            i = ids[k] - ROW0
            if status[i] != 1 or resting[i]:
                continue
            xy[i, 0], xy[i, 1], yaw[i] = f[k, 0], f[k, 1], f[k, 2]
            vel[i, 0], vel[i, 1], yaw_rate[i] = f[k, 3], f[k, 4], f[k, 5]
            out[n], at[n] = i, k
            n += 1
    return out[:n], at[:n]


def seed_grid(model: IceModel) -> tuple[np.ndarray, ...]:
    """Every template's Voronoi seeds (template frame, m) bucketed in a uniform grid of about
    SEEDS_PER_BUCKET seeds a bucket: per template its first bucket, buckets per side and
    bucket side (m); the buckets' first entries (CSR) and entries (cell offsets in the
    template); and the seeds by global cell (G, 2). A k-d tree would do the search too, but
    it is called from numba, once per contact, with the seeds of broken cells skipped."""
    seeds = model.centroid[:, :2] + model.seed_offset
    first_bucket, per_side, size, counts, entries = [0], [], [], [], []
    for t, (a, b) in enumerate(zip(model.template_start[:-1], model.template_start[1:])):
        side = model.templates[t].side
        n = max(1, int(math.sqrt((b - a) / SEEDS_PER_BUCKET)))
        cell = np.clip((seeds[a:b] / (side / n)).astype(np.int64), 0, n - 1)
        bucket = cell[:, 0] + n * cell[:, 1]
        entries.append(np.argsort(bucket, kind="stable"))
        counts.append(np.bincount(bucket, minlength=n * n))
        first_bucket.append(first_bucket[-1] + n * n)
        per_side.append(n)
        size.append(side / n)
    first = np.concatenate([[0], np.cumsum(np.concatenate(counts))]) if counts else np.zeros(1, np.int64)
    return (np.array(first_bucket[:-1], dtype=np.int64), np.array(per_side, dtype=np.int64),
            np.array(size, dtype=float), first.astype(np.int64),
            np.concatenate(entries).astype(np.int64) if entries else np.zeros(0, np.int64),
            np.ascontiguousarray(seeds), model.template_start.astype(np.int64))


@numba.njit(cache=True)
def nearest_cell(qx, qy, t, row_start, status, bonded, floe_of, floe, bucket0, per_side, size, first, entries, seeds,
                 g0):
    """Row of the cell whose seed is nearest (qx, qy), template t's frame (m), among the
    cells of the tile whose rows start at row_start: its intact cells (floe < 0), or the
    intact cells and those bonded to it of the wide floe ``floe`` (``floe_of``: each global
    cell's floe; ``compound_floes``); -1 if there is none."""
    n, h = per_side[t], size[t]
    bx, by = min(max(int(qx / h), 0), n - 1), min(max(int(qy / h), 0), n - 1)
    best, best_row = np.inf, -1
    for r in range(n):
        if best_row >= 0 and best <= ((r - 1) * h) ** 2:
            break
        for j in range(max(by - r, 0), min(by + r, n - 1) + 1):
            for i in range(max(bx - r, 0), min(bx + r, n - 1) + 1):
                if max(abs(i - bx), abs(j - by)) != r:
                    continue
                k = bucket0[t] + i + n * j
                for e in range(first[k], first[k + 1]):
                    c = entries[e]
                    row = row_start + c
                    if floe < 0 and status[row] != 0:
                        continue
                    if floe >= 0 and (floe_of[g0[t] + c] != floe or status[row] > 1
                                      or (status[row] == 1 and not bonded[row])):
                        continue
                    dx, dy = seeds[g0[t] + c, 0] - qx, seeds[g0[t] + c, 1] - qy
                    d = dx * dx + dy * dy
                    if d < best:
                        best, best_row = d, row
    return best_row


@numba.njit(cache=True)
def contact_rows(ints, f, status, working, template, corner, turns, row_start, sides,
                  bucket0, per_side, size, first, entries, seeds, g0):
    """Rows of both bodies of each arbiter (ints (k, 3): body ids a, b and contact count;
    f (k, 8): impulse, normal, points A1, A2) and the mean contact point (k, 2) m.
    On a tile body the row is the intact cell with the seed nearest the point (the point
    lies on its cell's boundary, the cell across is broken); on a wide floe's body it is
    left NOT_A_FLOE for ``compound_floes.bond_rows``; on a tile no longer worked
    (leaving the space), or on a body that is not a floe, it is NOT_A_FLOE. So are both
    rows of a contact with no points this step: Chipmunk keeps a separated pair's contact a
    few steps, with no impulse, and the pair no longer touches (a floe that has left the
    hull is not struck by it)."""
    k_n = ints.shape[0]
    rows = np.empty((2, k_n), np.int64)
    point = np.empty((k_n, 2))
    for k in range(k_n):
        if ints[k, 2] > 1:
            point[k, 0], point[k, 1] = 0.5 * (f[k, 4] + f[k, 6]), 0.5 * (f[k, 5] + f[k, 7])
        else:
            point[k, 0], point[k, 1] = f[k, 4], f[k, 5]
        if ints[k, 2] == 0:
            rows[0, k] = rows[1, k] = NOT_A_FLOE
            continue
        for side in range(2):
            code = np.int64(ints[k, side])
            if code >= BOND0:  # a wide floe's body: ``compound_floes.bond_rows`` names its row
                rows[side, k] = NOT_A_FLOE
            elif code >= TILE0:
                p = code - TILE0
                row = NOT_A_FLOE
                if p < len(working) and working[p]:
                    qx, qy = template_point(point[k, 0], point[k, 1], p, template, corner, turns, sides)
                    found = nearest_cell(qx, qy, template[p], row_start[p], status, status, g0, -1, bucket0,
                                         per_side, size, first, entries, seeds, g0)  # floe -1: bonded, floe_of unread
                    if found >= 0:
                        row = found
                rows[side, k] = row
            elif code >= ROW0:
                rows[side, k] = code - ROW0
            elif code >= HULL0:
                rows[side, k] = HULL_ROW0 - (code - HULL0)
            else:
                rows[side, k] = NOT_A_FLOE
    return rows[0], rows[1], point


def warm_up() -> None:
    """Load the compiled kernels of this module (numba compiles or loads on first call)."""
    none = np.zeros(0, dtype=np.int64)
    scatter_free(none.astype(np.uintp), np.zeros((0, 6)), none.astype(np.uint8), none.astype(np.bool_),
                  np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2), np.float32), np.zeros(0, np.float32))
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    one = np.zeros(1, dtype=np.int64)
    contact_rows(np.zeros((0, 3), np.uintp), np.zeros((0, 8)), none.astype(np.uint8), none.astype(np.uint8),
                  none, np.zeros((0, 2)), none, none, np.ones(1), one, one + 1, np.ones(1), np.zeros(2, np.int64),
                  none, np.zeros((0, 2)), np.zeros(2, np.int64))
    hull_contacts(none, none, np.zeros((0, 2)), np.zeros((0, 2)), HULL_ROW0)
    hull_overlaps(none, none.astype(np.uint8), none.astype(np.uint8), none.astype(np.int32), np.zeros((0, 2)),
                   np.zeros(0), square, np.array([0, 4]), np.ones(1), square, np.zeros(2), 1.0, 0.0, np.zeros(4),
                   none, np.zeros((0, 2)), none, none, none, np.ones(1), np.ones(1), one, one + 1, np.ones(1),
                   np.zeros(2, np.int64), none)
