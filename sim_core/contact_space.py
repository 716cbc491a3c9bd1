"""Planar contact of hull, intact cells and free floes, on pymunk (the Chipmunk2D engine).

Chipmunk does the collision detection and the contact impulses; this module keeps pymunk's
bodies in step with the floe arrays. Every intact cell is its own static body, so a contact
names the exact cell it loads. Breaking switches that body to dynamic in place. Colliders
(mesh or sphere) carry the floe-floe contact, but the hull breaks whatever it touches
geometrically: an intact sphere cell also carries its true outline, as a sensor that only
the hull's query sees. The hull
is a kinematic body driven by the ship model. State moves between pymunk and the arrays
through ``pymunk.batch`` (one C call per step, no Python loop over bodies). Water drag in
the plane is Chipmunk's velocity damping, an exponential decay with the configured time
constant, applied in C. A quadratic drag would need a Python callback per body and step.
"""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pymunk.batch as pb

from sim_core.floe_state import FREE, INTACT, FloeState
from sim_core.ice_model import IceModel

HULL_ROW = -1
_HULL_BIT, _FLOE_BIT, _OUTLINE_BIT = 1, 2, 4
_HULL = pymunk.ShapeFilter(categories=_HULL_BIT, mask=_FLOE_BIT | _OUTLINE_BIT)
_FLOE = pymunk.ShapeFilter(categories=_FLOE_BIT, mask=_HULL_BIT | _FLOE_BIT)
_OUTLINE = pymunk.ShapeFilter(categories=_OUTLINE_BIT, mask=_HULL_BIT)  # seen by the hull only
_UNDER_HULL = pymunk.ShapeFilter(categories=0, mask=0)
_STATIC_ROW = -2  # bodies that are not floes (the space's own static body)
_BODY_FIELDS = (pb.BodyFields.BODY_ID | pb.BodyFields.POSITION | pb.BodyFields.ANGLE
                | pb.BodyFields.VELOCITY | pb.BodyFields.ANGULAR_VELOCITY)
