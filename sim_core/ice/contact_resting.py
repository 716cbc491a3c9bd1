"""Floes coming to rest in the contact space and waking again (``FloeRest``, a part of
``ContactSpace``): a floe at rest sheds its contacts, becomes a static body out of the
space's body lists, and comes back as a dynamic body when it is struck. Split from
``sim_core.ice.contact`` by responsibility; the space's own attributes are used as they are
there (``_shedding``, ``_tiles``, ``_cp``, ``_moving_at``, ``_rest_work``)."""
from __future__ import annotations

import numpy as np
from pymunk._chipmunk import lib

from sim_core.ice.chipmunk_bodies import FLOE_FILTER, NO_CONTACT, body_at, shape_at
from sim_core.ice.floes import FloeState, FloeStatus


class FloeRest:
    """Resting and waking floes, for ``ContactSpace``."""

    def rest_share(self, picks: np.ndarray) -> int:
        """How many of the moving floes at these places (ascending) in the last
        ``read_free`` a step may start taking out of the dynamic set. Each, as it settles,
        costs Chipmunk a search of its dynamic bodies from the first up to its own, so the
        searches are counted (not timed) against ``rest_search_work``; at least one is
        taken. (Moving its shape into the static tree, which looks up the
        moving floes it overlaps, costs more, and grows with the moving floes as the engine
        step does: 16 us a floe with 8800 moving, 5 us with 3200, on 2 cores; the count
        ``rest_per_step`` bounds that.)"""
        return max(1, int(np.searchsorted(np.cumsum(self._moving_at[picks]), self._rest_work, side="right")))

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
            lib.cpShapeSetFilter(shape_at(p), NO_CONTACT)
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
                    body = body_at(p)
                    lib.cpBodySetType(body, lib.CP_BODY_TYPE_STATIC)  # its shape moves to the static index
                    lib.cpShapeSetFilter(shape_at(shape), FLOE_FILTER)
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
            body = body_at(p)
            lib.cpSpaceAddBody(self._cp, body)  # static, with its shape in the space's static index
            lib.cpBodySetType(body, lib.CP_BODY_TYPE_DYNAMIC)  # moves the shape to the dynamic index; no mass from it
            lib.cpBodySetMass(body, mass)
            lib.cpBodySetMoment(body, moment)
            lib.cpBodySetVelocity(body, (v[0], v[1]))
            lib.cpBodySetAngularVelocity(body, w)
        state.resting[rows] = False
        state.calm[rows] = 0
