"""Floes at rest far from every hull leave the dynamic set, and come back when they are needed.

Astern of the ship the broken channel packs and comes to rest: thousands of floes the engine
would otherwise solve every step for nothing. A free floe that has stayed slower than
``rest_speed`` (its centre, and its rim turning) for ``rest_after_s``, settled on the water
and farther from every hull than the rest radius sheds its contacts and becomes a static
body (``ContactSpace.rest``, then ``settle``): moving floes still strike it, but it and
its resting neighbours cost no solver work. It wakes (``ContactSpace.wake``), with the
velocity it came to rest with, when the hull comes within the wake radius (Chipmunk does
not collide kinematic and static bodies, so the hull must never meet a resting floe), or
when the contacts' pushes have brought it to ``rest_speed``: in each step it met its
strikers as a wall, so it takes their impulses into the velocity it keeps while resting,
and a steady push adds up.

This is Chipmunk's sleeping done floe by floe. Chipmunk sleeps and wakes whole touching
groups, and the packed channel is one group of thousands: one touch woke them all, in steps
of 0.1-1.1 s. Every test here is a count or a threshold, so reruns stay the same.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numba
import numpy as np

from sim_core.ice.chipmunk_bodies import LOWEST_ROW
from sim_core.ice.contact_kernels import Contacts
from sim_core.ice.model import IceModel
from sim_core.ice.tiles import IceData, bond_floe
from sim_core.ice.vertical import settled

_WAKE_SHARE = 0.8  # the wake radius as a share of the rest radius
_CLEARANCE = 10.0  # m beyond the hull's reach that a resting floe always wakes
_LOOK_AGAIN = 20.0  # m the hull moves between looks at every row for resting floes to wake


def radii(model: IceModel, data: IceData) -> tuple[float, float]:
    """The rest and wake radii about the hull's reference point (m): ``rest_distance`` and
    0.8 of it, both pushed out so that the wake radius clears the hull's reach plus a
    floe's radius by 10 m."""
    wake = max(_WAKE_SHARE * model.settings.rest_distance, data.contacts.reach + _CLEARANCE)
    return wake / _WAKE_SHARE, wake


@numba.njit(cache=True)
def _speed(i, vel, yaw_rate, gcell, extent):
    """How fast row i moves, m/s: its centre's speed plus its rim's from turning."""
    return math.sqrt(vel[i, 0] ** 2 + vel[i, 1] ** 2) + abs(yaw_rate[i]) * extent[gcell[i]]


@numba.njit(cache=True)
def _calm_far(rows, vel, yaw_rate, gcell, extent, calm, speed, steps, submerged, z_equilibrium, heave, roll,
              pitch, heave_rate, roll_rate, pitch_rate, xy, hull_xy, radius):
    """Count the moving rows' steps at rest (slower than speed, m/s: the centre's speed
    plus the rim's from turning; a faster step starts the count again), and return the
    places in rows (ascending) of those at rest for ``steps``, above water, settled at
    their draft and farther than radius (m) from every hull's reference point (hull_xy
    (h, 2), m)."""
    out = np.empty(len(rows), np.int64)
    n = 0
    for k in range(len(rows)):
        i = rows[k]
        if _speed(i, vel, yaw_rate, gcell, extent) >= speed:
            calm[i] = 0
            continue
        if calm[i] < 65535:
            calm[i] += 1
        if calm[i] < steps or submerged[i]:
            continue
        near = False
        for h in range(hull_xy.shape[0]):
            near = near or (xy[i, 0] - hull_xy[h, 0]) ** 2 + (xy[i, 1] - hull_xy[h, 1]) ** 2 <= radius * radius
        if near:
            continue
        if settled(i, gcell, z_equilibrium, heave, roll, pitch, heave_rate, roll_rate, pitch_rate):
            out[n] = k
            n += 1
    return out[:n]


