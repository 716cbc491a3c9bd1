"""A wide floe moving as one body until it breaks (``CompoundFloes``, a part of
``ContactSpace``), and the kernels that read such bodies' contacts and poses.

A floe wider than the ship's beam is laid as the paper's pre-fracture cut to the floe
(§2.1): intact cells, their shapes on a static body of the floe's own, at no cost a step.
When a hull comes near such a floe (``WAKE_REACH`` beyond the hull's bounds, more
``WAKE_AHEAD_S`` of its speed), ``bond`` turns that body dynamic, a compound body: a shape
per cell of its rim (the cells inside are held out of the engine until the rim around them
breaks, ``wide_floes``), the floe's mass, centre of mass and moment of inertia summed from
all its cells'.
Their rows become FREE and ``bonded``: drawn, streamed and frozen as floes, their poses
following the floe's body (``scatter_bonded``). So the floe moves as a whole: the hull
and other floes push and turn it, and the water drags it. At rest and far from every
hull it turns static again, and a hull coming near wakes it
(``sim_core.ice.compound_rest``).

A cell of the floe breaks away when a contact loads it past its capacity: struck by a
free floe, by the test an intact edge meets (``step._hard_pushes``); struck by the hull, by
the energy test of ``breaking.pushed_hard``, J v_n >= K(h), v_n the larger of the hull's
approach speed at the contact and J / M, the speed the contact gave the floe's body (the
hull does not ride up, so there is no load test). The engine's rigid contact took the
hull's whole approach out of the floe in one impulse J. A breaking edge carries its
failure load F_s (the paper's Table 3 wedge load, ``breaking.static_capacity``) while the
hull crushes through the cell, advancing the cell's size d = sqrt(plan area) at v_n; so
the floe keeps F_s d / v_n of J, the rest goes back from its body at the contact, and the
hull's load counts only that share (``hull_breaks``, ``struck_off``). The crushing time is
this project's model, not the paper's: with the edge's elastic-energy impulse K / v_n
alone (about 70 times less for 0.5 m ice, its cells 2.4 m across), a floe struck at
0.3 m/s did not move and the hull cut through it cell by cell. A broken cell gets a body
of its own (``unbond``, from ``ContactSpace.free``), and the floe's body its remaining
cells' mass properties. So a slow push moves a floe, and a ship at speed breaks a channel
into it, shoving it the harder the longer it crushes. Where the cells left on the body no
longer hang together (a channel right across the floe), it parts: each part a body of its
own (``floe_parts``).

A tile frozen keeps its bonded cells as frozen floes, with the body each was on, and a
thaw makes them those bodies again (``sim_core.ice.compound_thaw``).

Not modelled: a floe a tile edge cuts is a body per tile; the bonded cells take no
conduction cracking (``bending``), so a floe parts only where its cells broke.

The attributes of ``ContactSpace`` are used as they are there (``_tiles``, ``_cp``,
``_entering``, ``model``, ``tiles``, ``hulls``, ``extent``, ``compounds``, ``_in_space``,
``_sides``, ``stop_shedding``).
"""
from __future__ import annotations

import math

import numba
import numpy as np
from pymunk._chipmunk import lib

from sim_core.ice.breaking import pushed_hard
from sim_core.ice.chipmunk_bodies import BOND0, HULL_ROW0, INTACT_IN, LOWEST_ROW, NOT_A_FLOE, TileBodies, body_at
from sim_core.ice.contact_kernels import Contacts, nearest_cell
from sim_core.ice.floes import FloeState, FloeStatus
from sim_core.ice.tile_frame import template_point
from sim_core.ice.wide_floes import floes_near

WAKE_REACH = 10.0  # m beyond a hull's bounds: a wide floe's bounds this near wake it
WAKE_AHEAD_S = 2.0  # s of the hull's speed added to that reach


