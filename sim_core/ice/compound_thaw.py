"""A woken wide floe coming back as one body when its tile thaws (``CompoundThaw``, a part
of ``ContactSpace``; the floe's body itself: ``sim_core.ice.compound_floes``).

A tile freezes far astern with its woken floes' cells kept as frozen floes, and with which
body each was on and where on it (``FrozenFloes.keep_bonds``). When the tile thaws (the
ship turns back, or the field drifts it back into range), those cells are built as the
floe's intact cells are, on the floe's static body where the tile lays them
(``tiles.prepare_thaw``), and ``rebond`` puts each body back where it froze: the body
turned and moved so that every cell lies at the pose it froze with, its cells bonded to it
again, its mass properties those of its cells, moving as its cells did when they froze
(as a frozen floe thaws with its velocity). Far from the hulls it comes to rest again
(``compound_rest``). A floe that had parted thaws as its parts, each a body of its own.

Without this a thawed floe came back as its cells, each a floe of its own held to the
others by contact only. In the issue's field (7/10 small and medium floes), the ship moved
1.5 km away until the tiles it had steamed through froze, then back: none of their 3980
bonded cells came back bonded; with this, all of them did, on their 17 bodies.

The attributes of ``ContactSpace`` are used as they are there (``_tiles``, ``_cp``,
``tiles``, ``model``, ``compounds``, ``_reweigh``, ``_set_dynamic``, ``_new_part``).
"""
from __future__ import annotations

import math

import numpy as np
from pymunk._chipmunk import lib

from sim_core.ice.chipmunk_bodies import TileBodies, body_at, shape_at
from sim_core.ice.floes import FloeState


class CompoundThaw:
    """Woken floes' bodies rebuilt at a thaw, for ``ContactSpace``."""

    def rebond(self, state: FloeState, placement: int, bonds: np.ndarray) -> None:
        """Bond a thawed tile's rows (its ``FROZEN_BOND`` records, bonds) to their floes'
        bodies again, each body where it froze, moving as it froze. Call after the tile's
        switch-in (``insert_tile``: the floes' static bodies are in the space, the cells'
        shapes not yet) and after the rows got back their frozen poses."""
        if not len(bonds):
            return
        start = int(self.tiles.row_start[placement])
        rows = start + bonds["cell"].astype(np.int64)
        state.bond_xy[rows], state.bond_yaw[rows], state.bonded[rows] = bonds["bond_xy"], bonds["bond_yaw"], True
        floes, bodies = self.model.wide.of_cell[state.gcell[rows]], self._tiles[placement]
        for k in np.unique(bonds["body"]).tolist():
            mine = bonds["body"] == k
            self._thaw_body(state, bodies, placement, int(floes[mine][0]), rows[mine])

    def _thaw_body(self, state: FloeState, bodies: TileBodies, placement: int, floe: int, rows: np.ndarray) -> None:
        """Make the bonded rows (one body's when it froze) of a wide floe one body again:
        the floe's own body, or, where another part of the floe took that, a body of the
        part's own (as ``floe_parts`` makes one) in a new slot. The body is posed so that
        its cells lie where the rows say, it moves as the rows did, and their shapes (built
        on the floe's body where the tile lays them) go into the space on it now."""
        c = self.compounds
        slot, ptr = bodies.wide[floe]
        j = rows - int(self.tiles.row_start[placement])
        shapes, held = bodies.intact[j], bodies.held[j]
        if slot in c.live:  # an earlier part has the floe's body
            body = lib.cpBodyNewStatic()
            slot, ptr = self._new_part(bodies, placement, floe, body)
            lib.cpSpaceAddBody(self._cp, body)
            for p in [*shapes[shapes != 0].tolist(), *held[held != 0].tolist()]:
                lib.cpShapeSetBody(shape_at(p), body)
        c.pose[slot] = _pose(state, rows[0])
        body = body_at(ptr)
        lib.cpBodySetAngle(body, float(c.pose[slot, 2]))
        lib.cpBodySetPosition(body, tuple(c.pose[slot, :2].tolist()))
        state.bond_slot[rows] = slot
        c.live[slot] = ptr
        c.resting.add(slot)  # static while ``_reweigh`` gives it its cells' mass properties
        self._reweigh(state, slot, rows)
        self._set_dynamic(slot)
        c.resting.discard(slot)
        c.velocity[slot] = _velocity(state, rows[0], c.pose[slot], c.cog[slot])
        lib.cpBodySetVelocity(body, tuple(c.velocity[slot, :2].tolist()))
        lib.cpBodySetAngularVelocity(body, float(c.velocity[slot, 2]))
        # The shapes go in onto the moving body, into the engine's dynamic index. Put on the
        # static body before it turned dynamic (moved from one index to the other), reruns
        # of a turn back into thawed floes differed in the last bits from the fourth step
        # after the thaw (tests/test_thawed_floe_reruns.py); so they are the same.
        for p in shapes[shapes != 0].tolist():
            lib.cpSpaceAddShape(self._cp, shape_at(p))
        bodies.bond_shape[j], bodies.intact[j] = shapes, 0


def _pose(state: FloeState, row: int) -> np.ndarray:
    """The pose (3,) of the body a bonded row is on, origin x, y m and angle rad, from the
    row's pose and its place on the body: its yaw is bond_yaw + angle, its centre the
    origin plus bond_xy turned by the angle."""
    angle = float(state.yaw[row] - state.bond_yaw[row])
    cos, sin = math.cos(angle), math.sin(angle)
    bx, by = state.bond_xy[row]
    return np.array([state.xy[row, 0] - (cos * bx - sin * by), state.xy[row, 1] - (sin * bx + cos * by), angle])


def _velocity(state: FloeState, row: int, pose: np.ndarray, cog: np.ndarray) -> np.ndarray:
    """The velocity (3,) of a body at its centre of mass, m/s, and its yaw rate, rad/s, from
    a bonded row's (the body's velocity field at the row's centre): v_c = v - w x (r - c),
    c the centre of mass cog (2,) in the body's frame, carried to the world by the pose."""
    cos, sin = math.cos(pose[2]), math.sin(pose[2])
    cx, cy = pose[0] + cos * cog[0] - sin * cog[1], pose[1] + sin * cog[0] + cos * cog[1]
    w = float(state.yaw_rate[row])
    (vx, vy), (x, y) = state.vel[row].astype(float), state.xy[row]
    return np.array([vx + w * (y - cy), vy - w * (x - cx), w])