@numba.njit(cache=True)
def _look(flag, xy, at, radius, zone):
    """Rows whose flag is set with their centre closer than radius (m) to the point at (m),
    and the other flagged rows closer than zone (m); both ascending."""
    near, other = np.empty(len(flag), np.int64), np.empty(len(flag), np.int64)
    n = m = 0
    for i in range(len(flag)):
        if flag[i]:
            d = (xy[i, 0] - at[0]) ** 2 + (xy[i, 1] - at[1]) ** 2
            if d < radius * radius:
                near[n] = i
                n += 1
            elif d < zone * zone:
                other[m] = i
                m += 1
    return near[:n], other[:m]


@numba.njit(cache=True)
def _pushes_on(a, b, impulse, point, flag, xy, gcell, mass, vel, vel_before):
    """The push (N s, world) and its moment (N m s, CCW about the centre) that the contacts
    (rows a, b; impulse on a, N s; point, m) put on each row whose flag is set, each
    contact's impulse taken at the row's share m / (m + m_other) of the pair's mass (kg, by
    global cell), and the speed (m/s) of its fastest striker, before or after the step
    (vel_before, vel: m/s by row); returns those rows
    (ascending), pushes, moments and speeds. Each row's contacts are summed in the order of
    the other row, not the engine's order (which follows C pointers), so that the sums
    round the same in every rerun."""
    n = 0
    for rows in (a, b):
        for k in range(len(rows)):
            if rows[k] >= 0 and flag[rows[k]]:
                n += 1
    key, entry = np.empty(n, np.int64), np.empty(n, np.int64)
    n = 0
    for side in range(2):
        rows, others = (a, b) if side == 0 else (b, a)
        for k in range(len(rows)):
            if rows[k] >= 0 and flag[rows[k]]:
                key[n] = rows[k] * (len(flag) - LOWEST_ROW + 1) + others[k] - LOWEST_ROW  # by row, then other
                entry[n] = side * len(a) + k
                n += 1
    order = np.argsort(key, kind="mergesort")
    rows_out, push, turn, fastest = np.empty(n, np.int64), np.zeros((n, 2)), np.zeros(n), np.zeros(n)
    m = -1
    for e in order:
        k, sign = (entry[e], 1.0) if entry[e] < len(a) else (entry[e] - len(a), -1.0)
        row = a[k] if sign > 0.0 else b[k]
        if m < 0 or rows_out[m] != row:
            m += 1
            rows_out[m] = row
        other = b[k] if sign > 0.0 else a[k]
        share = 1.0
        if other >= 0:
            share = mass[gcell[row]] / (mass[gcell[row]] + mass[gcell[other]])
            for v in (vel, vel_before):
                fastest[m] = max(fastest[m], math.sqrt(float(v[other, 0]) ** 2 + float(v[other, 1]) ** 2))
        jx, jy = share * sign * impulse[k, 0], share * sign * impulse[k, 1]
        push[m, 0] += jx
        push[m, 1] += jy
        turn[m] += (point[k, 0] - xy[row, 0]) * jy - (point[k, 1] - xy[row, 1]) * jx
    return rows_out[:m + 1], push[:m + 1], turn[:m + 1], fastest[:m + 1]


def wake_near_hull(model: IceModel, data: IceData, hull: int, hull_xy: np.ndarray) -> None:
    """Wake the resting floes within the wake radius of a hull's (by index) reference
    point (m). Resting floes do not move: every ``_LOOK_AGAIN`` m that the hull moves, all
    rows are looked at, and the resting ones within that distance of the wake radius are
    kept (``HullRows.wake_look``); until the next look only those can come within it."""
    st, wake, rows_of = data.state, radii(model, data)[1], data.hulls[hull]
    hull_xy = np.asarray(hull_xy, dtype=np.float64)
    at, rows = rows_of.wake_look
    if math.hypot(hull_xy[0] - at[0], hull_xy[1] - at[1]) < _LOOK_AGAIN:
        rows = rows[st.resting[rows]]
        near, rows = _look_among(rows, st.xy, hull_xy, wake)
        rows_of.wake_look = (at, rows)
    else:
        near, rows = _look(st.resting, st.xy, hull_xy, wake, wake + _LOOK_AGAIN)
        rows_of.wake_look = (hull_xy.copy(), rows)
    if len(near):
        data.contacts.wake(st, near)