_ARB_FIELDS = (pb.ArbiterFields.BODY_A_ID | pb.ArbiterFields.BODY_B_ID | pb.ArbiterFields.TOTAL_IMPULSE
               | pb.ArbiterFields.NORMAL | pb.ArbiterFields.CONTACT_COUNT | pb.ArbiterFields.POINT_A_1
               | pb.ArbiterFields.POINT_B_1 | pb.ArbiterFields.POINT_A_2 | pb.ArbiterFields.POINT_B_2)


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
        # a few thousand steps of a mesh-collider run, with every state finite. This code
        # switches static bodies to dynamic and changes shape filters, and that is the
        # suspected trigger. Not investigated further.
        self.space.damping = math.exp(-1.0 / s.drag_time_s)  # per second: v *= damping ** dt
        self.hull = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self.hull_shape = pymunk.Poly(self.hull, [tuple(p) for p in hull_outline])
        # the outline as pymunk keeps it: convex, counter-clockwise, body frame (y to port)
        self.hull_outline = np.array([tuple(v) for v in self.hull_shape.get_vertices()])
        self.hull_half_beam = float(np.abs(self.hull_outline[:, 1]).max())
        self.hull_shape.friction = hull_friction
        self.hull_shape.filter = _HULL
        self.space.add(self.hull, self.hull_shape)
        self._bodies: dict[int, tuple[pymunk.Body, pymunk.Shape]] = {}
        self._outline_sensors: dict[int, pymunk.Shape] = {}
        self._row_of_id: dict[int, int] = {self.hull.id: HULL_ROW}
        self._lookup = None
        self._buffer = pb.Buffer()

    # -- building -------------------------------------------------------------------------
    def add_intact(self, state: FloeState, rows: np.ndarray) -> None:
        """Add static bodies for intact rows at their current pose."""
        m, f = self.model, self.model.settings.ice_friction
        for i in rows:
            g = state.gcell[i]
            body = pymunk.Body(body_type=pymunk.Body.STATIC)
            body.position = tuple(state.xy[i])
            body.angle = float(state.yaw[i])
            ring = [tuple(p) for p in m.outline[m.outline_start[g]:m.outline_start[g + 1]]]
            shape = pymunk.Circle(body, float(m.radius[g])) if m.is_sphere[g] else pymunk.Poly(body, ring)
            shape.friction = f
            shape.filter = _FLOE
            self.space.add(body, shape)
            if m.is_sphere[g]:
                sensor = pymunk.Poly(body, ring)
                sensor.sensor = True
                sensor.filter = _OUTLINE
                self.space.add(sensor)
                self._outline_sensors[int(i)] = sensor
            self._bodies[int(i)] = (body, shape)
            self._row_of_id[body.id] = int(i)
        self._lookup = None

    def free(self, state: FloeState, rows: np.ndarray) -> None:
        """Turn intact rows into free floes: their static bodies become dynamic in place."""
        m = self.model
        for i in rows:
            body, _ = self._bodies[int(i)]
            sensor = self._outline_sensors.pop(int(i), None)
            if sensor is not None:
                self.space.remove(sensor)
            g = state.gcell[i]
            body.body_type = pymunk.Body.DYNAMIC
            body.mass = float(m.mass[g])
            body.moment = float(m.inertia[g, 2])
        state.status[rows] = FREE

    def set_submerged(self, rows: np.ndarray, submerged: bool) -> None:
        """Take rows out of (or back into) all planar contact: floes under the hull. A floe
        going under is pinned by the hull and loses its planar velocity."""
        f = _UNDER_HULL if submerged else _FLOE
        for i in rows:
            body, shape = self._bodies[int(i)]
            shape.filter = f
            if submerged:
                body.velocity = (0.0, 0.0)
                body.angular_velocity = 0.0

    def remove(self, rows: np.ndarray) -> None:
        """Take rows' bodies out of the space (frozen or discarded floes)."""
        for i in rows:
            body, shape = self._bodies.pop(int(i))
            del self._row_of_id[body.id]
            sensor = self._outline_sensors.pop(int(i), None)
            self.space.remove(body, shape, *([sensor] if sensor is not None else []))
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
        rows = {self._row_of_id.get(q.shape.body.id, _STATIC_ROW) for q in self.space.shape_query(self.hull_shape)}
        rows = np.array(sorted(r for r in rows if r >= 0), dtype=np.int64)
        return rows[state.status[rows] == INTACT] if len(rows) else rows

    def step(self, dt: float) -> None:
        self.space.step(dt)

    def _rows_of(self, ids: np.ndarray) -> np.ndarray:
        if self._lookup is None:
            keys = np.fromiter(self._row_of_id.keys(), dtype=np.uint64, count=len(self._row_of_id))
            vals = np.fromiter(self._row_of_id.values(), dtype=np.int64, count=len(self._row_of_id))
            order = np.argsort(keys)
            self._lookup = (keys[order], vals[order])
        keys, vals = self._lookup
        pos = np.clip(np.searchsorted(keys, ids), 0, max(len(keys) - 1, 0))
        return np.where(keys[pos] == ids, vals[pos], _STATIC_ROW) if len(keys) else np.full(len(ids), _STATIC_ROW)

    def read_free(self, state: FloeState) -> None:
        """Copy pose and velocity of the free floes from pymunk into the arrays."""
        buf = self._buffer
        buf.clear()
        pb.get_space_bodies(self.space, _BODY_FIELDS, buf)
        ids = np.frombuffer(buf.int_buf(), dtype=np.uintp).astype(np.uint64)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ids), 6)
        rows = self._rows_of(ids)
        sel = rows >= 0
        rows, f = rows[sel], f[sel]
        free = state.status[rows] == FREE
        rows, f = rows[free], f[free]
        state.xy[rows] = f[:, 0:2]
        state.yaw[rows] = f[:, 2]
        state.vel[rows] = f[:, 3:5]
        state.yaw_rate[rows] = f[:, 5]

    def read_contacts(self) -> dict[str, np.ndarray]:
        """Contacts of the last step: rows of bodies a and b (HULL_ROW for the hull), the
        impulse on a (N s), the normal from a to b, and the mean contact point (world m)."""
        buf = self._buffer
        buf.clear()
        pb.get_space_arbiters(self.space, _ARB_FIELDS, buf)
        ints = np.frombuffer(buf.int_buf(), dtype=np.uintp).astype(np.uint64).reshape(-1, 3)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ints), 12)
        count = ints[:, 2].astype(np.float64)
        point = np.where(count[:, None] > 1, 0.5 * (f[:, 4:6] + f[:, 8:10]), f[:, 4:6])
        return {"a": self._rows_of(ints[:, 0]), "b": self._rows_of(ints[:, 1]),
                "impulse": f[:, 0:2].copy(), "normal": f[:, 2:4].copy(), "point": point}
