"""Planar contact of hull, intact cells and free floes, on pymunk (the Chipmunk2D engine).

Chipmunk does the collision detection and the contact impulses; this module keeps pymunk's
bodies in step with the floe arrays. All intact cells of a placed tile are shapes of one
static body, so the per-step body walk sees a few tile bodies, not thousands of cells. A
contact on a tile body is traced to its cell by the Voronoi property: the cell holding a
point is the one with the nearest seed. A contact point lies on the loaded cell's boundary,
and the neighbour across that boundary is already broken (that is where the striker came
from), so the nearest seed among the tile's intact cells names the loaded cell; a sphere
collider lies inside its cell, so there the answer is exact. Breaking moves a cell's shape
from its tile body to a new dynamic body. Colliders (mesh or sphere) carry the floe-floe
contact, but the hull breaks whatever it touches geometrically: an intact sphere cell also
carries its true outline, as a sensor that only the hull's query sees. The hull is a
kinematic body driven by the ship model. State moves between pymunk and the arrays through
``pymunk.batch`` (one C call per step, no Python loop over bodies). Water drag in the plane
is Chipmunk's velocity damping, an exponential decay with the configured time constant,
applied in C. A quadratic drag would need a Python callback per body and step.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymunk
import pymunk.batch as pb
from scipy.spatial import cKDTree

from sim_core.ice.floes import FloeState, FloeStatus
from sim_core.ice.model import IceModel, placed_outlines

HULL_ROW = -1
_HULL_BIT, _FLOE_BIT, _OUTLINE_BIT = 1, 2, 4
_HULL = pymunk.ShapeFilter(categories=_HULL_BIT, mask=_FLOE_BIT | _OUTLINE_BIT)
_FLOE = pymunk.ShapeFilter(categories=_FLOE_BIT, mask=_HULL_BIT | _FLOE_BIT)
_OUTLINE = pymunk.ShapeFilter(categories=_OUTLINE_BIT, mask=_HULL_BIT)  # seen by the hull only
_UNDER_HULL = pymunk.ShapeFilter(categories=0, mask=0)
_NOT_A_FLOE = -2  # bodies that are not floes (the space's own static body)
_TILE_CODE = -3  # tile t's static body is coded _TILE_CODE - t
_NEAREST = 8  # seeds searched for the nearest intact cell; a contact's cell is always among them
_BODY_FIELDS = (pb.BodyFields.BODY_ID | pb.BodyFields.POSITION | pb.BodyFields.ANGLE
                | pb.BodyFields.VELOCITY | pb.BodyFields.ANGULAR_VELOCITY)
_ARB_FIELDS = (pb.ArbiterFields.BODY_A_ID | pb.ArbiterFields.BODY_B_ID | pb.ArbiterFields.TOTAL_IMPULSE
               | pb.ArbiterFields.NORMAL | pb.ArbiterFields.CONTACT_COUNT | pb.ArbiterFields.POINT_A_1
               | pb.ArbiterFields.POINT_B_1 | pb.ArbiterFields.POINT_A_2 | pb.ArbiterFields.POINT_B_2)


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
        the contact point (m)."""
        on_a, on_b = self.a == HULL_ROW, self.b == HULL_ROW
        other = np.concatenate([self.b[on_a], self.a[on_b]])
        impulse = np.concatenate([self.impulse[on_a], -self.impulse[on_b]])
        return other, impulse, np.concatenate([self.point[on_a], self.point[on_b]])