class CompoundSlots:
    """Every wide floe's body switched into the space, by slot (and every part that parted
    from one, ``floe_parts``): its placement, global floe, C body, centre of mass in the
    body's frame (m) and pose at the last ``read_poses`` (origin x, y m; angle rad). A body
    is made static at the world's origin, its cells' shapes where the tile lays them, so
    the body's frame is the world's as the floe lay when it woke (a part keeps its floe's
    frame). ``live``: slot -> C body of the woken floes of tiles worked now; ``resting``:
    those of them at rest far from the hulls, static again, and ``shedding``: those
    shedding their contacts before that (``compound_rest``). Slots are never reused, so
    that a body still leaving the space with its tile never names another floe (a few tens
    of bytes a wide floe laid)."""

    def __init__(self) -> None:
        self.n = 0
        self.placement, self.floe, self.body = np.zeros(64, np.int64), np.zeros(64, np.int64), np.zeros(64, np.uintp)
        self.cog, self.pose, self.velocity = np.zeros((64, 2)), np.zeros((64, 3)), np.zeros((64, 3))
        self.mass, self.moment, self.radius = np.zeros(64), np.zeros(64), np.zeros(64)
        self.live: dict[int, int] = {}
        self.resting: set[int] = set()
        self.shedding: dict[int, int] = {}  # slot -> the engine's stamp from which it has shed its contacts

    def add(self, placement: int, floe: int, body: int) -> int:
        """A new slot for a body (C pointer) of the floe; returns it."""
        if self.n == len(self.floe):
            for name in ("placement", "floe", "body", "cog", "pose", "velocity", "mass", "moment", "radius"):
                old = getattr(self, name)
                setattr(self, name, np.concatenate([old, np.zeros_like(old)]))
        slot, self.n = self.n, self.n + 1
        self.placement[slot], self.floe[slot], self.body[slot] = placement, floe, body
        self.cog[slot], self.pose[slot] = 0.0, 0.0
        return slot

    def read_poses(self) -> None:
        """Read the moving woken bodies' poses from the engine (a few C calls a body)."""
        for slot, body in self.live.items():
            if slot in self.resting:
                continue
            at = lib.cpBodyGetPosition(body_at(body))
            self.pose[slot] = at.x, at.y, lib.cpBodyGetAngle(body_at(body))


def _mass_properties(mass: np.ndarray, izz: np.ndarray, at: np.ndarray) -> tuple[float, np.ndarray, float]:
    """Mass (kg), centre of mass (2,) and moment of inertia about it (kg m2) of cells of
    mass (n,) kg and yaw moment izz (n,) kg m2 about their centres at (n, 2) m."""
    total = float(mass.sum())
    centre = mass @ at / total
    return total, centre, float((izz + mass * ((at - centre) ** 2).sum(axis=1)).sum())


