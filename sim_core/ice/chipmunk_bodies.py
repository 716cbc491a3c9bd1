"""Chipmunk's C objects for the ice: the codes a body's user data holds, the shape filters, a
floe's collider made on a C body, and a placed tile's static body with its cells' shapes
(``TileBodies``).

The contact space (``sim_core.ice.contact``) drives Chipmunk through the C API that pymunk
bundles (``pymunk._chipmunk``), not through pymunk's Python classes, for the floes: a pymunk
``Body`` or ``Shape`` is a Python object in a reference cycle with its cffi handle, so
thousands of them cost seconds of creation per tile swap, pauses of a tenth of a second
whenever Python's cyclic collector walks them, and about a kilobyte each. A floe here costs
its C body and shape and two pointers in an array, and a body names its floe directly: its
user data is the floe's code (``ROW0 + row``, ``TILE0 + placement`` for a tile's static
body, ``BOND0 + slot`` for a wide floe's body (``compound_floes``), ``HULL0 + k`` for the
k-th hull), which ``pymunk.batch`` returns as the body id.
"""
from __future__ import annotations

import numpy as np
import pymunk
from pymunk._chipmunk import ffi, lib

MAX_HULLS = 16  # hulls one contact space holds: the ships of one exercise
NOT_A_FLOE = -1  # bodies that are not floes (the space's own static body)
HULL_ROW0 = -2  # a contact's row on hull k is HULL_ROW0 - k
LOWEST_ROW = HULL_ROW0 - (MAX_HULLS - 1)  # no contact's row is below this
HULL0 = 1
ROW0, TILE0 = HULL0 + MAX_HULLS, 1 << 40  # body user data: hull k is HULL0 + k, then floe rows, tile bodies
BOND0 = 1 << 50  # and wide floes' bodies, by slot (``compound_floes.CompoundSlots``)
HULL_BIT, FLOE_BIT = 1, 2
INTACT_IN, FLOE_IN = 1, 2  # TileBodies.in_space flags
FLOE_UNDER = 4  # and: the floe's shape is out of the space while it is under a hull (``TileBodies.sink``)
HULL_FILTER = (0, HULL_BIT, FLOE_BIT)  # Chipmunk shape filters: (group, categories, mask)
FLOE_FILTER = (0, FLOE_BIT, HULL_BIT | FLOE_BIT)
NO_CONTACT = (0, 0, 0)  # floes under the hull, and floes shedding their contacts before they rest
IDENTITY = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)  # cpTransform


def ptr_of(cdata) -> int:
    return int(ffi.cast("uintptr_t", cdata))


def shape_at(ptr: int):
    return ffi.cast("cpShape *", ptr)


def body_at(ptr: int):
    return ffi.cast("cpBody *", ptr)


def new_shape(body, ring: list, radius: float, centre: tuple[float, float], sphere: bool, friction: float) -> int:
    """A floe collider on a C body: a circle of radius about centre, or the convex polygon
    ring [(x, y), ...], both in the body's frame (m)."""
    if sphere:
        shape = lib.cpCircleShapeNew(body, radius, centre)
    else:
        shape = lib.cpPolyShapeNew(body, len(ring), ffi.new("cpVect[]", ring), IDENTITY, 0.0)
    lib.cpShapeSetFriction(shape, friction)
    lib.cpShapeSetFilter(shape, FLOE_FILTER)
    return ptr_of(shape)