@numba.njit(cache=True)
def _look_among(rows, xy, at, radius):
    """Of rows (ascending), those with their centre closer than radius (m) to the point at
    (m), and the others; both ascending."""
    near = np.zeros(len(rows), np.bool_)
    for k in range(len(rows)):
        i = rows[k]
        near[k] = (xy[i, 0] - at[0]) ** 2 + (xy[i, 1] - at[1]) ** 2 < radius * radius
    return rows[near], rows[~near]


@numba.njit(cache=True)
def _take_pushes(rows, push, turn, fastest, mass, inertia, gcell, extent, vel, yaw_rate, speed):
    """Add the pushes (N s) and their moments (N m s) to the velocities (m/s, rad/s) that
    resting rows keep, at most as fast as their fastest strikers (m/s: a floe pinched
    between a wall and a floe the hull drives meets impulses without bound, but would have
    moved on with it), and return the rows now moving at speed (m/s) or faster."""
    out = np.empty(len(rows), np.int64)
    n = 0
    for k in range(len(rows)):
        i, g = rows[k], gcell[rows[k]]
        vel[i, 0] += np.float32(push[k, 0] / mass[g])
        vel[i, 1] += np.float32(push[k, 1] / mass[g])
        yaw_rate[i] += np.float32(turn[k] / inertia[g, 2])
        now, top = _speed(i, vel, yaw_rate, gcell, extent), max(fastest[k], speed)
        if now > top:
            cut = top / now
            vel[i, 0], vel[i, 1], yaw_rate[i] = vel[i, 0] * cut, vel[i, 1] * cut, yaw_rate[i] * cut
            now = _speed(i, vel, yaw_rate, gcell, extent)  # top, as the float32 velocities round it
        if now >= speed:
            out[n] = i
            n += 1
    return out[:n]


def drift_settled(model: IceModel, data: IceData, water: tuple[float, float]) -> bool:
    """Whether the floes at rest came to rest in the drift the water now has (its velocity,
    world x east, y north, m/s: current and wind drift), so that more may. After a change
    every resting floe is woken, ``rest_per_step`` a step, to feel the new drift, and none
    comes to rest until they all are. A floe drifting free moves faster than ``rest_speed``
    and never rests; those that come to rest in a drift are jammed (against the level ice at
    a channel's edge), as in still water those the ship left behind."""
    if data.rest_water == water:
        return True
    rows = np.flatnonzero(data.state.resting)[:model.settings.rest_per_step]
    if len(rows):
        data.contacts.wake(data.state, rows)
        return False
    data.rest_water = water
    return True


def wake_struck(model: IceModel, data: IceData, con: Contacts, vel_before: np.ndarray | None = None) -> None:
    """Give the resting floes the pushes of the last step's contacts, and wake those they
    bring to ``rest_speed``. In the step a resting floe met its striker as a wall (a static
    body takes no impulse): the wall stopped the striker's approach with an impulse J. Had
    the floe been free, the two would have moved on together (a plastic collision), the floe
    taking J m / (m + m_striker); so that share of J (and of its moment about the floe's
    centre) goes into the velocity it keeps while resting. A steady push too small to wake a
    floe in one step adds up until it does; and a small cake that a heavy floe presses
    against does not take the heavy floe's whole stopping impulse (which would throw it off
    at tens of m/s); nor does it move faster than its fastest striker, before or after the
    step (``vel_before``, m/s by row; the rows' velocities now where not given)."""
    st = data.state
    rows, push, turn, fastest = _pushes_on(con.a, con.b, con.impulse, con.point, st.resting, st.xy, st.gcell,
                                           model.mass, st.vel, st.vel if vel_before is None else vel_before)
    woken = _take_pushes(rows, push, turn, fastest, model.mass, model.inertia, st.gcell, data.contacts.extent, st.vel,
                         st.yaw_rate, model.settings.rest_speed)
    if len(woken):
        data.contacts.wake(st, woken)


