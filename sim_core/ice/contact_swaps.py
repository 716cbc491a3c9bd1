"""Tiles switching into and out of the contact space (``TileSwaps``, a part of
``ContactSpace``): a built tile's objects enter over the coming steps, a dropped tile's
leave over them, each step's share budgeted by counts, not wall time, so that reruns stay
the same. Split from ``sim_core.ice.contact`` by responsibility; the space's own
attributes are used as they are there (``_tiles``, ``_cp``, ``_entering``, ``_leaving``,
``_tile_index``, ``compounds``, ``_insert_budget``, ``_removal_work``, ``_arbiters``)."""
from __future__ import annotations

from pymunk._chipmunk import ffi, lib

from sim_core.ice.chipmunk_bodies import BOND0, TILE0, TileBodies, body_at

# A tile removal's own cost (the static tree, its body's contacts), counted as visits of
# cached contacts, of which each removal also walks all: measured 2.2 us a removal with
# none cached and 18 us with 983 (16 ns a contact), 2 cores.
REMOVAL_OWN_COST = 140


class TileSwaps:
    """Switching tiles in and out, for ``ContactSpace``."""

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
        lib.cpBodySetUserData(body_at(bodies.body), ffi.cast("void *", TILE0 + placement))
        lib.cpSpaceAddBody(self._cp, body_at(bodies.body))
        for floe, (_, body) in bodies.wide.items():  # its wide floes' bodies, static until they wake
            slot = self.compounds.add(placement, floe, body)
            bodies.wide[floe] = slot, body
            lib.cpBodySetUserData(body_at(body), ffi.cast("void *", BOND0 + slot))
            lib.cpSpaceAddBody(self._cp, body_at(body))
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
        c = self.compounds
        for slot in [*(k for k, _ in bodies.wide.values()), *bodies.parts]:  # its wide floes' bodies: no longer read
            c.live.pop(slot, None)
            c.resting.discard(slot)  # nor woken by a hull coming near again
            c.shedding.pop(slot, None)
        if bodies in self._entering:
            self._entering.remove(bodies)
        bodies.queue = bodies.built()
        self._leaving.append((placement, bodies))

    def _swap_work(self) -> None:
        """Switch the step's share of objects of entering tiles in, and of leaving tiles out.
        Adding costs a few microseconds an object; removing one costs Chipmunk a walk over
        every cached contact (cpSpaceFilterArbiters) besides its own (``REMOVAL_OWN_COST``),
        so removals are budgeted by that work (``swap_removal_work``: about 2 ms a step).
        Both shares are counts, not wall times, so that reruns stay the same."""
        budget = self._insert_budget
        while budget > 0 and self._entering:
            bodies = self._entering[0]
            cells = max(1, budget // 2)  # a thawed floe is two objects: body and shape
            chunk, bodies.queue = bodies.queue[:cells], bodies.queue[cells:]
            budget -= max(bodies.insert(self._cp, chunk), 1)
            if not len(bodies.queue):
                self._entering.pop(0)
        budget = min(self._insert_budget, max(8, self._removal_work // (self._arbiters + REMOVAL_OWN_COST)))
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

    def is_leaving(self, placement: int) -> bool:
        """Whether objects of the placement's last switch-out are still in the space."""
        return any(k == placement for k, _ in self._leaving)