class TileBodies:
    """Engine objects of one placed tile, by row offset in the tile (0 = none): the static
    body holding its intact cells, their shapes (a wide floe's on a body of the floe's own,
    ``wide``: global floe -> its slot, -1 until the tile is switched in, and body; static
    until the floe wakes, ``compound_floes``; ``parts``: slot -> body of each part that
    parted from such a body, ``floe_parts``), its free floes' bodies and shapes, and its
    bonded cells' shapes; the shapes of wide floes' cells ``held`` out of the space while
    their floe is whole around them (``hold``: which cells to build so,
    ``wide_floes.WideFloes.inner``); which of them are in the space; and the offsets still
    to switch in or out."""

    def __init__(self, count: int, hold: np.ndarray | None = None) -> None:
        self.body = ptr_of(lib.cpBodyNewStatic())
        self.hold = np.zeros(count, dtype=bool) if hold is None else hold
        self.held = np.zeros(count, dtype=np.uintp)
        self.intact = np.zeros(count, dtype=np.uintp)
        self.floe_body = np.zeros(count, dtype=np.uintp)
        self.floe_shape = np.zeros(count, dtype=np.uintp)
        self.bond_shape = np.zeros(count, dtype=np.uintp)
        self.wide: dict[int, tuple[int, int]] = {}
        self.parts: dict[int, int] = {}
        self.in_space = np.zeros(count, dtype=np.uint8)  # INTACT_IN | FLOE_IN
        self.queue = np.zeros(0, dtype=np.int64)  # offsets to switch in (entering) or out (leaving)

    def insert(self, space, offsets: np.ndarray) -> int:
        """Add the built objects at offsets to the space; returns how many went in."""
        flags = self.in_space[offsets]
        cells = offsets[(self.intact[offsets] != 0) & (flags & INTACT_IN == 0)]
        floes = offsets[(self.floe_body[offsets] != 0) & (flags & FLOE_IN == 0)]
        add_shape, add_body, cast = lib.cpSpaceAddShape, lib.cpSpaceAddBody, ffi.cast
        for p in self.intact[cells].tolist():
            add_shape(space, cast("cpShape *", p))
        for b, p in zip(self.floe_body[floes].tolist(), self.floe_shape[floes].tolist()):
            add_body(space, cast("cpBody *", b))
            add_shape(space, cast("cpShape *", p))
        self.in_space[cells] |= INTACT_IN
        self.in_space[floes] |= FLOE_IN
        return len(cells) + 2 * len(floes)

    def remove(self, space, offsets: np.ndarray) -> int:
        """Take the objects at offsets out of the space and free them; returns how many."""
        flags = self.in_space[offsets]
        cast = ffi.cast
        cells = offsets[self.intact[offsets] != 0]
        for p, inside in zip(self.intact[cells].tolist(), (flags[self.intact[offsets] != 0] & INTACT_IN).tolist()):
            shape = cast("cpShape *", p)
            if inside:
                lib.cpSpaceRemoveShape(space, shape)
            lib.cpShapeFree(shape)
        has_floe = self.floe_body[offsets] != 0
        floes = offsets[has_floe]
        for b, p, inside in zip(self.floe_body[floes].tolist(), self.floe_shape[floes].tolist(),
                                (flags[has_floe] & (FLOE_IN | FLOE_UNDER)).tolist()):
            body, shape = cast("cpBody *", b), cast("cpShape *", p)
            if inside:
                if inside == FLOE_IN:
                    lib.cpSpaceRemoveShape(space, shape)
                if lib.cpBodyGetSpace(body) != ffi.NULL:  # a resting floe's body is not (``rest``)
                    lib.cpSpaceRemoveBody(space, body)
            lib.cpShapeFree(shape)
            lib.cpBodyFree(body)
        bonded = self.bond_shape[offsets][self.bond_shape[offsets] != 0]
        self.drop_shapes(space, bonded)
        held = self.free_held(offsets)
        self.intact[offsets] = self.floe_body[offsets] = self.floe_shape[offsets] = self.bond_shape[offsets] = 0
        self.in_space[offsets] = 0
        return len(cells) + 2 * len(floes) + len(bonded) + held

    def sink(self, space, offsets: np.ndarray) -> None:
        """Take the shapes of the free floes at offsets out of the space while they are under
        a hull; their bodies stay. A floe under the hull touches nothing in the plane, but
        its shape would stay in the broad phase, paired every step with the pieces piled
        under the hull with it. Only moving floes' shapes (body in the space) go out."""
        for k, b, p in zip(offsets.tolist(), self.floe_body[offsets].tolist(), self.floe_shape[offsets].tolist()):
            if self.in_space[k] & (FLOE_IN | FLOE_UNDER) == FLOE_IN and lib.cpBodyGetSpace(body_at(b)) != ffi.NULL:
                lib.cpSpaceRemoveShape(space, shape_at(p))
                self.in_space[k] |= FLOE_UNDER

    def lift(self, space, offsets: np.ndarray) -> None:
        """Put back into the space the shapes ``sink`` took out, of the floes at offsets."""
        under = offsets[self.in_space[offsets] & FLOE_UNDER != 0]
        for p in self.floe_shape[under].tolist():
            lib.cpSpaceAddShape(space, shape_at(p))
        self.in_space[under] &= ~np.uint8(FLOE_UNDER)

    def expose(self, space, offsets: np.ndarray, bonded: np.ndarray) -> None:
        """Put the held shapes of cells at offsets (bonded (n,): on a woken floe's body, else
        intact) into the space, on the body they are on (their floe's, or the part's that
        took them, ``floe_parts``)."""
        has = self.held[offsets] != 0
        offsets, bonded = offsets[has], bonded[has]
        for p in self.held[offsets].tolist():
            lib.cpSpaceAddShape(space, shape_at(p))
        self.bond_shape[offsets[bonded]] = self.held[offsets[bonded]]
        self.intact[offsets[~bonded]] = self.held[offsets[~bonded]]
        self.in_space[offsets[~bonded]] |= INTACT_IN
        self.held[offsets] = 0

    def move_shapes(self, space, offsets: np.ndarray, body) -> None:
        """Move the bonded cells' shapes at offsets, in the space or held out of it, onto
        another body (in the space, in the same frame): Chipmunk changes a shape's body only
        out of the space, so those in it go out and back in."""
        in_space, held = self.bond_shape[offsets], self.held[offsets]
        for p in in_space[in_space != 0].tolist():
            lib.cpSpaceRemoveShape(space, shape_at(p))
            lib.cpShapeSetBody(shape_at(p), body)
            lib.cpSpaceAddShape(space, shape_at(p))
        for p in held[held != 0].tolist():
            lib.cpShapeSetBody(shape_at(p), body)

    def free_held(self, offsets: np.ndarray) -> int:
        """Free the held shapes (never in the space) at offsets; returns how many."""
        held = self.held[offsets][self.held[offsets] != 0]
        for p in held.tolist():
            lib.cpShapeFree(shape_at(p))
        self.held[offsets] = 0
        return len(held)

    @staticmethod
    def drop_shapes(space, shapes: np.ndarray) -> None:
        """Take shapes (C pointers) out of the space and free them."""
        for p in shapes.tolist():
            shape = shape_at(p)
            lib.cpSpaceRemoveShape(space, shape)
            lib.cpShapeFree(shape)

    def built(self) -> np.ndarray:
        """Offsets holding any object."""
        return np.nonzero((self.intact != 0) | (self.floe_body != 0) | (self.bond_shape != 0) | (self.held != 0))[0]

    def wide_body(self, floe: int) -> int:
        """The static body (C pointer) of a wide floe's intact cells, made at first need."""
        if floe not in self.wide:
            self.wide[floe] = (-1, ptr_of(lib.cpBodyNewStatic()))
        return self.wide[floe][1]

    def drop_wide(self, space, floe: int) -> None:
        """Take a wide floe's body (its shapes already gone) out of the space and free it."""
        _free_body(space, self.wide.pop(floe)[1])

    def drop_part(self, space, slot: int) -> None:
        """Take the body of a part of a wide floe (its shapes already gone) out of the space and free it."""
        _free_body(space, self.parts.pop(slot))

    def release(self, space) -> None:
        """Take everything out of the space and free it, the static body last."""
        self.remove(space, self.built())
        for floe in list(self.wide):
            self.drop_wide(space, floe)
        for slot in list(self.parts):
            self.drop_part(space, slot)
        _free_body(space, self.body)
        self.body = 0


def _free_body(space, ptr: int) -> None:
    """Take a body (C pointer) out of the space, if it is in it, and free it."""
    body = body_at(ptr)
    if lib.cpBodyGetSpace(body) != ffi.NULL:
        lib.cpSpaceRemoveBody(space, body)
    lib.cpBodyFree(body)


def free_all(space: pymunk.Space, tiles: dict, leaving: list, hulls: list[tuple[int, int]]) -> None:
    """Free every C object the contact space made, before the space itself goes; ``hulls``:
    each hull's body and shape (C pointers)."""
    for bodies in [*tiles.values(), *(b for _, b in leaving)]:
        bodies.release(space._space)
    for body_ptr, shape_ptr in hulls:
        hull_body, hull_shape = body_at(body_ptr), shape_at(shape_ptr)
        lib.cpSpaceRemoveShape(space._space, hull_shape)
        lib.cpSpaceRemoveBody(space._space, hull_body)
        lib.cpShapeFree(hull_shape)
        lib.cpBodyFree(hull_body)