class CompoundFloes:
    """Wide floes' bodies, for ``ContactSpace``."""

    def wake_near(self, state: FloeState, hull: int, speed: float) -> list[tuple[int, int]]:
        """The wide floes still static, with intact cells, near the hull (by index) moving at
        speed (m/s), of tiles whose objects are all in the space: (placement, global
        floe) pairs."""
        box = self.hulls[hull].in_world()
        reach = WAKE_REACH + WAKE_AHEAD_S * speed
        lo, hi = box.min(axis=0) - reach, box.max(axis=0) + reach
        ids, _, _, _ = self._in_space()
        w, tl = self.model.wide, self.tiles
        near_p, near_f = floes_near(ids, tl.template, tl.corner, tl.quarter_turns, self._sides, w.template_floes,
                                    w.box, lo[0], lo[1], hi[0], hi[1])
        out = []
        for p, f in zip(near_p.tolist(), near_f.tolist()):
            bodies = self._tiles[p]
            if f not in bodies.wide or bodies.wide[f][0] in self.compounds.live or bodies in self._entering:
                continue  # woken (if resting, see ``wake_resting``), or not all in the space yet
            rows = tl.row_start[p] + w.cells[w.cells_start[f]:w.cells_start[f + 1]]
            if np.any(state.status[rows] == FloeStatus.INTACT):
                out.append((p, f))
        return out

    def _set_dynamic(self, slot: int) -> None:
        """Make a floe's body dynamic with its slot's mass properties, its origin kept, at rest."""
        c = self.compounds
        body = body_at(c.live[slot])
        origin = lib.cpBodyGetPosition(body)
        lib.cpBodySetType(body, lib.CP_BODY_TYPE_DYNAMIC)  # its shapes move to the dynamic index
        lib.cpBodySetMass(body, float(c.mass[slot]))
        lib.cpBodySetMoment(body, float(c.moment[slot]))
        lib.cpBodySetCenterOfGravity(body, tuple(c.cog[slot].tolist()))
        lib.cpBodySetPosition(body, (origin.x, origin.y))

    def bond(self, state: FloeState, placement: int, floe: int) -> np.ndarray:
        """Wake a wide floe: its static body, holding its intact cells' shapes, turns
        dynamic, at rest, with their mass properties; returns their rows (the caller makes
        them FREE). Chipmunk moves the shapes from its static index to the dynamic one (a
        microsecond or two a shape; taking them out and making new ones cost 26 us a shape
        in the pack, most of it a walk over every contact for each static shape taken out)."""
        m, w = self.model, self.model.wide
        bodies, start = self._tiles[placement], int(self.tiles.row_start[placement])
        rows = start + w.cells[w.cells_start[floe]:w.cells_start[floe + 1]]
        rows = rows[state.status[rows] == FloeStatus.INTACT]
        offsets = rows - start
        bodies.bond_shape[offsets], bodies.intact[offsets] = bodies.intact[offsets], 0
        bodies.in_space[offsets] &= ~np.uint8(INTACT_IN)
        g, xy = state.gcell[rows], state.xy[rows]
        slot, ptr = bodies.wide[floe]
        c = self.compounds
        c.mass[slot], c.cog[slot], c.moment[slot] = _mass_properties(m.mass[g], m.inertia[g, 2], xy)
        c.radius[slot] = self._reach(g, xy, c.cog[slot])
        c.live[slot] = ptr
        self._set_dynamic(slot)
        state.bond_xy[rows], state.bond_yaw[rows], state.bonded[rows] = xy, state.yaw[rows], True
        state.bond_slot[rows] = slot
        state.vel[rows], state.yaw_rate[rows] = 0.0, 0.0
        return rows

    def unbond(self, state: FloeState, rows: np.ndarray) -> np.ndarray:
        """Take bonded rows' shapes off their floes' bodies (their rows keep the poses and
        velocities they had on it). A body left with no cell goes; one whose cells no longer
        hang together parts (``floe_parts``), and each keeps its cells' mass properties and
        its velocity field. Returns the rows of the cells that parting left alone, taken
        off their body too, for the caller to make floes of their own."""
        w, alone = self.model.wide, []
        for tile in np.unique(state.tile[rows]).tolist():
            bodies, start = self._tiles[tile], int(self.tiles.row_start[tile])
            mine = rows[state.tile[rows] == tile]
            self._take_off(state, bodies, start, mine)
            for slot in np.unique(state.bond_slot[mine]).tolist():
                self.stop_shedding(slot)  # its new rim collides (``compound_rest``)
                floe = int(self.compounds.floe[slot])
                left = start + w.cells[w.cells_start[floe]:w.cells_start[floe + 1]]
                left = left[state.bonded[left] & (state.bond_slot[left] == slot)]
                lone = self.part(state, bodies, slot, left) if len(left) else left
                self._take_off(state, bodies, start, lone)
                alone.append(lone)
                if len(lone) == len(left):  # no cell left on it
                    self._drop_body(bodies, slot)
        return np.concatenate(alone) if alone else rows[:0]

    def _take_off(self, state: FloeState, bodies: TileBodies, start: int, rows: np.ndarray) -> None:
        """Take bonded rows of a tile (its first row start) off their floes' bodies and free their shapes."""
        shapes = bodies.bond_shape[rows - start]
        bodies.drop_shapes(self._cp, shapes[shapes != 0])
        bodies.free_held(rows - start)
        bodies.bond_shape[rows - start] = 0
        state.bonded[rows] = False

    def _drop_body(self, bodies: TileBodies, slot: int) -> None:
        """Take a floe's body (by slot; its shapes gone) out of the space and free it."""
        c = self.compounds
        c.live.pop(slot)
        c.resting.discard(slot)
        floe = int(c.floe[slot])
        if floe in bodies.wide and bodies.wide[floe][0] == slot:
            bodies.drop_wide(self._cp, floe)
        else:
            bodies.drop_part(self._cp, slot)

    def _reach(self, g: np.ndarray, at: np.ndarray, cog: np.ndarray) -> float:
        """How far (m) cells g (n,) at (n, 2) m reach from a centre of mass cog (2,), m."""
        return float(np.hypot(*(at - cog).T).max() + self.extent[g].max())

    def _reweigh(self, state: FloeState, slot: int, rows: np.ndarray) -> None:
        """Give a floe's body (by slot) the mass properties and reach of its bonded rows,
        about their centre of mass, its origin, pose and velocity field kept (a resting
        body's slot only)."""
        m, body = self.model, body_at(int(self.compounds.body[slot]))
        g = state.gcell[rows]
        total, cog, moment = _mass_properties(m.mass[g], m.inertia[g, 2], state.bond_xy[rows])
        old_cog = self.compounds.cog[slot].copy()
        self.compounds.cog[slot], self.compounds.mass[slot], self.compounds.moment[slot] = cog, total, moment
        self.compounds.radius[slot] = self._reach(g, state.bond_xy[rows], cog)
        if slot in self.compounds.resting:  # static: ``_set_dynamic`` gives it these when it wakes
            return
        origin, angle = lib.cpBodyGetPosition(body), lib.cpBodyGetAngle(body)
        v, w = lib.cpBodyGetVelocity(body), lib.cpBodyGetAngularVelocity(body)
        dx, dy = cog - old_cog
        c, s = math.cos(angle), math.sin(angle)
        rx, ry = c * dx - s * dy, s * dx + c * dy  # the centre's shift, world
        lib.cpBodySetMass(body, total)
        lib.cpBodySetMoment(body, moment)
        lib.cpBodySetCenterOfGravity(body, tuple(cog.tolist()))
        lib.cpBodySetPosition(body, (origin.x, origin.y))  # the origin stays where it was
        lib.cpBodySetVelocity(body, (v.x - w * ry, v.y + w * rx))

    def push_back(self, state: FloeState, row: int, impulse: tuple[float, float], point: tuple[float, float]) -> None:
        """Apply an impulse (N s, world) at a point (m) to the body of a bonded row."""
        lib.cpBodyApplyImpulseAtWorldPoint(body_at(int(self.compounds.body[state.bond_slot[row]])), impulse, point)