class _BodyCodes:
    """Sorted table of pymunk body ids (their C pointers) -> code (a floe's row, HULL_ROW,
    or _TILE_CODE - tile), kept up to date as bodies come and go, so a step looks its
    bodies up with one searchsorted instead of rebuilding a dict."""

    def __init__(self) -> None:
        self.keys = np.zeros(0, dtype=np.uint64)
        self.codes = np.zeros(0, dtype=np.int64)

    def add(self, ids: list[int], codes: list[int]) -> None:
        keys = np.concatenate([self.keys, np.array(ids, dtype=np.uint64)])
        order = np.argsort(keys, kind="stable")
        self.keys, self.codes = keys[order], np.concatenate([self.codes, np.array(codes, dtype=np.int64)])[order]

    def remove(self, ids: list[int]) -> None:
        keep = ~np.isin(self.keys, np.array(ids, dtype=np.uint64))
        self.keys, self.codes = self.keys[keep], self.codes[keep]

    def lookup(self, ids: np.ndarray) -> np.ndarray:
        """Codes of body ids; _NOT_A_FLOE for bodies not in the table."""
        if not len(self.keys):
            return np.full(len(ids), _NOT_A_FLOE, dtype=np.int64)
        pos = np.clip(np.searchsorted(self.keys, ids), 0, len(self.keys) - 1)
        return np.where(self.keys[pos] == ids, self.codes[pos], _NOT_A_FLOE)


