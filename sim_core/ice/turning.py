"""Broken pieces turning against the bow before they go under it.

Continuous icebreaking takes each piece through three phases (Enkvist 1972, "On the ice
resistance encountered by ships operating in the continuous mode of icebreaking", Swedish
Academy of Engineering Sciences in Finland, Report 24; Valanto 2001, "The resistance of
ships in level ice", SNAME Transactions 109): the hull breaks it from the sheet, turns it
until it lies parallel to the hull's surface, and slides it down and along the hull. The
contact model (``sim_core.ice.step``) takes a struck piece out of planar contact at once;
this module gives its turning a geometry, so that the trainee sees pieces tip against the
stem and the bow's flare instead of vanishing under them.

Geometry, in the vertical plane through the piece towards the hull: a piece of length d
turns about its far edge, which stays at the waterline, while the hull's surface, inclined
at psi to the horizontal, pushes its near edge down. psi is the bow's normal angle,
tan psi = tan phi / sin alpha (stem angle phi, waterline angle alpha; Lindqvist 1989, as in
``sim_core.ship.resistance``). With its near edge on the hull's surface once that surface
has advanced x across the waterline, towards the piece, since the turn began (derived here
from that picture, not a published model):

    x / d = sin(theta) / tan(psi) + 1 - cos(theta),

so the piece lies parallel to the hull (theta = psi) after the surface has advanced exactly
its length d. Over the next d of the surface's advance it slides down and under the hull,
from that pose to the submerged pose of ``step`` (held a thickness down, tilted by
``PUSHED_DOWN_TILT``), its depth and tilt linear in the advance (our choice: a turned piece
of 3 m lies 1.0 m deep and 0.75 rad tilted on the default ship's bow, and had jumped to the
submerged pose in one step). The surface at the bow advances
across its waterline by sin(alpha) of the ship's advance (``HullMotion.surface_advance``):
for the default ship, twice the piece's length of ship's advance. The turn is kinematic:
it follows the hull's advance, not a dynamic model of the piece, and the piece's plan
position stays where the contact model pins it (its centre, not its far edge, is the
turn's plan point). Its length is the side of a square of its plan area (our choice).
"""
from __future__ import annotations

import math

import numba
import numpy as np

PUSHED_DOWN_TILT = 0.25  # rad: roll of a floe the bow has turned under (its pose once the turn is done)


@numba.njit(cache=True)
def turn_angle(advanced: float, psi: float) -> float:
    """The piece's turn theta (rad, 0..psi) once the hull's surface has advanced ``advanced``
    piece lengths (x / d) since the turn began, on a hull surface at psi (rad) to the horizontal."""
    if advanced <= 0.0:
        return 0.0
    if advanced >= 1.0:
        return psi
    cot = 1.0 / math.tan(psi)
    theta = min(psi, advanced * math.tan(psi))  # small turns: x / d = theta / tan psi
    for _ in range(12):  # Newton; f is monotone on [0, psi]
        f = math.sin(theta) * cot + 1.0 - math.cos(theta) - advanced
        theta = min(max(theta - f / (math.cos(theta) * cot + math.sin(theta)), 0.0), psi)
    return theta


@numba.njit(cache=True)
def start_turns(rows, xy, turn, turn_dir, plan_area, gcell, hull_xy, c, s, stem):
    """Start the turn of pieces going under: each has twice its length still to go
    (``turn``, m: its turn, then its slide under the hull) and the direction (rad, CCW from
    east) from its centre to the nearest point of the hull's centre line between midship
    and stem (heading c, s; stem m ahead of hull_xy)."""
    for i in rows:
        turn[i] = 2.0 * math.sqrt(plan_area[gcell[i]])
        dx, dy = xy[i, 0] - hull_xy[0], xy[i, 1] - hull_xy[1]
        along = min(max(c * dx + s * dy, 0.0), stem)
        turn_dir[i] = math.atan2(hull_xy[1] + along * s - xy[i, 1], hull_xy[0] + along * c - xy[i, 0])


@numba.njit(cache=True)
def advance_turns(rows, submerged, turn, turn_dir, plan_area, gcell, z_equilibrium, thickness, yaw, heave, roll,
                  pitch, advance, psi):
    """Turn the submerged pieces of rows still turning by the hull's advance (m) this step:
    over the first length of it their centre goes down with the turn and their tilt grows
    towards psi about the horizontal axis across the direction to the hull (near edge
    down); over the second they slide from lying parallel to the hull to the submerged
    pose; one whose turn is done keeps that pose. Returns how many are still turning."""
    left = 0
    for i in rows:
        if not submerged[i] or turn[i] <= 0.0:
            continue
        g = gcell[i]
        d = math.sqrt(plan_area[g])
        turn[i] -= advance
        if turn[i] <= 0.0:
            turn[i] = 0.0
            heave[i] = z_equilibrium[g] - thickness[g]
            roll[i], pitch[i] = PUSHED_DOWN_TILT, 0.0
            continue
        left += 1
        theta = turn_angle((2.0 * d - turn[i]) / d, psi)
        slid = max(0.0, 1.0 - turn[i] / d)  # share of the slide under the hull done
        heave[i] = z_equilibrium[g] - ((1.0 - slid) * 0.5 * d * math.sin(theta) + slid * thickness[g])
        # rotation axis z x (towards the hull): a right-handed turn about it takes the near edge down;
        # roll and pitch as the components of the turn about the piece's own axes (small-angle form)
        ax, ay = -math.sin(turn_dir[i]), math.cos(turn_dir[i])
        cy, sy = math.cos(yaw[i]), math.sin(yaw[i])
        roll[i] = (1.0 - slid) * theta * (cy * ax + sy * ay) + slid * PUSHED_DOWN_TILT
        pitch[i] = (1.0 - slid) * theta * (-sy * ax + cy * ay)
    return left


def warm_up() -> None:
    """Load the compiled kernels."""
    none, f32, f64 = np.zeros(0, np.int64), np.zeros(0, np.float32), np.zeros(0)
    turn_angle(0.5, 0.7)
    start_turns(none, np.zeros((0, 2)), f32, f32, f64, none.astype(np.int32), np.zeros(2), 1.0, 0.0, 1.0)
    advance_turns(none, none.astype(np.bool_), f32, f32, f64, none.astype(np.int32), f64, f64, f64, f32, f32, f32,
                  0.1, 0.7)