@numba.njit(cache=True)
def scatter_bonded(ids, f, status, bonded, bond_slot, working, row_start, slot_p, slot_f, slot_cog, slot_velocity,
                   cells_start, cells, bond_xy, bond_yaw, xy, yaw, vel, yaw_rate):
    """Write the poses and velocities of the bonded rows of each wide floe's body (a row's
    body: its ``bond_slot``) among the bodies ids (n,) with poses and velocities f (n, 6:
    origin x, y m, angle rad, centre of mass velocity m/s, rad/s) into the arrays, and each
    body's velocity into its slot's (x, y m/s; rad/s); a body of a tile no longer worked is
    skipped."""
    for k in range(len(ids)):
        if ids[k] < BOND0:
            continue
        slot = ids[k] - BOND0
        p, fl = slot_p[slot], slot_f[slot]
        if p >= len(working) or not working[p]:
            continue
        c, s = math.cos(f[k, 2]), math.sin(f[k, 2])
        cx = f[k, 0] + c * slot_cog[slot, 0] - s * slot_cog[slot, 1]
        cy = f[k, 1] + s * slot_cog[slot, 0] + c * slot_cog[slot, 1]
        w = f[k, 5]
        slot_velocity[slot, 0], slot_velocity[slot, 1], slot_velocity[slot, 2] = f[k, 3], f[k, 4], w
        for e in range(cells_start[fl], cells_start[fl + 1]):
            i = row_start[p] + cells[e]
            if status[i] != 1 or not bonded[i] or bond_slot[i] != slot:
                continue
            x = f[k, 0] + c * bond_xy[i, 0] - s * bond_xy[i, 1]
            y = f[k, 1] + s * bond_xy[i, 0] + c * bond_xy[i, 1]
            xy[i, 0], xy[i, 1], yaw[i] = x, y, bond_yaw[i] + f[k, 2]
            vel[i, 0], vel[i, 1], yaw_rate[i] = f[k, 3] - w * (y - cy), f[k, 4] + w * (x - cx), w