def _rotate(v: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Vectors (n, 2) rotated CCW by per-row angles (n,), rad."""
    c, s = np.cos(angle), np.sin(angle)
    return np.column_stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]])


class ContactSpace:
    """pymunk space holding the hull and the floes of breakable tiles."""

    def __init__(self, model: IceModel, hull_outline: np.ndarray, hull_friction: float) -> None:
        s = model.settings
        self.model = model
        self.space = pymunk.Space()
        self.space.iterations = s.solver_iterations
        self.space.collision_slop = s.collision_slop
        # Sleeping stays off. With sleeping enabled (idle speed set, since with no gravity in
        # the plane Chipmunk's default idle speed is zero), cpSpaceStep hung here for good after
        # a few thousand steps of a mesh-collider run, with every state finite. Not investigated
        # further; with intact ice in a few static tile bodies, the step does not need it.
        self.space.damping = math.exp(-1.0 / s.drag_time_s)  # per second: v *= damping ** dt
        self.hull = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self.hull_shape = pymunk.Poly(self.hull, [tuple(p) for p in hull_outline])
        # the outline as pymunk keeps it: convex, counter-clockwise, body frame (y to port)
        self.hull_outline = np.array([tuple(v) for v in self.hull_shape.get_vertices()])
        self.hull_half_beam = float(np.abs(self.hull_outline[:, 1]).max())
        self.hull_shape.friction = hull_friction
        self.hull_shape.filter = _HULL
        self.space.add(self.hull, self.hull_shape)
        self._tile_rows: dict[int, tuple[np.ndarray, cKDTree]] = {}  # rows, tree of their seeds (world m)
        # per floe row (lists indexed by row, grown as rows are added): its dynamic body,
        # its collider shape, and the outline sensor of an intact sphere cell
        self._floe_body: list[pymunk.Body | None] = []
        self._shape: list[pymunk.Shape | None] = []
        self._sensor: list[pymunk.Shape | None] = []
        self._codes = _BodyCodes()
        self._codes.add([self.hull.id], [HULL_ROW])
        self._buffer = pb.Buffer()

    def _grow(self, rows: int) -> None:
        """Make room in the per-row lists for rows [0, rows)."""
        extra = rows - len(self._shape)
        if extra > 0:
            for table in (self._floe_body, self._shape, self._sensor):
                table.extend([None] * extra)

    # -- building -------------------------------------------------------------------------
    def _collider(self, body: pymunk.Body, row: int, g: int, centre: list[float], ring: list) -> pymunk.Shape:
        """The cell's collider on body: a circle about centre or the polygon ring, both in
        the body's frame; the shape carries its floe row."""
        m = self.model
        shape = pymunk.Circle(body, float(m.radius[g]), centre) if m.is_sphere[g] else pymunk.Poly(body, ring)
        shape.friction = m.settings.ice_friction
        shape.filter = _FLOE
        shape.row = row
        self._shape[row] = shape
        return shape

    def _rings(self, g: np.ndarray, at: np.ndarray, angle: np.ndarray) -> list[list]:
        """Outlines of cells g placed at (at, angle), as lists of (x, y) for pymunk."""
        pts, counts = placed_outlines(self.model, g, at, angle)
        pts, ends = pts.tolist(), np.cumsum(counts).tolist()
        return [pts[a:b] for a, b in zip([0] + ends[:-1], ends)]

    def add_tile(self, state: FloeState, tile: int, rows: np.ndarray) -> None:
        """Add a tile's intact rows, at their current pose, as shapes of one static body."""
        m = self.model
        self._grow(state.n)
        body = pymunk.Body(body_type=pymunk.Body.STATIC)
        body.tile = tile
        g, xy, yaw = state.gcell[rows], state.xy[rows], state.yaw[rows]
        rings, centres, sphere = self._rings(g, xy, yaw), xy.tolist(), m.is_sphere[g].tolist()
        shapes = []
        for i, gi, centre, ring, is_sphere in zip(rows.tolist(), g.tolist(), centres, rings, sphere):
            shapes.append(self._collider(body, i, gi, centre, ring))
            if is_sphere:
                sensor = pymunk.Poly(body, ring)
                sensor.sensor = True
                sensor.filter = _OUTLINE
                sensor.row = i
                shapes.append(sensor)
                self._sensor[i] = sensor
        self.space.add(body, *shapes)
        seeds = xy + _rotate(m.seed_offset[g], yaw)
        self._tile_rows[tile] = (np.asarray(rows), cKDTree(seeds))
        self._codes.add([body.id], [_TILE_CODE - tile])

    def _drop_intact_shapes(self, i: int) -> pymunk.Body:
        shape, sensor = self._shape[i], self._sensor[i]
        self._shape[i] = self._sensor[i] = None
        self.space.remove(*(s for s in (shape, sensor) if s is not None))
        return shape.body

    def free(self, state: FloeState, rows: np.ndarray) -> None:
        """Intact rows leave their tile body, each for a dynamic body of its own."""
        for i in rows.tolist():
            self._drop_intact_shapes(i)
        self.add_floes(state, rows)

    def add_floes(self, state: FloeState, rows: np.ndarray) -> None:
        """Add rows as free floes, each a dynamic body at its current pose and velocity."""
        m = self.model
        self._grow(state.n)
        g = state.gcell[rows]
        rings = self._rings(g, np.zeros((len(rows), 2)), np.zeros(len(rows)))
        ids = []
        for i, gi, ring in zip(rows.tolist(), g.tolist(), rings):
            body = pymunk.Body(float(m.mass[gi]), float(m.inertia[gi, 2]))
            body.position = tuple(state.xy[i])
            body.angle = float(state.yaw[i])
            body.velocity = tuple(state.vel[i])
            body.angular_velocity = float(state.yaw_rate[i])
            self.space.add(body, self._collider(body, i, gi, [0.0, 0.0], ring))
            self._floe_body[i] = body
            ids.append(body.id)
        self._codes.add(ids, rows.tolist())

    def set_submerged(self, rows: np.ndarray, submerged: bool) -> None:
        """Take free rows out of (or back into) all planar contact: floes under the hull. A
        floe going under is pinned by the hull and loses its planar velocity."""
        f = _UNDER_HULL if submerged else _FLOE
        for i in rows.tolist():
            self._shape[i].filter = f
            if submerged:
                self.set_velocity(np.array([i]), np.zeros((1, 2)), np.zeros(1))

    def set_velocity(self, rows: np.ndarray, velocity: np.ndarray, yaw_rate: np.ndarray) -> None:
        """Give free rows a planar velocity (n, 2) m/s and yaw rate (n,) rad/s."""
        for i, v, w in zip(rows.tolist(), velocity.tolist(), yaw_rate.tolist()):
            body = self._floe_body[i]
            body.velocity = (v[0], v[1])
            body.angular_velocity = w

    def remove(self, state: FloeState, rows: np.ndarray) -> None:
        """Take intact or free rows out of the space (frozen or discarded floes); a tile body
        goes when its last intact cell has gone."""
        gone = []
        for i, intact in zip(rows.tolist(), (state.status[rows] == FloeStatus.INTACT).tolist()):
            if intact:
                body = self._drop_intact_shapes(i)
                if not body.shapes:
                    del self._tile_rows[body.tile]
                    self.space.remove(body)
                    gone.append(body.id)
            else:
                body, shape = self._floe_body[i], self._shape[i]
                self._floe_body[i] = self._shape[i] = None
                self.space.remove(body, shape)
                gone.append(body.id)
        self._codes.remove(gone)

    # -- per step -------------------------------------------------------------------------
    def set_hull(self, xy: np.ndarray, angle: float, velocity: np.ndarray, angular_velocity: float) -> None:
        """Pose (world m, rad CCW) and velocity of the kinematic hull for the coming step."""
        self.hull.position = (float(xy[0]), float(xy[1]))
        self.hull.angle = float(angle)
        self.hull.velocity = (float(velocity[0]), float(velocity[1]))
        self.hull.angular_velocity = float(angular_velocity)
        self.space.reindex_shapes_for_body(self.hull)

    def hull_touching(self, state: FloeState) -> np.ndarray:
        """Rows of intact cells the hull overlaps now (kinematic-static pairs make no contacts
        in Chipmunk, so they are found by a shape query)."""
        rows = {getattr(q.shape, "row", _NOT_A_FLOE) for q in self.space.shape_query(self.hull_shape)}
        rows = np.array(sorted(r for r in rows if r >= 0), dtype=np.int64)
        return rows[state.status[rows] == FloeStatus.INTACT] if len(rows) else rows

    def step(self, dt: float) -> None:
        self.space.step(dt)

    def _rows_at(self, state: FloeState, ids: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Rows of the bodies in a contact list; on a tile body, the intact cell with the
        seed nearest the contact point (world m). The point lies on its cell's boundary,
        so that cell is among the few seeds nearest to it."""
        rows = self._codes.lookup(ids)
        on_tile = rows <= _TILE_CODE
        tiles = _TILE_CODE - rows[on_tile]
        at = np.nonzero(on_tile)[0]
        rows[on_tile] = _NOT_A_FLOE
        for tile in np.unique(tiles):
            k = at[tiles == tile]
            cells, tree = self._tile_rows[int(tile)]
            near = tree.query(points[k], k=min(_NEAREST, len(cells)))[1].reshape(len(k), -1)
            intact = state.status[cells[near]] == FloeStatus.INTACT
            first = np.argmax(intact, axis=1)
            rows[k] = np.where(intact.any(axis=1), cells[near[np.arange(len(k)), first]], _NOT_A_FLOE)
        return rows

    def read_free(self, state: FloeState) -> None:
        """Copy pose and velocity of the free floes from pymunk into the arrays."""
        buf = self._buffer
        buf.clear()
        pb.get_space_bodies(self.space, _BODY_FIELDS, buf)
        ids = np.frombuffer(buf.int_buf(), dtype=np.uintp).astype(np.uint64)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ids), 6)
        rows = self._codes.lookup(ids)
        sel = rows >= 0
        rows, f = rows[sel], f[sel]
        state.xy[rows] = f[:, 0:2]
        state.yaw[rows] = f[:, 2]
        state.vel[rows] = f[:, 3:5]
        state.yaw_rate[rows] = f[:, 5]

    def read_contacts(self, state: FloeState) -> Contacts:
        """Contacts of the last step."""
        buf = self._buffer
        buf.clear()
        pb.get_space_arbiters(self.space, _ARB_FIELDS, buf)
        ints = np.frombuffer(buf.int_buf(), dtype=np.uintp).astype(np.uint64).reshape(-1, 3)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ints), 12)
        count = ints[:, 2].astype(np.float64)
        point = np.where(count[:, None] > 1, 0.5 * (f[:, 4:6] + f[:, 8:10]), f[:, 4:6])
        return Contacts(self._rows_at(state, ints[:, 0], point), self._rows_at(state, ints[:, 1], point),
                        f[:, 0:2].copy(), f[:, 2:4].copy(), point)
