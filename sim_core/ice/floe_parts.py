"""A woken wide floe parting where a channel cuts it (``FloeParts``, a part of
``ContactSpace``; the floe's body itself: ``sim_core.ice.compound_floes``).

When cells leave a wide floe's body (``CompoundFloes.unbond``), the cells left on it may no
longer hang together: a hull that breaks a channel right across the floe leaves a part on
either side, and a cell whose neighbours all broke lies alone. The largest part keeps the
body; every other part of two cells or more gets a body of its own, laid where it lies and
moving as it moved on the floe's body, so that the parts go their own ways from there on; a
cell alone becomes a floe of its own, as a broken cell does.

Cells hang together where they may touch: ``WideFloes.mates``, the floe's cells whose
enclosing circles come within ``MATE_GAP`` of each other, which holds every pair of cells
that share an edge. So a part never parts where its cells touch; a crack narrower than
about a cell may leave two parts joined, a channel the hull breaks (a beam wide) does not.

The attributes of ``ContactSpace`` are used as they are there (``_cp``, ``model``,
``tiles``, ``compounds``, ``_reweigh``).
"""
from __future__ import annotations

import numba
import numpy as np
from pymunk._chipmunk import ffi, lib

from sim_core.ice.chipmunk_bodies import BOND0, TileBodies, body_at, ptr_of
from sim_core.ice.floes import FloeState


@numba.njit(cache=True)
def body_parts(g, mates_start, mates):
    """Which part each of a body's cells g (n,) (global cells of one template) lies in:
    cells joined through a chain of mates (``WideFloes.mates_start``, ``mates``) share one.

    Returns the parts (n,) int64, numbered 0, 1, ... in the order of each part's first cell,
    and their count. A walk over the mates, written here rather than scipy's
    ``connected_components``, which needs a sparse matrix built for each call: 1.4 ms
    against 32 us for a body of 1340 cells (2 cores)."""
    n = len(g)
    lo = g.min()
    where = np.full(g.max() - lo + 1, -1, np.int64)  # a global cell's place among g
    for i in range(n):
        where[g[i] - lo] = i
    part = np.full(n, -1, np.int64)
    stack = np.empty(n, np.int64)
    parts = 0
    for first in range(n):
        if part[first] >= 0:
            continue
        part[first], stack[0], top = parts, first, 1
        while top:
            top -= 1
            i = stack[top]
            for e in range(mates_start[g[i]], mates_start[g[i] + 1]):
                k = mates[e] - lo
                if 0 <= k < len(where) and where[k] >= 0 and part[where[k]] < 0:
                    part[where[k]] = parts
                    stack[top] = where[k]
                    top += 1
        parts += 1
    return part, parts


class FloeParts:
    """Parting a wide floe's body, for ``ContactSpace``."""

    def part(self, state: FloeState, bodies: TileBodies, slot: int, rows: np.ndarray) -> np.ndarray:
        """Part the body of a slot whose bonded rows (ascending) are rows: the largest part
        keeps it, with its cells' mass properties and reach; every other part of two cells
        or more gets a body of its own (``_part_body``). Returns the rows of the cells left
        alone, still on the body, for the caller to take off: all of them where no two
        hang together, and the body is to go."""
        w = self.model.wide
        part, parts = body_parts(state.gcell[rows], w.mates_start, w.mates)
        size = np.bincount(part, minlength=parts)
        keep = int(np.argmax(size))
        if size[keep] == 1:
            return rows
        for k in np.flatnonzero(size > 1).tolist():
            if k != keep:
                self._part_body(state, bodies, slot, rows[part == k])
        self._reweigh(state, slot, rows[part == keep])
        return rows[(size[part] == 1) & (part != keep)]

    def _part_body(self, state: FloeState, bodies: TileBodies, parent: int, rows: np.ndarray) -> None:
        """Move bonded rows of a floe's body (by slot) onto a body of their own, in a new
        slot: in the parent body's frame (the rows' ``bond_xy`` and ``bond_yaw`` hold), with
        the parent's velocity at its centre of mass and the parent's yaw rate, static if
        the parent rests."""
        c = self.compounds
        body = lib.cpBodyNew(1.0, 1.0)  # its mass properties: ``_reweigh`` below
        slot, ptr = self._new_part(bodies, int(c.placement[parent]), int(c.floe[parent]), body)
        c.pose[slot], c.velocity[slot], c.cog[slot] = c.pose[parent], c.velocity[parent], c.cog[parent]
        old = body_at(int(c.body[parent]))
        lib.cpBodySetCenterOfGravity(body, tuple(c.cog[parent].tolist()))
        lib.cpBodySetAngle(body, lib.cpBodyGetAngle(old))
        lib.cpBodySetPosition(body, lib.cpBodyGetPosition(old))
        lib.cpBodySetVelocity(body, lib.cpBodyGetVelocity(old))
        lib.cpBodySetAngularVelocity(body, lib.cpBodyGetAngularVelocity(old))
        lib.cpSpaceAddBody(self._cp, body)
        c.live[slot] = ptr
        if parent in c.resting:
            lib.cpBodySetType(body, lib.CP_BODY_TYPE_STATIC)
            c.resting.add(slot)
        bodies.move_shapes(self._cp, rows - int(self.tiles.row_start[c.placement[slot]]), body)
        state.bond_slot[rows] = slot
        self._reweigh(state, slot, rows)  # from the parent's centre of mass to its own, velocity field kept

    def _new_part(self, bodies: TileBodies, placement: int, floe: int, body) -> tuple[int, int]:
        """Give a new body (C object) of a part of a wide floe of the placement a slot, and
        name it by the slot (its user data); the tile's objects hold it. Returns the slot and
        the body's pointer."""
        ptr = ptr_of(body)
        slot = self.compounds.add(placement, floe, ptr)
        lib.cpBodySetUserData(body, ffi.cast("void *", BOND0 + slot))
        bodies.parts[slot] = ptr
        return slot, ptr


def warm_up() -> None:
    """Load the compiled kernel of this module (numba compiles or loads on first call)."""
    cells = np.zeros(1, FloeState.gcell.dtype)  # as the rows hold them: another type would compile again
    body_parts(cells, np.zeros(2, np.int64), np.zeros(0, np.int64))