@numba.njit(cache=True)
def bond_rows(ints, point, a, b, status, bonded, bond_slot, working, template, corner, turns, row_start, sides, slot_p,
              slot_f, pose, floe_of, bucket0, per_side, size, first, entries, seeds, g0):
    """Fill in the rows (a, b; k,) of the contacts (ints (k, 3): body ids and contact count;
    points (k, 2) m) on wide floes' bodies: the floe's intact or bonded cell with the
    Voronoi seed nearest the point (as ``contact_kernels.contact_rows`` names intact cells;
    the point, carried back by the body's motion (``pose``, ``CompoundSlots``) to where the
    floe lay when it woke, lies in its template as the tile lays it); NOT_A_FLOE on a body
    of a tile no longer worked, with no point this step, or where that cell is bonded to
    another body (``bond_slot``: a part of the floe that parted, ``floe_parts``)."""
    for k in range(ints.shape[0]):
        for side in range(2):
            code = np.int64(ints[k, side])
            if code < BOND0:
                continue
            row = NOT_A_FLOE
            slot = code - BOND0
            p = slot_p[slot]
            if ints[k, 2] > 0 and p < len(working) and working[p]:
                c, s = math.cos(pose[slot, 2]), math.sin(pose[slot, 2])
                dx, dy = point[k, 0] - pose[slot, 0], point[k, 1] - pose[slot, 1]
                qx, qy = template_point(c * dx + s * dy, -s * dx + c * dy, p, template, corner, turns, sides)
                row = nearest_cell(qx, qy, template[p], row_start[p], status, bonded, floe_of, slot_f[slot],
                                   bucket0, per_side, size, first, entries, seeds, g0)
                row = NOT_A_FLOE if row < 0 or (bonded[row] and bond_slot[row] != slot) else row
            if side == 0:
                a[k] = row
            else:
                b[k] = row


@numba.njit(cache=True)
def hull_breaks(a, b, impulse, normal, point, bonded, vel, gcell, bond_slot, body_mass, k_impact, edge_capacity,
                plan_area, hull_xy, hull_vel, hull_w):
    """Of the contacts (rows a, b; impulse on a, N s; unit normal from a to b; point, m)
    between a hull and a bonded row, those that break the row: J v_n >= K
    (``breaking.pushed_hard``), v_n the larger of the hull's approach speed (m/s) to the
    row's cell at the point (from the hulls' reference points (h, 2) m, velocities (h, 2)
    m/s and yaw rates (h,) rad/s, and the rows' velocities before the step) and J / M, the
    speed the contact gave the floe's body (its mass M, kg, by slot): the hull, of no finite
    mass, loses none. Returns the contacts and the share of each one's impulse the breaking
    edge passed on: F_s d / (v_n J), at most 1 (F_s the cell's edge capacity, N; d the
    square root of its plan area, m2)."""
    out, share = np.empty(len(a), np.int64), np.empty(len(a))
    n = 0
    for k in range(len(a)):
        if LOWEST_ROW <= a[k] <= HULL_ROW0 and b[k] >= 0 and bonded[b[k]]:
            hull, row, sign = HULL_ROW0 - a[k], b[k], 1.0
        elif LOWEST_ROW <= b[k] <= HULL_ROW0 and a[k] >= 0 and bonded[a[k]]:
            hull, row, sign = HULL_ROW0 - b[k], a[k], -1.0
        else:
            continue
        tx, ty = sign * normal[k, 0], sign * normal[k, 1]  # from the hull to the cell
        rx, ry = point[k, 0] - hull_xy[hull, 0], point[k, 1] - hull_xy[hull, 1]
        ux = hull_vel[hull, 0] - hull_w[hull] * ry - vel[row, 0]
        uy = hull_vel[hull, 1] + hull_w[hull] * rx - vel[row, 1]
        j, m, g = math.sqrt(impulse[k, 0] ** 2 + impulse[k, 1] ** 2), body_mass[bond_slot[row]], gcell[row]
        v_n = max(ux * tx + uy * ty, 0.0)
        if pushed_hard(j, v_n, m, k_impact[g]):
            out[n] = k
            share[n] = min(1.0, edge_capacity[g] * math.sqrt(plan_area[g]) / (max(v_n, j / m) * j))
            n += 1
    return out[:n], share[:n]


