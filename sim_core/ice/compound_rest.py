"""Wide floes' bodies coming to rest far from the hulls and waking again (``CompoundRest``, a
part of ``ContactSpace``; the bodies themselves: ``sim_core.ice.compound_floes``).

A woken floe at rest ``REST_REACH`` clear of every hull turns static again: no solver work,
and no drift in the field's frame, as resting floes (``sim_core.ice.resting``). First, as
a resting floe does (``contact_resting.FloeRest.rest``), it sheds its contacts: for the
engine's contact persistence its shapes collide with nothing, so that Chipmunk drops their
contacts in its own steps. Chipmunk keeps a contact between two static bodies for good
and lists it every step, with the points it had when the floe stopped: a floe made static
against the level ice or another resting floe would leave such contacts behind, read as
contacts at those stale points every step after. A hull coming near wakes the floe again.

The attributes of ``ContactSpace`` are used as they are there (``_tiles``, ``_cp``,
``space``, ``model``, ``hulls``, ``compounds``, ``_set_dynamic``).
"""
from __future__ import annotations

import numpy as np
from pymunk._chipmunk import lib

from sim_core.ice.chipmunk_bodies import FLOE_FILTER, NO_CONTACT, body_at, ptr_of, shape_at
from sim_core.ice.compound_floes import WAKE_AHEAD_S, WAKE_REACH

REST_REACH = 40.0  # m beyond every hull's bounds: a woken floe at rest this far from them turns static


class CompoundRest:
    """Resting and waking wide floes' bodies, for ``ContactSpace``."""

    def wake_resting(self, hull: int, speed: float) -> None:
        """Wake the resting floes whose reach from their centre comes within ``WAKE_REACH``
        (more ``WAKE_AHEAD_S`` of the speed, m/s) of the hull's (by index) bounds."""
        c = self.compounds
        if not c.resting:
            return
        slots = np.fromiter(c.resting, np.int64, len(c.resting))
        for slot in slots[self._clear_of(hull, slots) < WAKE_REACH + WAKE_AHEAD_S * speed].tolist():
            self._set_dynamic(slot)
            c.resting.discard(slot)

    def rest_far(self, speed: float) -> None:
        """Woken floes slower than speed (m/s, at their rim) whose reach from their centre lies
        ``REST_REACH`` or more beyond every hull's bounds start shedding their contacts; those
        that have shed them and are still so go static."""
        c = self.compounds
        shed = [k for k, stamp in c.shedding.items() if stamp <= lib.cpSpaceGetTimestamp(self._cp)]
        for slot in shed:
            self.stop_shedding(slot)
        settled = np.array([k for k in shed if k in c.live], np.int64)
        for slot in settled[self._at_rest_far(settled, speed)].tolist():
            body = body_at(c.live[slot])
            lib.cpBodySetVelocity(body, (0.0, 0.0))
            lib.cpBodySetAngularVelocity(body, 0.0)
            lib.cpBodySetType(body, lib.CP_BODY_TYPE_STATIC)  # its shapes move to the static index
            c.resting.add(slot)
        slots = np.array([k for k in c.live if k not in c.resting and k not in c.shedding], np.int64)
        for slot in slots[self._at_rest_far(slots, speed)].tolist():
            self._filter(slot, NO_CONTACT)
            c.shedding[slot] = lib.cpSpaceGetTimestamp(self._cp) + self.space.collision_persistence

    def stop_shedding(self, slot: int) -> None:
        """A floe's body (by slot) collides again, if it was shedding its contacts."""
        if self.compounds.shedding.pop(slot, None) is not None and slot in self.compounds.live:
            self._filter(slot, FLOE_FILTER)

    def _filter(self, slot: int, shape_filter: tuple[int, int, int]) -> None:
        """Give the shapes in the space of a live floe's body (by slot) a Chipmunk filter
        (the floe's cells' shapes on that body: a floe that parted has more than one)."""
        c, w = self.compounds, self.model.wide
        floe = int(c.floe[slot])
        shapes = self._tiles[int(c.placement[slot])].bond_shape[w.cells[w.cells_start[floe]:w.cells_start[floe + 1]]]
        body = int(c.body[slot])
        for p in shapes[shapes != 0].tolist():
            if ptr_of(lib.cpShapeGetBody(shape_at(p))) == body:
                lib.cpShapeSetFilter(shape_at(p), shape_filter)

    def _at_rest_far(self, slots: np.ndarray, speed: float) -> np.ndarray:
        """Which woken floes (by slot) are slower than speed (m/s, at their rim) and lie
        ``REST_REACH`` or more beyond every hull's bounds."""
        if not len(slots):
            return np.zeros(0, bool)
        c = self.compounds
        v = c.velocity[slots]
        slow = np.hypot(v[:, 0], v[:, 1]) + np.abs(v[:, 2]) * c.radius[slots] < speed
        return slow & (np.min([self._clear_of(k, slots) for k in range(len(self.hulls))], axis=0) >= REST_REACH)

    def _clear_of(self, hull: int, slots: np.ndarray) -> np.ndarray:
        """How far (m) woken floes' reach from their centre lies outside a hull's (by index)
        bounds (world, axis-aligned; 0 where they meet)."""
        box = self.hulls[hull].in_world()
        lo, hi = box.min(axis=0), box.max(axis=0)
        centre = self._centres(slots)
        out = np.maximum(np.maximum(lo - centre, centre - hi), 0.0)
        return np.maximum(np.hypot(out[:, 0], out[:, 1]) - self.compounds.radius[slots], 0.0)

    def _centres(self, slots: np.ndarray) -> np.ndarray:
        """Woken floes' centres of mass (n, 2), world m, at their last read poses."""
        c = self.compounds
        x, y, angle = c.pose[slots].T
        cx, cy = c.cog[slots].T
        cos, sin = np.cos(angle), np.sin(angle)
        return np.column_stack([x + cos * cx - sin * cy, y + sin * cx + cos * cy])
