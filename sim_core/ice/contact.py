"""Planar contact of hull, intact cells and free floes, on Chipmunk2D (through pymunk).

Chipmunk does the collision detection and the contact impulses; this module keeps its
bodies in step with the floe arrays. It drives Chipmunk through the C API that pymunk
bundles (``pymunk._chipmunk``), not through pymunk's Python classes, for the floes: a pymunk
``Body`` or ``Shape`` is a Python object in a reference cycle with its cffi handle, so
thousands of them cost seconds of creation per tile swap, pauses of a tenth of a second
whenever Python's cyclic collector walks them, and about a kilobyte each. A floe here costs
its C body and shape and two pointers in an array, and a body names its floe directly: its
user data is the floe's code (``_ROW0 + row``, ``_TILE0 + placement`` for a tile's static
body, ``_HULL_ID``), which ``pymunk.batch`` returns as the body id.

All intact cells of a placed tile are shapes of one static body, so the per-step body walk
sees a few tile bodies, not thousands of cells. A contact on a tile body is traced to its
cell by the Voronoi property: the cell holding a point is the one with the nearest seed. A
contact point lies on the loaded cell's boundary, and the neighbour across that boundary is
already broken (that is where the striker came from), so the nearest seed among the tile's
intact cells names the loaded cell; a sphere collider lies inside its cell, so there the
answer is exact. The seeds are searched in a uniform grid of buckets per template, in the
template's frame (``_seed_grid``). Breaking moves a cell's shape from its tile body to a new dynamic body. Colliders
(mesh or sphere) carry the floe-floe contact, but the hull breaks whatever it touches
geometrically: the hull's overlap with intact cells is tested against their true outlines
(separating axes, in numba), not through the engine. The hull is a kinematic body driven
by the ship model. State moves between Chipmunk and the arrays through ``pymunk.batch``
(one C call per step, no Python loop over bodies). Water drag in the plane is Chipmunk's
velocity damping, an exponential decay with the configured time constant, applied in C. A
quadratic drag would need a Python callback per body and step.

A tile enters the space in two parts: ``build_tile`` makes its static body and shapes
(the costly part, a few microseconds per cell, done ahead of need) and ``insert_tile``
adds them to the space (about a microsecond per cell), so crossing the detection radius
only switches a prepared tile in.
"""
from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numba
import numpy as np
import pymunk
import pymunk.batch as pb
from pymunk._chipmunk import ffi, lib

from sim_core.ice.floes import FloeState, FloeStatus, TilePlacement
from sim_core.ice.model import IceModel, placed_centroids, placed_outlines

HULL_ROW = -1
_NOT_A_FLOE = -2  # bodies that are not floes (the space's own static body)
_TILE_CODE = -3  # a contact on tile t's static body is coded _TILE_CODE - t
_HULL_ID, _ROW0, _TILE0 = 1, 2, 1 << 40  # body user data: the hull, floe rows, tile bodies
_HULL_BIT, _FLOE_BIT = 1, 2
_INTACT_IN, _FLOE_IN = 1, 2  # TileBodies.in_space flags
_HULL = (0, _HULL_BIT, _FLOE_BIT)  # Chipmunk shape filters: (group, categories, mask)
_FLOE = (0, _FLOE_BIT, _HULL_BIT | _FLOE_BIT)
_NO_CONTACT = (0, 0, 0)  # floes under the hull, and floes shedding their contacts before they rest
_IDENTITY = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)  # cpTransform
_SEEDS_PER_BUCKET = 4  # mean Voronoi seeds per bucket of a template's seed grid
_ROW_BY_ROW = 16  # fewer rows than this have their engine objects looked up one by one
_BODY_FIELDS = (pb.BodyFields.BODY_ID | pb.BodyFields.POSITION | pb.BodyFields.ANGLE
                | pb.BodyFields.VELOCITY | pb.BodyFields.ANGULAR_VELOCITY)
_ARB_FIELDS = (pb.ArbiterFields.BODY_A_ID | pb.ArbiterFields.BODY_B_ID | pb.ArbiterFields.TOTAL_IMPULSE
               | pb.ArbiterFields.NORMAL | pb.ArbiterFields.CONTACT_COUNT | pb.ArbiterFields.POINT_A_1
               | pb.ArbiterFields.POINT_A_2)  # a contact's points on body a only: its mean point is all we use