def rest_far(model: IceModel, data: IceData, moving: np.ndarray, hull_xy: np.ndarray, dt: float,
             new: bool = True) -> None:
    """Settle the floes that have shed their contacts (``ContactSpace.settle``); and (if
    ``new``) count the moving rows' steps at rest, and start taking out of the dynamic set
    those at rest for ``rest_after_s``, above water, settled and beyond the rest radius of
    every hull (``hull_xy``: their reference points (h, 2), m): up to
    ``rest_per_step`` of them and the contact space's ``rest_share``, first those that come
    first among its dynamic bodies (moving is in that order), which Chipmunk finds soonest."""
    s, st = model.settings, data.state
    settled = data.contacts.settle(st)
    zone = radii(model, data)[1] + _LOOK_AGAIN
    for hull in data.hulls if len(settled) else ():  # those within a hull's last look's zone join the rows it kept
        at, rows = hull.wake_look
        inside = settled[((st.xy[settled] - at) ** 2).sum(axis=1) < zone * zone]
        if len(inside):
            hull.wake_look = (at, np.union1d(rows, inside))
    if not new:
        return
    steps = min(65535, max(1, math.ceil(s.rest_after_s / dt)))
    picks = _calm_far(moving, st.vel, st.yaw_rate, st.gcell, data.contacts.extent, st.calm, s.rest_speed, steps,
                      st.submerged, model.z_equilibrium, st.heave, st.roll, st.pitch, st.heave_rate, st.roll_rate,
                      st.pitch_rate, st.xy, np.asarray(hull_xy, dtype=np.float64).reshape(-1, 2), radii(model, data)[0])
    if len(picks):
        data.contacts.rest(st, moving[picks[:min(s.rest_per_step, data.contacts.rest_share(picks))]])


def wake_wide_floes(model: IceModel, data: IceData, hulls: Sequence) -> None:
    """Wake the wide floes' bodies near each hull (``step.HullMotion``; after the hulls broke
    what they lie on: a ship laid in the ice), their cells bonded."""
    if not model.settings.wide_floes_move:
        return
    space = data.contacts
    for k, hull in enumerate(hulls):
        speed = float(np.hypot(*hull.velocity))
        space.wake_resting(k, speed)
        for placement, floe in space.wake_near(data.state, k, speed):
            bond_floe(data, placement, floe)


def after_step(model: IceModel, data: IceData, con: Contacts, vel_before: np.ndarray, moving: np.ndarray,
               hulls_xy: np.ndarray, dt: float, settled_drift: bool) -> None:
    """After the ice step: wake the resting floes struck hard (``wake_struck``), and put the
    floes far from the hulls (``hulls_xy``, (h, 2) m) to rest (``rest_far``)."""
    wake_struck(model, data, con, vel_before)
    rest_far(model, data, moving, hulls_xy, dt, new=settled_drift)
    if data.contacts.compounds.live:
        data.contacts.rest_far(model.settings.rest_speed)


def warm_up(model: IceModel) -> None:
    """Load the compiled kernel."""
    none, f32 = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.float32)
    _calm_far(none, np.zeros((0, 2), np.float32), f32, none.astype(np.int32), np.ones(1), none.astype(np.uint16),
              1.0, 1, none.astype(np.bool_), model.z_equilibrium, f32, f32, f32, f32, f32, f32, np.zeros((0, 2)),
              np.zeros((1, 2)), 1.0)
    _look(none.astype(np.bool_), np.zeros((0, 2)), np.zeros(2), 1.0, 2.0)
    _look_among(none, np.zeros((0, 2)), np.zeros(2), 1.0)
    _take_pushes(none, np.zeros((0, 2)), np.zeros(0), np.zeros(0), model.mass, model.inertia, none.astype(np.int32),
                 np.ones(1), np.zeros((0, 2), np.float32), np.zeros(0, np.float32), 1.0)
    _pushes_on(none, none, np.zeros((0, 2)), np.zeros((0, 2)), none.astype(np.bool_), np.zeros((0, 2)),
               none.astype(np.int32), np.zeros(0), np.zeros((0, 2), np.float32),
               np.zeros((0, 2), np.float32))
