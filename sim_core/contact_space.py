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

import numpy as np
import pymunk
import pymunk.batch as pb
from scipy.spatial import cKDTree

from sim_core.floe_state import FREE, INTACT, FloeState
from sim_core.ice_model import IceModel

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
        self._tile_of_id: dict[int, int] = {}
        self._floe_body: dict[int, pymunk.Body] = {}
        self._shape: dict[int, pymunk.Shape] = {}
        self._sensor: dict[int, pymunk.Shape] = {}
        self._row_of_shape: dict[pymunk.Shape, int] = {}
        self._row_of_id: dict[int, int] = {self.hull.id: HULL_ROW}
        self._lookup = None
        self._buffer = pb.Buffer()

    # -- building -------------------------------------------------------------------------
    def _collider(self, body: pymunk.Body, g: int, centre: list[float], ring: list) -> pymunk.Shape:
        """The cell's collider on body: a circle about centre or the polygon ring, both in
        the body's frame."""
        m = self.model
        shape = pymunk.Circle(body, float(m.radius[g]), centre) if m.is_sphere[g] else pymunk.Poly(body, ring)
        shape.friction = m.settings.ice_friction
        shape.filter = _FLOE
        return shape

    def _rings(self, g: np.ndarray, at: np.ndarray, angle: np.ndarray) -> list[list]:
        """Outlines of cells g placed at (at, angle), as lists of (x, y) for pymunk; one
        numpy transform for all of them."""
        m = self.model
        start, stop = m.outline_start[g], m.outline_start[g + 1]
        counts = stop - start
        owner = np.repeat(np.arange(len(g)), counts)
        idx = np.repeat(start - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
        pts = (_rotate(m.outline[idx], angle[owner]) + at[owner]).tolist()
        ends = np.cumsum(counts).tolist()
        return [pts[a:b] for a, b in zip([0] + ends[:-1], ends)]

    def add_tile(self, state: FloeState, tile: int, rows: np.ndarray) -> None:
        """Add a tile's intact rows, at their current pose, as shapes of one static body."""
        m = self.model
        body = pymunk.Body(body_type=pymunk.Body.STATIC)
        g, xy, yaw = state.gcell[rows], state.xy[rows], state.yaw[rows]
        rings, centres, sphere = self._rings(g, xy, yaw), xy.tolist(), m.is_sphere[g].tolist()
        shapes = []
        for i, gi, centre, ring, is_sphere in zip(rows.tolist(), g.tolist(), centres, rings, sphere):
            shape = self._collider(body, gi, centre, ring)
            shapes.append(shape)
            self._shape[i] = shape
            self._row_of_shape[shape] = i
            if is_sphere:
                sensor = pymunk.Poly(body, ring)
                sensor.sensor = True
                sensor.filter = _OUTLINE
                shapes.append(sensor)
                self._sensor[i] = sensor
                self._row_of_shape[sensor] = i
        self.space.add(body, *shapes)
        seeds = xy + _rotate(m.seed_offset[g], yaw)
        self._tile_rows[tile] = (np.asarray(rows), cKDTree(seeds))
        self._tile_of_id[body.id] = tile
        self._lookup = None

    def _drop_intact_shapes(self, i: int) -> pymunk.Body:
        shape = self._shape.pop(i)
        sensor = self._sensor.pop(i, None)
        for s in (shape, sensor):
            if s is not None:
                self.space.remove(s)
                del self._row_of_shape[s]
        return shape.body

    def free(self, state: FloeState, rows: np.ndarray) -> None:
        """Turn intact rows into free floes: each leaves its tile body for a dynamic body."""
        for i in rows:
            self._drop_intact_shapes(int(i))
        self.add_floes(state, rows)

    def add_floes(self, state: FloeState, rows: np.ndarray) -> None:
        """Add rows as free floes, each a dynamic body at its current pose and velocity."""
        m = self.model
        g = state.gcell[rows]
        rings = self._rings(g, np.zeros((len(rows), 2)), np.zeros(len(rows)))
        for i, gi, ring in zip(rows.tolist(), g.tolist(), rings):
            body = pymunk.Body(float(m.mass[gi]), float(m.inertia[gi, 2]))
            body.position = tuple(state.xy[i])
            body.angle = float(state.yaw[i])
            body.velocity = tuple(state.vel[i])
            body.angular_velocity = float(state.yaw_rate[i])
            shape = self._collider(body, gi, [0.0, 0.0], ring)
            self.space.add(body, shape)
            self._floe_body[i] = body
            self._shape[i] = shape
            self._row_of_shape[shape] = i
            self._row_of_id[body.id] = i
        state.status[rows] = FREE
        self._lookup = None

    def set_submerged(self, rows: np.ndarray, submerged: bool) -> None:
        """Take free rows out of (or back into) all planar contact: floes under the hull. A
        floe going under is pinned by the hull and loses its planar velocity."""
        f = _UNDER_HULL if submerged else _FLOE
        for i in rows:
            self._shape[int(i)].filter = f
            if submerged:
                self.set_velocity(np.array([i]), np.zeros((1, 2)), np.zeros(1))

    def set_velocity(self, rows: np.ndarray, velocity: np.ndarray, yaw_rate: np.ndarray) -> None:
        """Give free rows a planar velocity (n, 2) m/s and yaw rate (n,) rad/s."""
        for i, v, w in zip(rows, velocity, yaw_rate):
            body = self._floe_body[int(i)]
            body.velocity = (float(v[0]), float(v[1]))
            body.angular_velocity = float(w)

    def remove(self, state: FloeState, rows: np.ndarray) -> None:
        """Take intact or free rows out of the space (frozen or discarded floes); a tile body
        goes when its last intact cell has gone."""
        for i in rows:
            i = int(i)
            if state.status[i] == INTACT:
                body = self._drop_intact_shapes(i)
                if not body.shapes:
                    tile = self._tile_of_id.pop(body.id)
                    del self._tile_rows[tile]
                    self.space.remove(body)
            else:
                body, shape = self._floe_body.pop(i), self._shape.pop(i)
                del self._row_of_id[body.id], self._row_of_shape[shape]
                self.space.remove(body, shape)
        self._lookup = None

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
        rows = {self._row_of_shape.get(q.shape, _NOT_A_FLOE) for q in self.space.shape_query(self.hull_shape)}
        rows = np.array(sorted(r for r in rows if r >= 0), dtype=np.int64)
        return rows[state.status[rows] == INTACT] if len(rows) else rows

    def step(self, dt: float) -> None:
        self.space.step(dt)

    def _body_codes(self, ids: np.ndarray) -> np.ndarray:
        """Code of each body id: its row for a free floe, HULL_ROW for the hull,
        _TILE_CODE - tile for a tile body, _NOT_A_FLOE otherwise."""
        if self._lookup is None:
            table = {**{i: _TILE_CODE - t for i, t in self._tile_of_id.items()}, **self._row_of_id}
            keys = np.fromiter(table.keys(), dtype=np.uint64, count=len(table))
            vals = np.fromiter(table.values(), dtype=np.int64, count=len(table))
            order = np.argsort(keys)
            self._lookup = (keys[order], vals[order])
        keys, vals = self._lookup
        pos = np.clip(np.searchsorted(keys, ids), 0, len(keys) - 1)
        return np.where(keys[pos] == ids, vals[pos], _NOT_A_FLOE)

    def _rows_at(self, state: FloeState, ids: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Rows of the bodies in a contact list; on a tile body, the intact cell with the
        seed nearest the contact point (world m). The point lies on its cell's boundary,
        so that cell is among the few seeds nearest to it."""
        rows = self._body_codes(ids)
        on_tile = rows <= _TILE_CODE
        tiles = _TILE_CODE - rows[on_tile]
        at = np.nonzero(on_tile)[0]
        rows[on_tile] = _NOT_A_FLOE
        for tile in np.unique(tiles):
            k = at[tiles == tile]
            cells, tree = self._tile_rows[int(tile)]
            near = tree.query(points[k], k=min(_NEAREST, len(cells)))[1].reshape(len(k), -1)
            intact = state.status[cells[near]] == INTACT
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
        rows = self._body_codes(ids)
        sel = rows >= 0
        rows, f = rows[sel], f[sel]
        state.xy[rows] = f[:, 0:2]
        state.yaw[rows] = f[:, 2]
        state.vel[rows] = f[:, 3:5]
        state.yaw_rate[rows] = f[:, 5]

    def read_contacts(self, state: FloeState) -> dict[str, np.ndarray]:
        """Contacts of the last step: rows of bodies a and b (HULL_ROW for the hull), the
        impulse on a (N s), the normal from a to b, and the mean contact point (world m)."""
        buf = self._buffer
        buf.clear()
        pb.get_space_arbiters(self.space, _ARB_FIELDS, buf)
        ints = np.frombuffer(buf.int_buf(), dtype=np.uintp).astype(np.uint64).reshape(-1, 3)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ints), 12)
        count = ints[:, 2].astype(np.float64)
        point = np.where(count[:, None] > 1, 0.5 * (f[:, 4:6] + f[:, 8:10]), f[:, 4:6])
        return {"a": self._rows_at(state, ints[:, 0], point), "b": self._rows_at(state, ints[:, 1], point),
                "impulse": f[:, 0:2].copy(), "normal": f[:, 2:4].copy(), "point": point}