@dataclass(frozen=True)
class Contacts:
    """Contacts of the last step, one entry per touching pair: rows of bodies a and b
    (``HULL_ROW`` for the hull, negative for anything that is not a floe), the impulse on a
    (N s, world), the unit normal from a to b, and the mean contact point (world m)."""

    a: np.ndarray  # (k,) int64
    b: np.ndarray  # (k,) int64
    impulse: np.ndarray  # (k, 2)
    normal: np.ndarray  # (k, 2)
    point: np.ndarray  # (k, 2)

    def with_hull(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Contacts with the hull: the other body's row, the impulse on the hull (N s) and
        the contact point (m); those with the hull as body a first."""
        return _with_hull(self.a, self.b, self.impulse, self.point)


@numba.njit(cache=True)
def _with_hull(a, b, impulse, point):
    """``Contacts.with_hull`` of the contacts' rows a, b (k,), impulses on a and points (k, 2)."""
    n = 0
    for k in range(len(a)):
        n += (a[k] == HULL_ROW) + (b[k] == HULL_ROW)
    other, on_hull, at = np.empty(n, np.int64), np.empty((n, 2)), np.empty((n, 2))
    n = 0
    for side in range(2):
        for k in range(len(a)):
            if (a[k] if side == 0 else b[k]) == HULL_ROW:
                sign = 1.0 if side == 0 else -1.0
                other[n] = b[k] if side == 0 else a[k]
                on_hull[n, 0], on_hull[n, 1] = sign * impulse[k, 0], sign * impulse[k, 1]
                at[n, 0], at[n, 1] = point[k, 0], point[k, 1]
                n += 1
    return other, on_hull, at


def _ptr(cdata) -> int:
    return int(ffi.cast("uintptr_t", cdata))


def _shape(ptr: int):
    return ffi.cast("cpShape *", ptr)


def _body(ptr: int):
    return ffi.cast("cpBody *", ptr)


def _new_shape(body, ring: list, radius: float, centre: tuple[float, float], sphere: bool, friction: float) -> int:
    """A floe collider on a C body: a circle of radius about centre, or the convex polygon
    ring [(x, y), ...], both in the body's frame (m)."""
    if sphere:
        shape = lib.cpCircleShapeNew(body, radius, centre)
    else:
        shape = lib.cpPolyShapeNew(body, len(ring), ffi.new("cpVect[]", ring), _IDENTITY, 0.0)
    lib.cpShapeSetFriction(shape, friction)
    lib.cpShapeSetFilter(shape, _FLOE)
    return _ptr(shape)


class TileBodies:
    """Engine objects of one placed tile, by row offset in the tile (0 = none): the static
    body holding its intact cells, their shapes, and its free floes' bodies and shapes;
    which of them are in the space; and the offsets still to switch in or out."""

    def __init__(self, count: int) -> None:
        self.body = _ptr(lib.cpBodyNewStatic())
        self.intact = np.zeros(count, dtype=np.uintp)
        self.floe_body = np.zeros(count, dtype=np.uintp)
        self.floe_shape = np.zeros(count, dtype=np.uintp)
        self.in_space = np.zeros(count, dtype=np.uint8)  # _INTACT_IN | _FLOE_IN
        self.queue = np.zeros(0, dtype=np.int64)  # offsets to switch in (entering) or out (leaving)

    def insert(self, space, offsets: np.ndarray) -> int:
        """Add the built objects at offsets to the space; returns how many went in."""
        flags = self.in_space[offsets]
        cells = offsets[(self.intact[offsets] != 0) & (flags & _INTACT_IN == 0)]
        floes = offsets[(self.floe_body[offsets] != 0) & (flags & _FLOE_IN == 0)]
        add_shape, add_body, cast = lib.cpSpaceAddShape, lib.cpSpaceAddBody, ffi.cast
        for p in self.intact[cells].tolist():
            add_shape(space, cast("cpShape *", p))
        for b, p in zip(self.floe_body[floes].tolist(), self.floe_shape[floes].tolist()):
            add_body(space, cast("cpBody *", b))
            add_shape(space, cast("cpShape *", p))
        self.in_space[cells] |= _INTACT_IN
        self.in_space[floes] |= _FLOE_IN
        return len(cells) + 2 * len(floes)

    def remove(self, space, offsets: np.ndarray) -> int:
        """Take the objects at offsets out of the space and free them; returns how many."""
        flags = self.in_space[offsets]
        cast = ffi.cast
        cells = offsets[self.intact[offsets] != 0]
        for p, inside in zip(self.intact[cells].tolist(), (flags[self.intact[offsets] != 0] & _INTACT_IN).tolist()):
            shape = cast("cpShape *", p)
            if inside:
                lib.cpSpaceRemoveShape(space, shape)
            lib.cpShapeFree(shape)
        has_floe = self.floe_body[offsets] != 0
        floes = offsets[has_floe]
        for b, p, inside in zip(self.floe_body[floes].tolist(), self.floe_shape[floes].tolist(),
                                (flags[has_floe] & _FLOE_IN).tolist()):
            body, shape = cast("cpBody *", b), cast("cpShape *", p)
            if inside:
                lib.cpSpaceRemoveShape(space, shape)
                if lib.cpBodyGetSpace(body) != ffi.NULL:  # a resting floe's body is not (``rest``)
                    lib.cpSpaceRemoveBody(space, body)
            lib.cpShapeFree(shape)
            lib.cpBodyFree(body)
        self.intact[offsets] = self.floe_body[offsets] = self.floe_shape[offsets] = 0
        self.in_space[offsets] = 0
        return len(cells) + 2 * len(floes)

    def built(self) -> np.ndarray:
        """Offsets holding any object."""
        return np.nonzero((self.intact != 0) | (self.floe_body != 0))[0]

    def release(self, space) -> None:
        """Take everything out of the space and free it, the static body last."""
        self.remove(space, self.built())
        body = _body(self.body)
        if lib.cpBodyGetSpace(body) != ffi.NULL:
            lib.cpSpaceRemoveBody(space, body)
        lib.cpBodyFree(body)
        self.body = 0


def _free_all(space: pymunk.Space, tiles: dict, leaving: list, hull: tuple[int, int]) -> None:
    """Free every C object the contact space made, before the space itself goes."""
    for bodies in [*tiles.values(), *(b for _, b in leaving)]:
        bodies.release(space._space)
    hull_body, hull_shape = _body(hull[0]), _shape(hull[1])
    lib.cpSpaceRemoveShape(space._space, hull_shape)
    lib.cpSpaceRemoveBody(space._space, hull_body)
    lib.cpShapeFree(hull_shape)
    lib.cpBodyFree(hull_body)


@numba.njit(cache=True)
def _separated(p: np.ndarray, q: np.ndarray) -> bool:
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
def _hull_overlaps(near, present, status, gcell, xy, yaw, outline, outline_start, extent, hull, hull_xy, hull_c,
                   hull_s, box, template, corner, turns, row_start, row_count, sides, pad, bucket0, per_side, size, first,
                   entries):
    """Rows of intact cells in the space, of the placements ``near``, whose outline
    overlaps the hull polygon (world m). present holds those placements'
    ``TileBodies.in_space`` one after another. Only the cells whose seed lies in a bucket of
    the seed grid (``_seed_grid``) that the hull's bounds reach, widened by the template's
    pad (m: the farthest a cell's outline lies from its seed), are looked at; the hull's
    body-frame box [x0, x1, y0, y1] screens them first."""
    out = np.empty(len(present), np.int64)
    n_out = 0
    offset = 0
    x0, x1 = hull[:, 0].min(), hull[:, 0].max()
    y0, y1 = hull[:, 1].min(), hull[:, 1].max()
    for p in near:
        t = template[p]
        half, n, h = 0.5 * sides[t], per_side[t], size[t]
        q = (-turns[p]) % 4  # world to template frame, as in _contact_rows
        c, s = (1, 0, -1, 0)[q], (0, 1, 0, -1)[q]
        lo_x = lo_y = np.inf
        hi_x = hi_y = -np.inf
        for wx, wy in ((x0, y0), (x1, y0), (x0, y1), (x1, y1)):
            rx, ry = wx - corner[p, 0] - half, wy - corner[p, 1] - half
            lx, ly = c * rx - s * ry + half, s * rx + c * ry + half
            lo_x, hi_x, lo_y, hi_y = min(lo_x, lx), max(hi_x, lx), min(lo_y, ly), max(hi_y, ly)
        i0, i1 = max(int((lo_x - pad[t]) // h), 0), min(int((hi_x + pad[t]) // h), n - 1)
        j0, j1 = max(int((lo_y - pad[t]) // h), 0), min(int((hi_y + pad[t]) // h), n - 1)
        for bj in range(j0, j1 + 1):
            for bi in range(i0, i1 + 1):
                k = bucket0[t] + bi + n * bj
                for e in range(first[k], first[k + 1]):
                    cell = entries[e]
                    j = row_start[p] + cell
                    if present[offset + cell] & _INTACT_IN == 0 or status[j] != 0:
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
                    if not _separated(hull, ring) and not _separated(ring, hull):
                        out[n_out] = j
                        n_out += 1
        offset += row_count[p]
    return out[:n_out]


@numba.njit(cache=True)
def _scatter_free(ids, f, status, resting, xy, yaw, vel, yaw_rate):
    """Write the pose and velocity rows f (n, 6) of floe bodies with these ids into the
    arrays, but not of rows already frozen (bodies of a tile still leaving the space) or
    resting (their static bodies report no velocity). Returns the rows written and their
    bodies' places in ids."""
    out, at = np.empty(len(ids), np.int64), np.empty(len(ids), np.int64)
    n = 0
    for k in range(len(ids)):
        if ids[k] >= _ROW0 and ids[k] < _TILE0:
            i = ids[k] - _ROW0
            if status[i] != 1 or resting[i]:
                continue
            xy[i, 0], xy[i, 1], yaw[i] = f[k, 0], f[k, 1], f[k, 2]
            vel[i, 0], vel[i, 1], yaw_rate[i] = f[k, 3], f[k, 4], f[k, 5]
            out[n], at[n] = i, k
            n += 1
    return out[:n], at[:n]


def _seed_grid(model: IceModel) -> tuple[np.ndarray, ...]:
    """Every template's Voronoi seeds (template frame, m) bucketed in a uniform grid of about
    _SEEDS_PER_BUCKET seeds a bucket: per template its first bucket, buckets per side and
    bucket side (m); the buckets' first entries (CSR) and entries (cell offsets in the
    template); and the seeds by global cell (G, 2). A k-d tree would do the search too, but
    it is called from numba, once per contact, with the seeds of broken cells skipped."""
    seeds = model.centroid[:, :2] + model.seed_offset
    first_bucket, per_side, size, counts, entries = [0], [], [], [], []
    for t, (a, b) in enumerate(zip(model.template_start[:-1], model.template_start[1:])):
        side = model.templates[t].side
        n = max(1, int(math.sqrt((b - a) / _SEEDS_PER_BUCKET)))
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
def _nearest_intact(qx, qy, t, row_start, status, bucket0, per_side, size, first, entries, seeds, g0):
    """Row of the intact cell whose seed is nearest (qx, qy), template t's frame (m), among
    the cells of the tile whose rows start at row_start; -1 if none is intact."""
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
                    if status[row] != 0:
                        continue
                    dx, dy = seeds[g0[t] + c, 0] - qx, seeds[g0[t] + c, 1] - qy
                    d = dx * dx + dy * dy
                    if d < best:
                        best, best_row = d, row
    return best_row


@numba.njit(cache=True)
def _contact_rows(ints, f, status, working, template, corner, turns, row_start, sides,
                  bucket0, per_side, size, first, entries, seeds, g0):
    """Rows of both bodies of each arbiter (ints (k, 3): body ids a, b and contact count;
    f (k, 8): impulse, normal, points A1, A2) and the mean contact point (k, 2) m.
    On a tile body the row is the intact cell with the seed nearest the point (the point
    lies on its cell's boundary, the cell across is broken); on a tile no longer worked
    (leaving the space), or on a body that is not a floe, it is _NOT_A_FLOE. So are both
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
            rows[0, k] = rows[1, k] = _NOT_A_FLOE
            continue
        for side in range(2):
            code = np.int64(ints[k, side])
            if code >= _TILE0:
                p = code - _TILE0
                row = _NOT_A_FLOE
                if p < len(working) and working[p]:
                    t = template[p]
                    half = 0.5 * sides[t]
                    q = (-turns[p]) % 4
                    c, s = (1, 0, -1, 0)[q], (0, 1, 0, -1)[q]
                    rx, ry = point[k, 0] - corner[p, 0] - half, point[k, 1] - corner[p, 1] - half
                    found = _nearest_intact(c * rx - s * ry + half, s * rx + c * ry + half, t, row_start[p],
                                            status, bucket0, per_side, size, first, entries, seeds, g0)
                    if found >= 0:
                        row = found
                rows[side, k] = row
            elif code >= _ROW0:
                rows[side, k] = code - _ROW0
            elif code == _HULL_ID:
                rows[side, k] = HULL_ROW
            else:
                rows[side, k] = _NOT_A_FLOE
    return rows[0], rows[1], point


def warm_up() -> None:
    """Load the compiled kernels of this module (numba compiles or loads on first call)."""
    none = np.zeros(0, dtype=np.int64)
    _scatter_free(none.astype(np.uintp), np.zeros((0, 6)), none.astype(np.uint8), none.astype(np.bool_),
                  np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2), np.float32), np.zeros(0, np.float32))
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    one = np.zeros(1, dtype=np.int64)
    _contact_rows(np.zeros((0, 3), np.uintp), np.zeros((0, 8)), none.astype(np.uint8), none.astype(np.uint8),
                  none, np.zeros((0, 2)), none, none, np.ones(1), one, one + 1, np.ones(1), np.zeros(2, np.int64),
                  none, np.zeros((0, 2)), np.zeros(2, np.int64))
    _with_hull(none, none, np.zeros((0, 2)), np.zeros((0, 2)))
    _hull_overlaps(none, none.astype(np.uint8), none.astype(np.uint8), none.astype(np.int32), np.zeros((0, 2)),
                   np.zeros(0), square, np.array([0, 4]), np.ones(1), square, np.zeros(2), 1.0, 0.0, np.zeros(4),
                   none, np.zeros((0, 2)), none, none, none, np.ones(1), np.ones(1), one, one + 1, np.ones(1),
                   np.zeros(2, np.int64), none)


class ContactSpace:
    """Chipmunk space holding the hull and the floes of breakable tiles."""

    def __init__(self, model: IceModel, tiles: TilePlacement, hull_outline: np.ndarray,
                 hull_friction: float) -> None:
        s = model.settings
        self.model, self.tiles = model, tiles
        self.space = pymunk.Space()
        self._cp = self.space._space  # the C space, for the C API calls below
        self.space.iterations = s.solver_iterations
        self.space.collision_slop = s.collision_slop
        # Chipmunk's sleeping stays off. Through the C API it no longer hung (the pymunk-object
        # design once hung in cpSpaceStep after a few thousand mesh-collider steps; three mesh
        # runs and two 1500 m transits with sleeping on ran through here), and it halved the
        # median step of the default transit. But it sleeps and wakes whole touching groups,
        # and the packed channel astern is one group of thousands: one touch, or the removal
        # of one frozen floe, woke them all, in steps of 0.1-1.1 s. Putting single floes to
        # sleep (cpBodySleep) breaks its rule that touching bodies sleep together, and freed
        # its contact memory twice. Floes at rest leave the dynamic set one by one instead, as
        # static bodies (``rest``, ``wake``; sim_core/ice/resting.py decides when).
        self.space.damping = math.exp(-1.0 / s.drag_time_s)  # per second: v *= damping ** dt
        self._water = (0.0, 0.0, 0.0)  # the water's velocity (m/s) and the step (s) the gravity was set for
        hull = lib.cpBodyNewKinematic()
        lib.cpBodySetUserData(hull, ffi.cast("void *", _HULL_ID))
        ring = [tuple(p) for p in np.asarray(hull_outline, dtype=float).tolist()]
        hull_shape = lib.cpPolyShapeNew(hull, len(ring), ffi.new("cpVect[]", ring), _IDENTITY, 0.0)
        lib.cpShapeSetFriction(hull_shape, hull_friction)
        lib.cpShapeSetFilter(hull_shape, _HULL)
        lib.cpSpaceAddBody(self._cp, hull)
        lib.cpSpaceAddShape(self._cp, hull_shape)
        self._hull = hull
        # the outline as Chipmunk keeps it: convex, counter-clockwise, body frame (y to port)
        verts = [lib.cpPolyShapeGetVert(hull_shape, i) for i in range(lib.cpPolyShapeGetCount(hull_shape))]
        self.hull_outline = np.array([(v.x, v.y) for v in verts])
        self.hull_half_beam = float(np.abs(self.hull_outline[:, 1]).max())
        self.hull_stem = float(self.hull_outline[:, 0].max())  # m forward of the reference point
        self._hull_box = np.array([self.hull_outline[:, 0].min(), self.hull_outline[:, 0].max(),
                                   self.hull_outline[:, 1].min(), self.hull_outline[:, 1].max()])
        self._hull_pose = (np.zeros(2), 0.0)
        self._tiles: dict[int, TileBodies] = {}  # placement -> its engine objects
        self._tile_index: tuple | None = None  # _in_space's arrays, until _tiles or the placements change
        self._entering: list[TileBodies] = []  # switched in, objects still going into the space
        self._leaving: list[tuple[int, TileBodies]] = []  # switched out, objects still to take out
        self._insert_budget, self._removal_work = s.swap_objects_per_step, s.swap_removal_work
        self._arbiters = 0  # contacts Chipmunk kept at the last read
        self._moving_at = np.zeros(0, dtype=np.int64)  # the moving floes' places among the bodies, last read
        # floes shedding their contacts before they rest: (the engine's time stamp from which
        # they may, their rows, the rows' placements and bodies, and those placements' engine
        # objects), oldest first (``rest``, ``settle``)
        self._shedding: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, dict[int, TileBodies]]] = []
        d = np.hypot(model.outline[:, 0], model.outline[:, 1])
        self.extent = np.maximum.reduceat(d, model.outline_start[:-1]) if len(d) else np.zeros(0)  # cell radius, m
        # farthest a point of the hull and of a cell it touches can be from the hull's reference point, m
        self.reach = float(np.hypot(*np.abs(self.hull_outline).max(axis=0))) + float(self.extent.max(initial=0.0))
        self._grid = _seed_grid(model)
        # per template, the farthest a cell's outline lies from its Voronoi seed, m
        spread = np.hypot(*model.seed_offset.T) + self.extent if len(self.extent) else np.zeros(0)
        self._pad = np.array([spread[a:b].max(initial=0.0) for a, b in zip(model.template_start[:-1],
                                                                           model.template_start[1:])])
        self._sides = np.array([t.side for t in model.templates], dtype=float)
        self._buffer = pb.Buffer()
        weakref.finalize(self, _free_all, self.space, self._tiles, self._leaving, (_ptr(hull), _ptr(hull_shape)))

    # -- building -------------------------------------------------------------------------
    def build_cells(self, bodies: TileBodies, template: int, corner: tuple[float, float] | np.ndarray,
                    quarter_turns: int, cells: np.ndarray) -> None:
        """Make, outside the space, the intact-cell shapes of cells (offsets in the template)
        of a template laid at corner (m) turned by quarter turns, on the tile's static
        body; ``insert_tile`` switches them in."""
        m = self.model
        g = int(m.template_start[template]) + cells
        home, yaw = placed_centroids(m, template, corner, quarter_turns)
        home = home[cells]
        body = _body(bodies.body)
        rings = self._rings(g, home, np.full(len(cells), yaw))
        friction = m.settings.ice_friction
        for j, gi, centre, ring, sphere in zip(cells.tolist(), g.tolist(), home.tolist(), rings,
                                               m.is_sphere[g].tolist()):
            bodies.intact[j] = _new_shape(body, ring, float(m.radius[gi]), tuple(centre), sphere, friction)

    def build_floes(self, bodies: TileBodies, offsets: np.ndarray, gcell: np.ndarray, xy: np.ndarray,
                    yaw: np.ndarray, vel: np.ndarray, yaw_rate: np.ndarray) -> None:
        """Make, outside the space, dynamic bodies for a tile's cells at offsets, of global
        cells gcell (n,), at poses xy (n, 2) m and yaw (n,) rad, with velocities vel (n, 2)
        m/s and yaw_rate (n,) rad/s; ``name_floes`` gives them their rows, ``insert_tile``
        or ``TileBodies.insert`` switch them in."""
        m = self.model
        rings = self._rings(gcell, np.zeros((len(gcell), 2)), np.zeros(len(gcell)))
        friction = m.settings.ice_friction
        for j, gi, ring, sphere, at, angle, v, w in zip(offsets.tolist(), gcell.tolist(), rings,
                                                         m.is_sphere[gcell].tolist(), xy.tolist(), yaw.tolist(),
                                                         vel.tolist(), yaw_rate.tolist()):
            body = lib.cpBodyNew(float(m.mass[gi]), float(m.inertia[gi, 2]))
            lib.cpBodySetPosition(body, (at[0], at[1]))
            lib.cpBodySetAngle(body, angle)
            lib.cpBodySetVelocity(body, (v[0], v[1]))
            lib.cpBodySetAngularVelocity(body, w)
            bodies.floe_body[j] = _ptr(body)
            bodies.floe_shape[j] = _new_shape(body, ring, float(m.radius[gi]), (0.0, 0.0), sphere, friction)

    @staticmethod
    def name_floes(bodies: TileBodies, offsets: np.ndarray, rows: np.ndarray) -> None:
        """Give the floe bodies at offsets their rows (a body names its floe's row)."""
        for j, row in zip(offsets.tolist(), rows.tolist()):
            lib.cpBodySetUserData(_body(int(bodies.floe_body[j])), ffi.cast("void *", _ROW0 + row))

    def insert_tile(self, bodies: TileBodies, placement: int) -> None:
        """Switch a built tile into the space as placement: its static body now, its intact
        shapes and floe bodies over the coming steps (``swap_objects_per_step`` a step, so
        no step pays for a whole tile; the hull cannot reach a tile's cells within the few
        steps that takes, since R_T keeps it at least a third of a tile away)."""
        for k, leaving in enumerate(self._leaving):
            if leaving[0] == placement:  # thawed before its freeze had finished: finish that first
                del self._leaving[k]
                leaving[1].release(self._cp)
                break
        lib.cpBodySetUserData(_body(bodies.body), ffi.cast("void *", _TILE0 + placement))
        lib.cpSpaceAddBody(self._cp, _body(bodies.body))
        bodies.queue = bodies.built()
        self._tiles[placement] = bodies
        self._tile_index = None
        self._entering.append(bodies)

    def drop_tile(self, placement: int) -> None:
        """Switch a tile out: it leaves the tiles the space works with now, and its objects
        leave the space over the coming steps. Its floes are frozen in the arrays meanwhile
        (``read_free`` does not copy FROZEN rows)."""
        bodies = self._tiles.pop(placement)
        self._tile_index = None
        if bodies in self._entering:
            self._entering.remove(bodies)
        bodies.queue = bodies.built()
        self._leaving.append((placement, bodies))

    def _swap_work(self) -> None:
        """Switch the step's share of objects of entering tiles in, and of leaving tiles out.
        Adding costs about a microsecond an object; removing one costs Chipmunk a walk over
        every cached contact (cpSpaceFilterArbiters), so removals are budgeted by that work.
        Both shares are counts, not wall times, so that reruns stay the same."""
        budget = self._insert_budget
        while budget > 0 and self._entering:
            bodies = self._entering[0]
            cells = max(1, budget // 2)  # a thawed floe is two objects: body and shape
            chunk, bodies.queue = bodies.queue[:cells], bodies.queue[cells:]
            budget -= max(bodies.insert(self._cp, chunk), 1)
            if not len(bodies.queue):
                self._entering.pop(0)
        budget = min(self._insert_budget, max(8, self._removal_work // max(self._arbiters, 1)))
        while budget > 0 and self._leaving:
            _, bodies = self._leaving[0]
            cells = max(1, budget // 3)  # a broken cell is up to three objects: shape, body, shape
            chunk, bodies.queue = bodies.queue[:cells], bodies.queue[cells:]
            budget -= max(bodies.remove(self._cp, chunk), 1)
            if not len(bodies.queue):
                self._leaving.pop(0)[1].release(self._cp)

    def switch_in_now(self) -> None:
        """Put every entering tile's objects into the space now, whatever the per-step
        budget: in the order the steps would have, without their engine steps between (a
        benchmark of a field already in the space)."""
        for bodies in self._entering:
            bodies.insert(self._cp, bodies.queue)
            bodies.queue = bodies.queue[:0]
        self._entering.clear()

    @property
    def swaps_pending(self) -> int:
        """Tiles still switching in or out."""
        return len(self._entering) + len(self._leaving)

    def _rings(self, g: np.ndarray, at: np.ndarray, angle: np.ndarray) -> list[list]:
        """Outlines of cells g placed at (at, angle), as lists of (x, y) for Chipmunk."""
        pts, counts = placed_outlines(self.model, g, at, angle)
        pts, ends = pts.tolist(), np.cumsum(counts).tolist()
        return [pts[a:b] for a, b in zip([0] + ends[:-1], ends)]

    def free(self, state: FloeState, rows: np.ndarray) -> None:
        """Intact rows leave their tile body, each for a dynamic body of its own, now."""
        for tile in np.unique(state.tile[rows]).tolist():
            bodies, start = self._tiles[tile], int(self.tiles.row_start[tile])
            mine = rows[state.tile[rows] == tile]
            j = mine - start
            bodies.remove(self._cp, j)
            self.build_floes(bodies, j, state.gcell[mine], state.xy[mine], state.yaw[mine], state.vel[mine],
                             state.yaw_rate[mine])
            self.name_floes(bodies, j, mine)
            bodies.insert(self._cp, j)

    def remove(self, state: FloeState, rows: np.ndarray) -> None:
        """Take intact or free rows of tiles in the space out of it, now, and free their
        engine objects."""
        for tile in np.unique(state.tile[rows]).tolist():
            bodies, start = self._tiles[tile], int(self.tiles.row_start[tile])
            bodies.remove(self._cp, rows[state.tile[rows] == tile] - start)

    def discard(self, bodies: TileBodies) -> None:
        """Free a built tile that was never switched in."""
        bodies.release(self._cp)

    def is_leaving(self, placement: int) -> bool:
        """Whether objects of the placement's last switch-out are still in the space."""
        return any(k == placement for k, _ in self._leaving)

    def has_tile(self, placement: int) -> bool:
        """Whether the placement's bodies are in the space."""
        return placement in self._tiles

    def _floe_objects(self, state: FloeState, rows: np.ndarray, kind: str) -> np.ndarray:
        """The engine objects (``"floe_body"`` or ``"floe_shape"``; C pointers, uintp) of
        free rows (n,) in the space: row by row for a few (most steps' floes going under,
        surfacing or waking), tile by tile for more (floes going to rest); the two cost the
        same at about 16 rows (2 us for one row, 13 us for 200 tile by tile)."""
        if len(rows) < _ROW_BY_ROW:
            start = self.tiles.row_start
            return np.array([getattr(self._tiles[t], kind)[i - start[t]] for i, t in
                             zip(rows.tolist(), state.tile[rows].tolist())], dtype=np.uintp)
        tiles = state.tile[rows]
        local = rows - self.tiles.row_start[tiles]
        out = np.empty(len(rows), dtype=np.uintp)
        for t in np.unique(tiles).tolist():
            at = tiles == t
            out[at] = getattr(self._tiles[t], kind)[local[at]]
        return out

    def _floe_shapes(self, state: FloeState, rows: np.ndarray) -> list[int]:
        return self._floe_objects(state, rows, "floe_shape").tolist()

    def _floe_bodies(self, state: FloeState, rows: np.ndarray) -> list[int]:
        return self._floe_objects(state, rows, "floe_body").tolist()

    def set_submerged(self, state: FloeState, rows: np.ndarray, submerged: bool) -> None:
        """Take free rows out of (or back into) all planar contact: floes under the hull. A
        floe going under is pinned by the hull and loses its planar velocity."""
        f = _NO_CONTACT if submerged else _FLOE
        for p in self._floe_shapes(state, rows):
            lib.cpShapeSetFilter(_shape(p), f)
        if submerged:
            self.set_velocity(state, rows, np.zeros((len(rows), 2)), np.zeros(len(rows)))

    def set_velocity(self, state: FloeState, rows: np.ndarray, velocity: np.ndarray, yaw_rate: np.ndarray) -> None:
        """Give free rows a planar velocity (n, 2) m/s and yaw rate (n,) rad/s."""
        for p, v, w in zip(self._floe_bodies(state, rows), velocity.tolist(), yaw_rate.tolist()):
            lib.cpBodySetVelocity(_body(p), (v[0], v[1]))
            lib.cpBodySetAngularVelocity(_body(p), w)

    # -- per step -------------------------------------------------------------------------
    def set_hull(self, xy: np.ndarray, angle: float, velocity: np.ndarray, angular_velocity: float) -> None:
        """Pose (world m, rad CCW) and velocity of the kinematic hull for the coming step."""
        lib.cpBodySetPosition(self._hull, (float(xy[0]), float(xy[1])))
        lib.cpBodySetAngle(self._hull, float(angle))
        lib.cpBodySetVelocity(self._hull, (float(velocity[0]), float(velocity[1])))
        lib.cpBodySetAngularVelocity(self._hull, float(angular_velocity))
        lib.cpSpaceReindexShapesForBody(self._cp, self._hull)
        self._hull_pose = (np.array([float(xy[0]), float(xy[1])]), float(angle))

    def _in_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The placements in the space (k,), their south-west and north-east corners (k, 2;
        m) and a flag per placement (tiles.n,) set for those in the space; made again only
        when the tiles in the space or the placements change."""
        if self._tile_index is None or len(self._tile_index[3]) != self.tiles.n:
            ids = np.fromiter(self._tiles, dtype=np.int64, count=len(self._tiles))
            lo = self.tiles.corner[ids]
            working = np.zeros(self.tiles.n, dtype=np.uint8)
            working[ids] = 1
            self._tile_index = (ids, lo, lo + self._sides[self.tiles.template[ids]][:, None], working)
        return self._tile_index

    def hull_touching(self, state: FloeState) -> np.ndarray:
        """Rows of intact cells in the space whose true outline the hull overlaps now
        (kinematic-static pairs make no contacts in Chipmunk, and sphere colliders are not
        the cells' outlines)."""
        m = self.model
        xy, angle = self._hull_pose
        c, s = math.cos(angle), math.sin(angle)
        hull = self.hull_outline @ np.array([[c, s], [-s, c]]) + xy
        tiles, lo, hi, _ = self._in_space()
        near = tiles[np.all((lo <= hull.max(axis=0)) & (hi >= hull.min(axis=0)), axis=1)]  # a tile's cells lie in it
        if not len(near):
            return np.zeros(0, dtype=np.int64)
        tl = self.tiles
        found = _hull_overlaps(near, np.concatenate([self._tiles[k].in_space for k in near.tolist()]), state.status,
                               state.gcell, state.xy, state.yaw, m.outline, m.outline_start, self.extent, hull, xy,
                               c, s, self._hull_box, tl.template, tl.corner, tl.quarter_turns, tl.row_start,
                               tl.row_count, self._sides, self._pad, *self._grid[:5])
        return np.sort(found)

    def set_water_velocity(self, east: float, north: float, dt: float) -> None:
        """Let the water move at (``east``, ``north``) m/s (world x, y) over the next step
        of dt (s): the floes' planar drag then pulls them towards it rather than to rest.
        Chipmunk's damping decays a body's velocity to zero (v <- v d + g dt, d = damping ** dt);
        a uniform acceleration g = v_w (1 - d) / dt, given as the space's gravity (which
        acts on the moving floes only, not on the kinematic hull or floes at rest), makes
        v_w the steady state: the same linear drag, relative to the water."""
        if (east, north, dt) == self._water:  # most steps: as the last one
            return
        self._water = (east, north, dt)
        share = (1.0 - self.space.damping ** dt) / dt
        self.space.gravity = (east * share, north * share)

    def step(self, dt: float) -> None:
        """Switch the step's share of tile objects in or out, then step the engine by dt (s)."""
        self._swap_work()
        self.engine_step(dt)

    def engine_step(self, dt: float) -> None:
        """The bare engine step of dt (s), ``cpSpaceStep``. Called through the C API: the
        floes are no pymunk objects, so pymunk's ``Space.step`` would only add its
        bookkeeping of them."""
        lib.cpSpaceStep(self._cp, dt)

    def read_free(self, state: FloeState) -> np.ndarray:
        """Copy pose and velocity of the moving free floes (not resting) from Chipmunk into
        the arrays; returns their rows, in the order of the space's dynamic bodies."""
        buf = self._buffer
        buf.clear()
        pb.get_space_bodies(self.space, _BODY_FIELDS, buf)  # the dynamic bodies first, in the space's order
        ids = np.frombuffer(buf.int_buf(), dtype=np.uintp)
        moving, self._moving_at = _scatter_free(
            ids, np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ids), 6), state.status, state.resting,
            state.xy, state.yaw, state.vel, state.yaw_rate)
        return moving

    def rest_share(self, picks: np.ndarray) -> int:
        """How many of the moving floes at these places (ascending) in the last
        ``read_free`` a step may start taking out of the dynamic set. Each, as it settles,
        costs Chipmunk a search of its dynamic bodies from the first up to its own, so the
        searches are counted (not timed) against the same work budget as tile removals; at
        least one is taken. (Moving its shape into the static tree, which looks up the
        moving floes it overlaps, costs more, and grows with the moving floes as the engine
        step does: 16 us a floe with 8800 moving, 5 us with 3200, on 2 cores; the count
        ``rest_per_step`` bounds that.)"""
        return max(1, int(np.searchsorted(np.cumsum(self._moving_at[picks]), self._removal_work, side="right")))

    def rest(self, state: FloeState, rows: np.ndarray) -> None:
        """Start taking free rows out of the dynamic set (no solver work; moving floes
        still collide with them): for the engine's contact persistence (steps) their shapes
        collide with nothing, so that Chipmunk drops their contacts in its own steps, as it
        drops every contact not renewed; then ``settle`` makes their bodies static. Chipmunk
        keeps contacts between two static bodies for good, and lists them every step;
        dropping a shape's contacts by taking it out of the space and back costs a walk over
        every contact the space holds, for each shape (30 us a floe at 10 000 floes, most
        of what resting cost). Meanwhile the floe and its neighbours may pass into each
        other by what they drift at rest in those steps (0.02 m/s: under a millimetre); the
        engine pushes such an overlap apart once the floe is static, and a push that gives
        it ``rest_speed`` wakes it. Rows already shedding are left as they are; the others'
        count of steps at rest starts again, so that they are not picked again meanwhile.
        Rows already resting are left too: ``settle`` may have rested them since the caller
        read the moving rows (a step long enough to count a floe at rest within the shedding)."""
        if self._shedding:
            rows = rows[~np.isin(rows, np.concatenate([entry[1] for entry in self._shedding]))]
        rows = rows[~state.resting[rows]]
        if not len(rows):
            return
        state.calm[rows] = 0
        for p in self._floe_shapes(state, rows):
            lib.cpShapeSetFilter(_shape(p), _NO_CONTACT)
        tiles = state.tile[rows]
        held = {t: self._tiles[t] for t in np.unique(tiles).tolist()}
        # the stamp Chipmunk ages contacts by: one a step (not for dt = 0)
        self._shedding.append((lib.cpSpaceGetTimestamp(self._cp) + self.space.collision_persistence, rows.copy(),
                               tiles, self._floe_objects(state, rows, "floe_body"), held))

    def settle(self, state: FloeState) -> np.ndarray:
        """Make the floes that have shed their contacts static bodies, and take those bodies
        out of the space's body lists; their shapes collide again, from the static index.
        Chipmunk needs a shape's body in the space only when the shape goes in, and
        collides a static shape through the shape alone, while ``read_free`` (which walks
        every body the space lists) no longer reads the resting floes back. The arrays keep
        the pose and the velocity they came to rest with. A floe whose tile left the space
        meanwhile is gone with it (its row may hold another tile's floe by now: the tile's
        engine objects and the body must be the same); one that was struck under the hull
        stays as it is. Returns the rows now resting."""
        settled = [np.zeros(0, dtype=np.int64)]
        while self._shedding and self._shedding[0][0] <= lib.cpSpaceGetTimestamp(self._cp):
            _, rows, tiles, bodies, held = self._shedding.pop(0)
            ok = (state.tile[rows] == tiles) & (state.status[rows] == FloeStatus.FREE) & ~state.submerged[rows] \
                & ~state.resting[rows]
            for t, objects in held.items():
                at = np.flatnonzero(ok & (tiles == t))
                if self._tiles.get(t) is not objects:
                    ok[at] = False
                    continue
                local = rows[at] - self.tiles.row_start[t]
                ours = objects.floe_body[local] == bodies[at]
                ok[at[~ours]] = False
                for p, shape in zip(bodies[at[ours]].tolist(), objects.floe_shape[local[ours]].tolist()):
                    body = _body(p)
                    lib.cpBodySetType(body, lib.CP_BODY_TYPE_STATIC)  # its shape moves to the static index
                    lib.cpShapeSetFilter(_shape(shape), _FLOE)
                    lib.cpSpaceRemoveBody(self._cp, body)
            state.resting[rows[ok]] = True
            settled.append(rows[ok])
        return np.concatenate(settled)

    def wake(self, state: FloeState, rows: np.ndarray) -> None:
        """Bring resting rows back into the dynamic set with their mass, moment and the
        velocity they came to rest with."""
        m = self.model
        g = state.gcell[rows]
        for p, mass, moment, v, w in zip(self._floe_bodies(state, rows), m.mass[g].tolist(), m.inertia[g, 2].tolist(),
                                         state.vel[rows].tolist(), state.yaw_rate[rows].tolist()):
            body = _body(p)
            lib.cpSpaceAddBody(self._cp, body)  # static, with its shape in the space's static index
            lib.cpBodySetType(body, lib.CP_BODY_TYPE_DYNAMIC)  # moves the shape to the dynamic index; no mass from it
            lib.cpBodySetMass(body, mass)
            lib.cpBodySetMoment(body, moment)
            lib.cpBodySetVelocity(body, (v[0], v[1]))
            lib.cpBodySetAngularVelocity(body, w)
        state.resting[rows] = False
        state.calm[rows] = 0

    def read_contacts(self, state: FloeState) -> Contacts:
        """Contacts of the last step, in Chipmunk's order (which follows hashes of C
        pointers and so differs from run to run: sums over contacts must not depend on it)."""
        buf = self._buffer
        buf.clear()
        pb.get_space_arbiters(self.space, _ARB_FIELDS, buf)
        ints = np.frombuffer(buf.int_buf(), dtype=np.uintp).reshape(-1, 3)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ints), 8)
        self._arbiters = len(ints)
        tiles = self.tiles
        a, b, point = _contact_rows(ints, f, state.status, self._in_space()[3], tiles.template, tiles.corner,
                                    tiles.quarter_turns, tiles.row_start, self._sides, *self._grid)
        return Contacts(a, b, f[:, 0:2].copy(), f[:, 2:4].copy(), point)
