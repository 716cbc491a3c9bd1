"""One step of the breakable ice: hull contact, conduction cracking, floating floes.

``ice_step(model, data, hull, dt)`` runs, in order: the hull breaks the intact cells it
touches; the contact engine steps (hull pushes floes, floes push each other and load the
intact edge); contacts that exceed an intact cell's capacity break it free; the free
floes' pose and velocity come back into the arrays; their heave, roll and pitch follow the
buoyancy. It returns the cells broken and the contact load on the hull.

Submersion: a planar model cannot let broken ice go under the bow, so without help the
hull bulldozes every piece ahead of it into the level ice and the push runs through the
whole field. Real icebreaking bends the ice down: the pieces turn and slide under the hull,
which is Lindqvist's submersion term. So a floe the hull strikes with its centre inside the
hull's beam goes under the hull. It leaves planar contact until the hull has passed over
it, then it surfaces in the channel. Floes at the edge of the path stay in
contact and are pushed aside, and those pushes crack the channel edge.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from sim_core.ice import contact, resting
from sim_core.ice import vertical
from sim_core.ice.breaking import pushed_hard
from sim_core.ice.contact import Contacts
from sim_core.ice.floes import BreakCause, FloeState, FloeStatus
from sim_core.ice.model import IceModel, vertical_substeps
from sim_core.ice.tiles import IceData, break_cells
from sim_core.ice.vertical import settled, vertical_step

_PUSHED_DOWN_TILT = 0.25  # rad: roll of a floe the bow has turned under
_CLEAR_AHEAD = 10.0  # m ahead of the stem: a submerged floe there is no longer held down
_BESIDE = 5.0  # m beyond the beam lines: a submerged floe there is no longer pressed by the hull
_NO_ROWS = np.zeros(0, dtype=np.int64)


@dataclass
class HullMotion:
    """The hull's planar pose and velocity in the ice world (x east, y north, CCW angles)."""

    xy: np.ndarray  # reference point (midship), m
    angle: float  # rad, CCW from east
    velocity: np.ndarray  # m/s
    angular_velocity: float  # rad/s, CCW


@dataclass
class IceStepReport:
    """What one ice step did. Forces in the world frame; moment CCW about the hull point."""

    broken_by_hull: np.ndarray
    broken_by_contact: np.ndarray
    hull_force: np.ndarray  # N
    hull_moment: float  # N m


