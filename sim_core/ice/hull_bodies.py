"""The hulls in the contact space: one kinematic Chipmunk body per ship.

Every ship of an exercise breaks ice in the one contact space, so that a ship following
another meets the channel the first left. A hull is a kinematic body (its ship's model
drives it) with one convex polygon, its waterline outline. Hulls collide with floes only,
not with each other: two ships meeting is the ship models' business, not the ice's. The
k-th hull's body carries the code ``HULL0 + k`` (``chipmunk_bodies``), and its contacts
the row ``HULL_ROW0 - k`` (``contact_kernels.Contacts``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pymunk._chipmunk import ffi, lib

from sim_core.ice.chipmunk_bodies import HULL0, HULL_FILTER, IDENTITY, MAX_HULLS, ptr_of


@dataclass
class HullBody:
    """One hull in the contact space: its C body and shape (pointers), its outline as
    Chipmunk keeps it (convex, counter-clockwise, body frame with x forward and y to port;
    (n, 2) m) with the measures the ice step reads of it, and its pose for the coming step
    (reference point, world m; angle, rad CCW from east)."""

    body: int
    shape: int
    outline: np.ndarray
    xy: np.ndarray = field(default_factory=lambda: np.zeros(2))
    angle: float = 0.0
    half_beam: float = field(init=False)  # m from the centre line to the widest point
    stem: float = field(init=False)  # m forward of the reference point
    box: np.ndarray = field(init=False)  # the outline's bounds: x min, x max, y min, y max (body frame, m)
    radius: float = field(init=False)  # m from the reference point: no point of the hull lies farther out

    def __post_init__(self) -> None:
        o = self.outline
        self.half_beam = float(np.abs(o[:, 1]).max())
        self.stem = float(o[:, 0].max())
        self.box = np.array([o[:, 0].min(), o[:, 0].max(), o[:, 1].min(), o[:, 1].max()])
        self.radius = float(np.hypot(*np.abs(o).max(axis=0)))

    def in_world(self) -> np.ndarray:
        """The outline at the hull's pose (n, 2), world m."""
        c, s = np.cos(self.angle), np.sin(self.angle)
        return self.outline @ np.array([[c, s], [-s, c]]) + self.xy


def new_hull(space, index: int, outline: np.ndarray, friction: float) -> HullBody:
    """Add the index-th hull to the C space: a kinematic body with the convex hull of
    ``outline`` ((n, 2) m, body frame: x forward, y to port) as its shape, of the given
    friction against ice."""
    if not 0 <= index < MAX_HULLS:
        raise ValueError(f"a contact space holds at most {MAX_HULLS} hulls, not {index + 1}")
    body = lib.cpBodyNewKinematic()
    lib.cpBodySetUserData(body, ffi.cast("void *", HULL0 + index))
    ring = [tuple(p) for p in np.asarray(outline, dtype=float).tolist()]
    shape = lib.cpPolyShapeNew(body, len(ring), ffi.new("cpVect[]", ring), IDENTITY, 0.0)
    lib.cpShapeSetFriction(shape, friction)
    lib.cpShapeSetFilter(shape, HULL_FILTER)
    lib.cpSpaceAddBody(space, body)
    lib.cpSpaceAddShape(space, shape)
    verts = [lib.cpPolyShapeGetVert(shape, i) for i in range(lib.cpPolyShapeGetCount(shape))]
    return HullBody(ptr_of(body), ptr_of(shape), np.array([(v.x, v.y) for v in verts]))


def move_hull(space, hull: HullBody, xy: np.ndarray, angle: float, velocity: np.ndarray,
              angular_velocity: float) -> None:
    """Pose (world m, rad CCW) and velocity (m/s, rad/s CCW) of a hull for the coming step."""
    body = ffi.cast("cpBody *", hull.body)
    lib.cpBodySetPosition(body, (float(xy[0]), float(xy[1])))
    lib.cpBodySetAngle(body, float(angle))
    lib.cpBodySetVelocity(body, (float(velocity[0]), float(velocity[1])))
    lib.cpBodySetAngularVelocity(body, float(angular_velocity))
    lib.cpSpaceReindexShapesForBody(space, body)
    hull.xy, hull.angle = np.array([float(xy[0]), float(xy[1])]), float(angle)
