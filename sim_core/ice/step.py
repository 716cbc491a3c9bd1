"""One step of the breakable ice: hull contact, conduction cracking, floating floes.

``ice_step(model, data, hulls, dt)`` runs, in order: each hull (one per ship, all in one
contact space) breaks the intact cells it touches, and cracks the level ice about them
(``sim_core.ice.bending``); the contact engine steps (hulls push floes, floes push each
other and load the intact edge); contacts that exceed an intact cell's capacity break it
free; the free floes' pose and velocity come back into the arrays; their heave, roll and
pitch follow the buoyancy. It returns the cells broken and cracked, and the contact load
on each hull. A ship that follows another meets the channel the first one broke, since
both hulls work on the same floes.

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
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numba
import numpy as np

from sim_core.ice import compound_floes, contact_kernels, floe_parts, resting, turning
from sim_core.ice.bending import crack_ahead
from sim_core.ice import vertical
from sim_core.ice.breaking import pushed_hard
from sim_core.ice.contact_kernels import Contacts
from sim_core.ice.floes import BreakCause, FloeState, FloeStatus
from sim_core.ice.model import IceModel, vertical_substeps
from sim_core.ice.tiles import IceData, break_cells
from sim_core.ice.vertical import settled, vertical_step
from sim_core.ice.wash import drag_in_wash

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
    surface_angle: float = 0.0  # rad: the bow's normal angle psi, against which struck pieces turn before they
    # go under (sim_core.ice.turning); 0: they go under at once
    surface_advance: float = 1.0  # the hull's surface at the bow moves across the waterline, towards a piece,
    # by this share of the ship's advance: sin of the waterline angle alpha


@dataclass
class IceStepReport:
    """What one ice step did. Forces in the world frame; moments CCW about each hull's
    reference point; by hull index."""

    broken_by_hull: np.ndarray
    broken_by_contact: np.ndarray
    cracked: np.ndarray  # rows of intact cells cracked (sim_core.ice.bending)
    hull_force: np.ndarray  # (h, 2) N, each hull's
    hull_moment: np.ndarray  # (h,) N m, each hull's
    hull_broke: np.ndarray  # (h,) int: intact cells each hull broke


@numba.njit(cache=True)
def _hard_pushes(a, b, impulse, normal, status, bonded, velocity, gcell, mass, k_impact, ride_load, edge_capacity):
    """Of contacts between a free floe (striker) and an intact or bonded cell (target; a
    bonded striker is a wide floe's body, ``compound_floes``, and breaks nothing): the targets
    broken (pushed hard, ``breaking.pushed_hard``, by a striker whose ride-up load reaches
    the edge's capacity), and the strikers pushed hard that could break nothing; both sorted,
    each row once."""
    broken, strong, weak = np.empty(len(a), np.int64), np.empty(len(a), np.int64), np.empty(len(a), np.int64)
    nb = ns = nw = 0
    for k in range(len(a)):
        if a[k] < 0 or b[k] < 0:
            continue
        if status[a[k]] == 1 and not bonded[a[k]] and (status[b[k]] == 0 or bonded[b[k]]):
            striker, target, sign = a[k], b[k], 1.0
        elif status[b[k]] == 1 and not bonded[b[k]] and (status[a[k]] == 0 or bonded[a[k]]):
            striker, target, sign = b[k], a[k], -1.0
        else:
            continue
        tx, ty = sign * normal[k, 0], sign * normal[k, 1]  # unit normal from striker to target
        j = math.sqrt(impulse[k, 0] * impulse[k, 0] + impulse[k, 1] * impulse[k, 1])
        v_n = max(np.float64(velocity[striker, 0]) * tx + np.float64(velocity[striker, 1]) * ty, 0.0)
        gs, gt = gcell[striker], gcell[target]
        if not pushed_hard(j, v_n, mass[gs], k_impact[gt]):
            continue
        if ride_load[gs] >= edge_capacity[gt]:
            broken[nb], strong[ns] = target, striker
            nb, ns = nb + 1, ns + 1
        else:
            weak[nw] = striker
            nw += 1
    strong, weak = np.unique(strong[:ns]), np.unique(weak[:nw])
    keep = np.ones(len(weak), np.bool_)  # weak strikers that broke nothing elsewhere: both sorted, a merge
    j = 0
    for k in range(len(weak)):
        while j < len(strong) and strong[j] < weak[k]:
            j += 1
        keep[k] = j == len(strong) or strong[j] != weak[k]
    return np.unique(broken[:nb]), weak[keep]


def _contact_breaks(model: IceModel, st: FloeState, con: Contacts,
                    velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Intact rows whose contact with a free floe broke them this step (the energy it
    brought and the load its striker can put on the edge, ``breaking.breaks``), and the free
    floes pushed hard against an edge they cannot break: jammed, they go under it."""
    return _hard_pushes(con.a, con.b, con.impulse, con.normal, st.status, st.bonded, velocity, st.gcell, model.mass,
                        model.k_impact, model.ride_load, model.edge_capacity)


@numba.njit(cache=True)
def _hull_load(rows, impulse, point, hull_xy, dt):
    """Force (N, world; fx, fy) and moment (N m, CCW about the hull's reference point
    hull_xy) of the hull's contact impulses (k, 2; N s) at points (k, 2; m) over dt (s),
    summed in the order of the struck rows (k,), each struck once: the engine lists
    contacts in a run-dependent order, and a sum that depended on it would make reruns of
    the same orders drift apart, through the ship, by whole cells."""
    fx = fy = moment = 0.0
    for k in np.argsort(rows):
        jx, jy = impulse[k, 0] / dt, impulse[k, 1] / dt
        moment += (point[k, 0] - hull_xy[0]) * jy - (point[k, 1] - hull_xy[1]) * jx
        fx += jx
        fy += jy
    return fx, fy, moment


@numba.njit(cache=True)
def _going_under(struck, jammed, status, submerged, bonded, xy, hull_xy, c, s, beam_half):
    """Free rows above water, not bonded to a wide floe's body, to send under: struck by
    the hull with their centre within beam_half (m) of its centre line (heading c, s = cos,
    sin of its CCW angle), or jammed."""
    rows = np.empty(len(struck) + len(jammed), np.int64)
    n = 0
    for i in struck:
        if abs(-s * (xy[i, 0] - hull_xy[0]) + c * (xy[i, 1] - hull_xy[1])) < beam_half:
            rows[n] = i
            n += 1
    for i in jammed:
        rows[n] = i
        n += 1
    rows = np.unique(rows[:n])
    keep = np.zeros(len(rows), np.bool_)
    for k in range(len(rows)):
        keep[k] = status[rows[k]] == 1 and not submerged[rows[k]] and not bonded[rows[k]]
    return rows[keep]


@numba.njit(cache=True)
def _hull_passed(rows, xy, hull_xy, c, s, outline, reach, stem, clear_ahead):
    """Which rows (a flag each) the hull no longer covers or presses: centre outside its
    convex CCW outline (body frame, m) and aft of midship, farther than reach (m) from the
    centre line, or clear ahead of the stem (m)."""
    out = np.zeros(len(rows), np.bool_)
    n = outline.shape[0]
    for k in range(len(rows)):
        i = rows[k]
        dx, dy = xy[i, 0] - hull_xy[0], xy[i, 1] - hull_xy[1]
        u, v = c * dx + s * dy, -s * dx + c * dy
        if not (u < 0.0 or abs(v) >= reach or u > stem + clear_ahead):
            continue
        for e in range(n):
            ex, ey = outline[(e + 1) % n, 0] - outline[e, 0], outline[(e + 1) % n, 1] - outline[e, 1]
            if ex * (v - outline[e, 1]) - ey * (u - outline[e, 0]) < 0.0:
                out[k] = True  # outside the outline
                break
    return out


@numba.njit(cache=True)
def _unsettled(rows, submerged, gcell, z_equilibrium, heave, roll, pitch, heave_rate, roll_rate, pitch_rate):
    """Of free rows in the dynamic set, those above water not yet at rest at their floating
    draft (``vertical.settled``): a settled floe needs no vertical update. (Floes outside
    the dynamic set need none: a resting one came to rest settled and nothing moves it
    vertically, a cell broken by contact this step lay settled in the level ice, and a
    thawed floe waits for its body to enter the space.)"""
    out = np.empty(len(rows), np.int64)
    n = 0
    for i in rows:
        if submerged[i]:
            continue
        if not settled(i, gcell, z_equilibrium, heave, roll, pitch, heave_rate, roll_rate, pitch_rate):
            out[n] = i
            n += 1
    return out[:n]


def _update_submersion(model: IceModel, data: IceData, k: int, hull: HullMotion, struck: np.ndarray,
                       jammed: np.ndarray = _NO_ROWS) -> None:
    """Struck floes with their centre inside the beam, and floes jammed against an edge
    they cannot break, go under: struck ones first turn against the bow (``turning``, where
    the hull has a surface angle), the others are at once held a thickness down and tilted;
    a submerged floe surfaces once the hull no longer covers or presses it (its centre
    outside the waterline, and aft of midship, more than _BESIDE beyond the beam lines, or
    clear ahead of the stem because the ship stopped or backed), and buoyancy brings it back
    up and rights it. A floe the hull has so passed stays afloat, struck or jammed: sent
    under, it came up in the same step, pinned (its velocity zeroed) and dropped a thickness
    every step it stayed so (in a jam: about 19 sendings under a step, mostly beside the hull).
    ``k``: the hull's index, whose motion is ``hull``."""
    st, space, body, rows = data.state, data.contacts, data.contacts.hulls[k], data.hulls[k]
    c, s = math.cos(hull.angle), math.sin(hull.angle)
    cover = (st.xy, hull.xy, c, s, body.outline, body.half_beam + _BESIDE, body.stem, _CLEAR_AHEAD)
    under = _going_under(struck, jammed, st.status, st.submerged, st.bonded, st.xy, hull.xy, c, s, body.half_beam) \
        if len(struck) or len(jammed) else _NO_ROWS
    under = under[~_hull_passed(under, *cover)]
    if len(under):
        rows.went_under = np.concatenate([rows.went_under[st.submerged[rows.went_under]], under])
        st.submerged[under] = True
        space.set_submerged(st, under, True)
        st.heave_rate[under] = st.roll_rate[under] = st.pitch_rate[under] = 0.0
        st.vel[under] = 0.0
        st.yaw_rate[under] = 0.0
        turns = under[np.isin(under, struck)] if hull.surface_angle > 0.0 else _NO_ROWS
        turning.start_turns(turns, st.xy, st.turn, st.turn_dir, model.plan_area, st.gcell, hull.xy, c, s,
                            body.stem)
        at_once = under[st.turn[under] <= 0.0]
        g = st.gcell[at_once]
        st.heave[at_once] = model.z_equilibrium[g] - model.thickness[g]
        st.roll[at_once] = turning.PUSHED_DOWN_TILT
    went = rows.went_under[st.submerged[rows.went_under]]
    up = went[_hull_passed(went, *cover)]
    if len(up):
        st.submerged[up] = False
        st.turn[up] = 0.0
        rows.went_under = rows.went_under[st.submerged[rows.went_under]]
        space.set_submerged(st, up, False)


def _advance_turns(model: IceModel, data: IceData, k: int, hull: HullMotion, dt: float) -> None:
    """Turn the pieces turning against the k-th hull's bow by its advance over the step."""
    went_under = data.hulls[k].went_under
    if hull.surface_angle <= 0.0 or not len(went_under):
        return
    st = data.state
    ahead = float(hull.velocity[0] * math.cos(hull.angle) + hull.velocity[1] * math.sin(hull.angle))
    advance = max(0.0, ahead) * hull.surface_advance * dt  # the surface's, across the waterline
    turning.advance_turns(went_under, st.submerged, st.turn, st.turn_dir, model.plan_area, st.gcell,
                          model.z_equilibrium, model.thickness, st.yaw, st.heave, st.roll, st.pitch, advance,
                          hull.surface_angle)


def _laid_under_hull(model: IceModel, data: IceData, k: int, hull: HullMotion) -> None:
    """What a tile switch laid under the k-th hull (its ship lying in the ice where an exercise
    starts or it was moved) goes under it, as if pushed down: the intact cells broken first,
    by no load of the bow (``BreakCause.NONE``: no crack patterns, no breaking counted).
    The bow breaking them in the first steps cost a crack pattern each: 23 and 32 ms of
    the first two ticks (74 and 148 cells) at the start of the pack-ice exercise."""
    laid = data.hulls[k].laid_under
    intact = laid[data.state.status[laid] == FloeStatus.INTACT]
    if len(intact):
        break_cells(data, intact, BreakCause.NONE)
    _update_submersion(model, data, k, hull, _NO_ROWS, laid)
    data.hulls[k].laid_under = _NO_ROWS


def _hulls_break(model: IceModel, data: IceData,
                 hulls: Sequence[HullMotion]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each hull breaks the intact cells it touches and cracks the level ice about them;
    what it struck goes under it. Returns the rows broken by the hulls and cracked (sorted),
    and how many each hull broke."""
    st, space = data.state, data.contacts
    broken, cracked, counts = [], [], np.zeros(len(hulls), dtype=np.int64)
    for k, hull in enumerate(hulls):
        if len(data.hulls[k].laid_under):
            _laid_under_hull(model, data, k, hull)
        by_hull = space.hull_touching(st, k)
        if len(by_hull):
            break_cells(data, by_hull, BreakCause.HULL)
            _update_submersion(model, data, k, hull, by_hull)
            cracked.append(crack_ahead(model, st, data.tiles, by_hull, np.asarray(hull.xy, dtype=float), hull.angle,
                                       space.hulls[k].outline))
            broken.append(by_hull)
            counts[k] = len(by_hull)
    return _union(broken), _union(cracked), counts


def _union(parts: list[np.ndarray]) -> np.ndarray:
    """The sorted union of sorted row arrays (each already free of repeats)."""
    if len(parts) <= 1:
        return parts[0] if parts else _NO_ROWS
    return np.unique(np.concatenate(parts))


def _hull_motions(hulls: Sequence[HullMotion]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hulls' reference points (h, 2) m, velocities (h, 2) m/s and yaw rates (h,) rad/s."""
    return (np.array([h.xy for h in hulls], dtype=float).reshape(-1, 2),
            np.array([h.velocity for h in hulls], dtype=float).reshape(-1, 2),
            np.array([h.angular_velocity for h in hulls], dtype=float))


def _nearest_hull(xy: np.ndarray, hulls: Sequence[HullMotion]) -> np.ndarray:
    """The index of the hull whose reference point is nearest each point (n, 2), m."""
    at = np.array([np.asarray(h.xy, dtype=float) for h in hulls])
    return np.argmin(((xy[:, None, :] - at[None, :, :]) ** 2).sum(axis=2), axis=1)


def _hull_loads(model: IceModel, data: IceData, con: Contacts, hulls: Sequence[HullMotion], jammed: np.ndarray,
                dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Send what each hull struck (and the jammed floes, under the hull nearest each) under
    it; returns each hull's contact force (h, 2; N, world) and moment (h,; N m, CCW)."""
    force, moment = np.zeros((len(hulls), 2)), np.zeros(len(hulls))
    owner = _nearest_hull(data.state.xy[jammed], hulls) if len(jammed) else _NO_ROWS
    for k, hull in enumerate(hulls):
        struck, impulse, point = con.with_hull(k)
        _update_submersion(model, data, k, hull, struck[struck >= 0], jammed[owner == k])
        fx, fy, moment[k] = _hull_load(struck, impulse, point, np.asarray(hull.xy, dtype=np.float64), dt)
        force[k] = fx, fy
    return force, moment


def ice_step(model: IceModel, data: IceData, hulls: Sequence[HullMotion], dt: float, water: np.ndarray | None = None,
             wash: Callable[[np.ndarray], np.ndarray] | None = None) -> IceStepReport:
    """Advance the breakable ice by dt seconds with each hull (in the order of the ice
    world's hulls, ``tiles.add_hull``) moving as given, in water moving at ``water`` (world
    x east, y north, m/s; None: still) and, where ``wash`` is given, locally faster by what
    it gives at a floe's centre (the propellers' jets)."""
    st, space = data.state, data.contacts
    if len(hulls) != len(space.hulls):
        raise ValueError(f"the ice world has {len(space.hulls)} hulls; {len(hulls)} motions were given")
    east, north = (0.0, 0.0) if water is None else (float(water[0]), float(water[1]))
    space.set_water_velocity(east, north, dt)
    resting_on = model.settings.rest_far_floes
    rest = resting_on and resting.drift_settled(model, data, (east, north))
    timer = data.timer
    for k, hull in enumerate(hulls):
        space.set_hull(k, hull.xy, hull.angle, hull.velocity, hull.angular_velocity)
        if resting_on:
            resting.wake_near_hull(model, data, k, hull.xy)
    by_hull, cracked, broke = _hulls_break(model, data, hulls)
    timer.lap("ice: hulls break")
    resting.wake_wide_floes(model, data, hulls)
    for k, hull in enumerate(hulls):
        _advance_turns(model, data, k, hull, dt)
    timer.lap("ice: waking, turns")
    space.step(dt)
    timer.lap("ice: engine")
    con = space.read_contacts(st)
    by_contact, jammed = _contact_breaks(model, st, con, st.vel)  # st.vel still holds pre-step velocities
    struck_off, breaker = compound_floes.struck_off(space, st, con, *_hull_motions(hulls)) if space.compounds.live \
        else (_NO_ROWS, _NO_ROWS)
    vel_before = st.vel.copy() if resting_on else None
    moving = space.read_free(st)
    if wash is not None and len(moving):
        drag_in_wash(data, moving, wash, dt)
    if len(by_contact):
        break_cells(data, by_contact, BreakCause.CONTACT)
    if len(struck_off):
        struck_off = np.setdiff1d(struck_off, by_contact)
        break_cells(data, struck_off, BreakCause.HULL)
        by_hull = _union([by_hull, struck_off])
        broke += np.bincount(breaker, minlength=len(hulls))
    timer.lap("ice: contacts")
    free = _unsettled(moving, st.submerged, st.gcell, model.z_equilibrium, st.heave, st.roll, st.pitch,
                      st.heave_rate, st.roll_rate, st.pitch_rate)
    if len(free):
        mat = model.material
        vertical_step(free, st.gcell, model.tris, model.tri_start, model.mass, model.inertia, model.damping,
                      model.settings.heave_added_mass, mat.water_density * mat.gravity, mat.gravity,
                      st.heave, st.roll, st.pitch, st.heave_rate, st.roll_rate, st.pitch_rate,
                      dt, vertical_substeps(model, dt))
    force, moment = _hull_loads(model, data, con, hulls, jammed, dt)
    timer.lap("ice: floating, loads")
    if resting_on:
        resting.after_step(model, data, con, vel_before, moving, _hull_motions(hulls)[0], dt, rest)
        timer.lap("ice: resting")
    return IceStepReport(by_hull, by_contact, cracked, force, moment, broke)


def warm_up(model: IceModel, data: IceData) -> None:
    """Load every compiled kernel the ice step uses, so that no step waits for a compile."""
    contact_kernels.warm_up()
    compound_floes.warm_up()
    floe_parts.warm_up()
    none, f32 = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.float32)
    flags = none.astype(np.bool_)
    _hard_pushes(none, none, np.zeros((0, 2)), np.zeros((0, 2)), none.astype(np.uint8), flags,
                 np.zeros((0, 2), np.float32), np.zeros(0, dtype=np.int32), model.mass, model.k_impact,
                 model.ride_load, model.edge_capacity)
    resting.warm_up(model)
    _hull_load(none, np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(2), 1.0)
    _hull_passed(none, np.zeros((0, 2)), np.zeros(2), 1.0, 0.0, data.contacts.hulls[0].outline, 1.0, 1.0, 1.0)
    _going_under(none, none, none.astype(np.uint8), flags, flags, np.zeros((0, 2)), np.zeros(2), 1.0, 0.0, 1.0)
    _unsettled(none, flags, none.astype(np.int32), model.z_equilibrium, f32, f32, f32, f32, f32, f32)
    vertical.warm_up(model.tris, model.tri_start, model.mass, model.inertia, model.damping)
    turning.warm_up()