def _contact_breaks(model: IceModel, st: FloeState, con: Contacts,
                    velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Intact rows whose contact with a free floe broke them this step (the energy it
    brought and the load its striker can put on the edge, ``breaking.breaks``), and the free
    floes pushed hard against an edge they cannot break: jammed, they go under it."""
    valid = (con.a >= 0) & (con.b >= 0)
    a, b, imp, nrm = con.a[valid], con.b[valid], con.impulse[valid], con.normal[valid]
    sa, sb = st.status[a], st.status[b]
    a_hits_b = (sa == FloeStatus.FREE) & (sb == FloeStatus.INTACT)
    b_hits_a = (sb == FloeStatus.FREE) & (sa == FloeStatus.INTACT)
    target = np.concatenate([b[a_hits_b], a[b_hits_a]])
    striker = np.concatenate([a[a_hits_b], b[b_hits_a]])
    toward = np.concatenate([nrm[a_hits_b], -nrm[b_hits_a]])  # unit normal from striker to target
    impulse = np.linalg.norm(np.concatenate([imp[a_hits_b], imp[b_hits_a]]), axis=1)
    v_n = np.maximum((velocity[striker] * toward).sum(axis=1), 0.0)
    gs, gt = st.gcell[striker], st.gcell[target]
    hard = pushed_hard(impulse, v_n, model.mass[gs], model.k_impact[gt])
    loads = model.ride_load[gs] >= model.edge_capacity[gt]
    broken = np.unique(target[hard & loads])
    return broken, np.setdiff1d(striker[hard & ~loads], striker[hard & loads])


def _hull_load(impulse: np.ndarray, point: np.ndarray, hull: HullMotion, dt: float) -> tuple[np.ndarray, float]:
    """Force (N, world) and moment (N m, CCW about the hull's reference point) of the hull's
    contact impulses (N s) at points (m) over dt (s). Summed exactly rounded (``math.fsum``):
    the engine lists contacts in a run-dependent order, and a sum that depended on it would
    make reruns of the same orders drift apart, through the ship, by whole cells."""
    force = impulse / dt
    arm = point - hull.xy
    moment = math.fsum(np.concatenate([arm[:, 0] * force[:, 1], -arm[:, 1] * force[:, 0]]).tolist())
    return np.array([math.fsum(force[:, 0].tolist()), math.fsum(force[:, 1].tolist())]), moment


def hull_frame(points: np.ndarray, hull: HullMotion) -> np.ndarray:
    """World points (n, 2) in the hull's body frame (x forward, y to port), m."""
    c, s = math.cos(hull.angle), math.sin(hull.angle)
    d = points - hull.xy
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


@numba.njit(cache=True)
def _surfacing(down, xy, hull_xy, c, s, outline, reach, stem, clear_ahead):
    """Of submerged rows, those the hull has passed: centre outside the hull's convex CCW
    outline (body frame, m) and aft of midship, farther than reach (m) from the centre
    line, or clear ahead of the stem (m)."""
    out = np.zeros(len(down), np.bool_)
    n = outline.shape[0]
    for k in range(len(down)):
        i = down[k]
        dx, dy = xy[i, 0] - hull_xy[0], xy[i, 1] - hull_xy[1]
        u, v = c * dx + s * dy, -s * dx + c * dy
        if not (u < 0.0 or abs(v) >= reach or u > stem + clear_ahead):
            continue
        inside = True
        for e in range(n):
            ex, ey = outline[(e + 1) % n, 0] - outline[e, 0], outline[(e + 1) % n, 1] - outline[e, 1]
            if ex * (v - outline[e, 1]) - ey * (u - outline[e, 0]) < 0.0:
                inside = False
                break
        out[k] = not inside
    return out


@numba.njit(cache=True)
def _unsettled_free(status, submerged, gcell, z_equilibrium, heave, roll, pitch, heave_rate, roll_rate, pitch_rate):
    """Free rows above water not yet at rest at their floating draft (``vertical.settled``):
    a settled floe needs no vertical update."""
    out = np.empty(len(status), np.int64)
    n = 0
    for i in range(len(status)):
        if status[i] != 1 or submerged[i]:
            continue
        if not settled(i, gcell, z_equilibrium, heave, roll, pitch, heave_rate, roll_rate, pitch_rate):
            out[n] = i
            n += 1
    return out[:n]


def _update_submersion(model: IceModel, data: IceData, hull: HullMotion, struck: np.ndarray,
                       jammed: np.ndarray = _NO_ROWS) -> None:
    """Struck floes with their centre inside the beam, and floes jammed against an edge
    they cannot break, go under, held a thickness down and tilted; a submerged floe
    surfaces once the hull no longer covers or presses it (its centre outside the
    waterline, and aft of midship, more than _BESIDE beyond the beam lines, or clear ahead
    of the stem because the ship stopped or backed), and buoyancy brings it back up and
    rights it."""
    st, space = data.state, data.contacts
    beam_half = space.hull_half_beam
    if len(struck) or len(jammed):
        under = struck[np.abs(hull_frame(st.xy[struck], hull)[:, 1]) < beam_half]
        under = np.union1d(under, jammed)
        under = under[(st.status[under] == FloeStatus.FREE) & ~st.submerged[under]]
        st.submerged[under] = True
        space.set_submerged(st, under, True)
        g = st.gcell[under]
        st.heave[under] = model.z_equilibrium[g] - model.thickness[g]
        st.roll[under] = _PUSHED_DOWN_TILT
        st.heave_rate[under] = st.roll_rate[under] = st.pitch_rate[under] = 0.0
        st.vel[under] = 0.0
        st.yaw_rate[under] = 0.0
    down = np.nonzero(st.submerged)[0]
    if len(down):
        up = down[_surfacing(down, st.xy, hull.xy, math.cos(hull.angle), math.sin(hull.angle), space.hull_outline,
                             beam_half + _BESIDE, float(space.hull_outline[:, 0].max()), _CLEAR_AHEAD)]
        st.submerged[up] = False
        space.set_submerged(st, up, False)


def ice_step(model: IceModel, data: IceData, hull: HullMotion, dt: float) -> IceStepReport:
    """Advance the breakable ice by dt seconds with the hull moving as given."""
    st, space = data.state, data.contacts
    rest = model.settings.rest_far_floes
    space.set_hull(hull.xy, hull.angle, hull.velocity, hull.angular_velocity)
    if rest:
        resting.wake_near_hull(model, data, hull.xy)
    by_hull = space.hull_touching(st)
    if len(by_hull):
        break_cells(data, by_hull, BreakCause.HULL)
        _update_submersion(model, data, hull, by_hull)
    space.step(dt)
    con = space.read_contacts(st)
    by_contact, jammed = _contact_breaks(model, st, con, st.vel)  # st.vel still holds pre-step velocities
    moving = space.read_free(st)
    if len(by_contact):
        break_cells(data, by_contact, BreakCause.CONTACT)
    free = _unsettled_free(st.status, st.submerged, st.gcell, model.z_equilibrium, st.heave, st.roll, st.pitch,
                           st.heave_rate, st.roll_rate, st.pitch_rate)
    if len(free):
        mat = model.material
        vertical_step(free, st.gcell, model.tris, model.tri_start, model.mass, model.inertia, model.damping,
                      model.settings.heave_added_mass, mat.water_density * mat.gravity, mat.gravity,
                      st.heave, st.roll, st.pitch, st.heave_rate, st.roll_rate, st.pitch_rate,
                      dt, vertical_substeps(model, dt))
    struck, impulse, point = con.with_hull()
    _update_submersion(model, data, hull, struck[struck >= 0], jammed)
    if rest:
        resting.wake_struck(model, data, con)
        resting.rest_far(model, data, moving, hull.xy, dt)
    force, moment = _hull_load(impulse, point, hull, dt)
    return IceStepReport(by_hull, by_contact, force, moment)


def warm_up(model: IceModel, data: IceData) -> None:
    """Load every compiled kernel the ice step uses, so that no step waits for a compile."""
    contact.warm_up()
    resting.warm_up(model)
    none, f32 = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.float32)
    _surfacing(none, np.zeros((0, 2)), np.zeros(2), 1.0, 0.0, data.contacts.hull_outline, 1.0, 1.0, 1.0)
    _unsettled_free(none.astype(np.uint8), none.astype(np.bool_), none.astype(np.int32), model.z_equilibrium,
                    f32, f32, f32, f32, f32, f32)
    vertical.warm_up(model.tris, model.tri_start, model.mass, model.inertia, model.damping)