def struck_off(space: CompoundFloes, state: FloeState, con: Contacts, hull_xy: np.ndarray, hull_vel: np.ndarray,
               hull_w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bonded rows the hulls (reference points (h, 2) m, velocities (h, 2) m/s, yaw
    rates (h,) rad/s) broke off their floes in the last step (``hull_breaks``; the rows'
    velocities still those before it), and the hull that broke each. Each broken contact's
    impulse beyond what the edge passed on goes back to the floe's body, and the contact
    keeps only that share (the hull's load)."""
    m = space.model
    hits, share = hull_breaks(con.a, con.b, con.impulse, con.normal, con.point, state.bonded, state.vel, state.gcell,
                              state.bond_slot, space.compounds.mass, m.k_impact, m.edge_capacity, m.plan_area, hull_xy,
                              hull_vel, hull_w)
    hull_is_a = con.a[hits] < 0
    rows = np.where(hull_is_a, con.b[hits], con.a[hits])
    hulls = HULL_ROW0 - np.where(hull_is_a, con.a[hits], con.b[hits])
    order = np.lexsort((hulls, rows))  # the engine lists contacts in a run-dependent order; the impulses add up in this
    rows, hulls, hull_is_a, hits, share = rows[order], hulls[order], hull_is_a[order], hits[order], share[order]
    for row, on_a, k, keep in zip(rows.tolist(), hull_is_a.tolist(), hits.tolist(), share.tolist()):
        on_cell = -con.impulse[k] if on_a else con.impulse[k]
        space.push_back(state, row, tuple((-(1.0 - keep) * on_cell).tolist()), tuple(con.point[k].tolist()))
        con.impulse[k] *= keep
    return rows, hulls


def warm_up() -> None:
    """Load the compiled kernels of this module (numba compiles or loads on first call)."""
    none, flags = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.bool_)
    status, f32 = none.astype(np.uint8), np.zeros((0, 2), np.float32)
    scatter_bonded(none.astype(np.uintp), np.zeros((0, 6)), status, flags, none.astype(np.int32), status, none, none,
                   none, np.zeros((0, 2)),
                   np.zeros((0, 3)), np.zeros(1, np.int64), none, np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)),
                   np.zeros(0), f32,
                   np.zeros(0, np.float32))
    bond_rows(np.zeros((0, 3), np.uintp), np.zeros((0, 2)), none, none, status, flags, none.astype(np.int32), status,
              none, np.zeros((0, 2)), none, none, np.ones(1), none, none, np.zeros((0, 3)), none, none, none,
              np.ones(1), none, none, np.zeros((0, 2)), none)
    hull_breaks(none, none, np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2)), flags, f32, none.astype(np.int32),
                none.astype(np.int32), np.ones(1), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros((1, 2)),
                np.zeros((1, 2)), np.zeros(1))
    floes_near(none, none, np.zeros((0, 2)), none, np.ones(1), np.zeros(2, np.int64), np.zeros((0, 4)), 0.0, 0.0,
               1.0, 1.0)
