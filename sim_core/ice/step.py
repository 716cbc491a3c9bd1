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

import numpy as np

from sim_core.ice import contact
from sim_core.ice import vertical
from sim_core.ice.breaking import breaks
from sim_core.ice.contact import Contacts
from sim_core.ice.floes import BreakCause, FloeState, FloeStatus
from sim_core.ice.model import IceModel, vertical_substeps
from sim_core.ice.tiles import IceData, break_cells
from sim_core.ice.vertical import vertical_step

_SETTLED = 1e-7  # m, rad, m/s, rad/s: a floe this close to rest at its draft is left alone
_PUSHED_DOWN_TILT = 0.25  # rad: roll of a floe the bow has turned under
_CLEAR_AHEAD = 10.0  # m ahead of the stem: a submerged floe there is no longer held down


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


def _contact_breaks(model: IceModel, st: FloeState, con: Contacts, velocity: np.ndarray) -> np.ndarray:
    """Intact rows whose contact with a free floe exceeded their capacity this step."""
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
    hit = breaks(impulse, v_n, model.mass[st.gcell[striker]], model.k_impact[st.gcell[target]])
    return np.unique(target[hit])


def _hull_load(impulse: np.ndarray, point: np.ndarray, hull: HullMotion, dt: float) -> tuple[np.ndarray, float]:
    """Force (N, world) and moment (N m, CCW about the hull's reference point) of the hull's
    contact impulses (N s) at points (m) over dt (s)."""
    force = impulse / dt
    arm = point - hull.xy
    return force.sum(axis=0), float((arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0]).sum())


def hull_frame(points: np.ndarray, hull: HullMotion) -> np.ndarray:
    """World points (n, 2) in the hull's body frame (x forward, y to port), m."""
    c, s = math.cos(hull.angle), math.sin(hull.angle)
    d = points - hull.xy
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


def inside_outline(points: np.ndarray, outline: np.ndarray) -> np.ndarray:
    """Points (n, 2) inside a convex counter-clockwise outline (m, 2), same frame."""
    edge = np.roll(outline, -1, axis=0) - outline
    rel = points[:, None, :] - outline[None, :, :]
    return np.all(edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0] >= 0.0, axis=1)


def _update_submersion(model: IceModel, data: IceData, hull: HullMotion, struck: np.ndarray) -> None:
    """Struck floes with their centre inside the beam go under, held a thickness down and
    tilted by the hull; a submerged floe surfaces once the hull no longer covers it (its
    centre outside the waterline, and aft of midship, beyond the beam lines, or clear
    ahead of the stem because the ship stopped or backed), and buoyancy brings it back
    up and rights it."""
    st, space = data.state, data.contacts
    beam_half = space.hull_half_beam
    if len(struck):
        struck = struck[(st.status[struck] == FloeStatus.FREE) & ~st.submerged[struck]]
        under = struck[np.abs(hull_frame(st.xy[struck], hull)[:, 1]) < beam_half]
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
        local = hull_frame(st.xy[down], hull)
        stem = space.hull_outline[:, 0].max()
        passed = (local[:, 0] < 0.0) | (np.abs(local[:, 1]) >= beam_half) | (local[:, 0] > stem + _CLEAR_AHEAD)
        up = down[passed & ~inside_outline(local, space.hull_outline)]
        st.submerged[up] = False
        space.set_submerged(st, up, False)


def _unsettled(model: IceModel, st: FloeState, rows: np.ndarray) -> np.ndarray:
    """Rows not yet at rest at their floating draft. In-plane contact does not couple into
    heave, roll or pitch, so a settled floe stays settled and needs no vertical update."""
    off = np.abs(st.heave[rows] - model.z_equilibrium[st.gcell[rows]]) + np.abs(st.roll[rows]) + np.abs(st.pitch[rows])
    rates = np.abs(st.heave_rate[rows]) + np.abs(st.roll_rate[rows]) + np.abs(st.pitch_rate[rows])
    return rows[(off > _SETTLED) | (rates > _SETTLED)]


def ice_step(model: IceModel, data: IceData, hull: HullMotion, dt: float) -> IceStepReport:
    """Advance the breakable ice by dt seconds with the hull moving as given."""
    st, space = data.state, data.contacts
    space.set_hull(hull.xy, hull.angle, hull.velocity, hull.angular_velocity)
    by_hull = space.hull_touching(st)
    if len(by_hull):
        break_cells(data, by_hull, BreakCause.HULL)
        _update_submersion(model, data, hull, by_hull)
    space.step(dt)
    con = space.read_contacts(st)
    by_contact = _contact_breaks(model, st, con, st.vel)  # st.vel still holds pre-step velocities
    space.read_free(st)
    if len(by_contact):
        break_cells(data, by_contact, BreakCause.CONTACT)
    free = _unsettled(model, st, np.nonzero((st.status == FloeStatus.FREE) & ~st.submerged)[0])
    if len(free):
        mat = model.material
        vertical_step(free, st.gcell, model.tris, model.tri_start, model.mass, model.inertia, model.damping,
                      model.settings.heave_added_mass, mat.water_density * mat.gravity, mat.gravity,
                      st.heave, st.roll, st.pitch, st.heave_rate, st.roll_rate, st.pitch_rate,
                      dt, vertical_substeps(model, dt))
    struck, impulse, point = con.with_hull()
    _update_submersion(model, data, hull, struck[struck >= 0])
    force, moment = _hull_load(impulse, point, hull, dt)
    return IceStepReport(by_hull, by_contact, force, moment)


def warm_up(model: IceModel, data: IceData) -> None:
    """Load every compiled kernel the ice step uses, so that no step waits for a compile."""
    contact.warm_up()
    vertical.warm_up(model.tris, model.tri_start, model.mass, model.inertia, model.damping)

