"""Heave, roll and pitch of the hull: the bow rising as the ship rides up on the ice and
breaking through, the heel in a turn and under the ice's side loads, and the eye on the
bridge with them.

The planar manoeuvring model (``sim_core.ship.model``) moves the ship in surge, sway and
yaw; this adds heave, roll and pitch as three uncoupled, linear mass-spring-dampers about
the floating position, with the hydrostatic restoring of a surface vessel (Fossen 2011,
"Handbook of Marine Craft Hydrodynamics and Motion Control", section 4.2.1):

  (m + A33) z'' + B33 z' + rho g A_wp z = F_z
  (I44 + A44) phi'' + B44 phi' + rho g V GM phi = K
  (I55 + A55) theta'' + B55 theta' + rho g I_L theta = F_z (x_stem - x_F)

z up, phi starboard down, theta bow up; A_wp, I_L and x_F the area, longitudinal second
moment and centre of the waterplane (taken from the waterline the ice world gives the hull,
``waterline_contour``; rho g I_L is rho g V GM_L with GM_L ~ BM_L = I_L / V, as for ships
BM_L is a hull's length, KB - KG a few metres). The added mass and inertia in heave and
pitch are taken equal to the mass and inertia, the order of magnitude of ship hulls
(Journée & Massie 2001, "Offshore Hydromechanics", chapter 6), and every damping as a ratio
of critical (``Motions``).

Roll: the ship file's metacentric height GM and centre of gravity above the keel KG. The
roll inertia with its added inertia is the one that gives the natural roll period of the
IMO's Intact Stability Code (2008, Part A, 2.3.4, the weather criterion):
T = 2 C B / sqrt(GM), C = 0.373 + 0.023 B/d - 0.043 L/100. The heeling moment about G is
that of the lateral forces where they act: the hull's and rudder's (the MMG model's Y_H +
Y_R) at half the draught, as the Code's heel in a turn has it (2.3.3.2: lever KG - d/2),
and the external load (the ice on the hull, with the wind) at the waterline:
K = -(Y_H + Y_R)(KG - d/2) - Y_ext (KG - d). In a steady turn the hull's force is the
centripetal one and the ship heels outwards; the rudder's first kick heels it inwards.
The wind's own lever (the centre of the windage above the waterline) is not in the ship
file, so its heel is understated.

The ice pushes the bow up: a normal force N on the stem, raked at phi_s to the waterline,
with hull friction mu, has the horizontal component N (sin phi_s + mu cos phi_s) that resists
the ship and the vertical one N (cos phi_s - mu sin phi_s), the decomposition of Lindqvist's
(1989) crushing term. So the bow's ice resistance R lifts the bow by
F_z = R (cos phi_s - mu sin phi_s) / (sin phi_s + mu cos phi_s).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim_core.frames.hull_contour import waterline_contour
from sim_core.ship.particulars import Motions


@dataclass(frozen=True)
class MotionsModel:
    """Heave, roll and pitch of one hull (SI): inertias with added inertia, dampings,
    hydrostatic stiffnesses, the stem's lever about the centre of flotation, the lift per
    newton of bow resistance and the heeling levers of the lateral forces (roll stiffness 0:
    no roll, for a ship file without GM and KG)."""

    heave_mass: float  # kg
    heave_damping: float  # N s/m
    heave_stiffness: float  # N/m
    pitch_inertia: float  # kg m^2
    pitch_damping: float  # N m s
    pitch_stiffness: float  # N m/rad
    stem_lever: float  # m: stem forward of the centre of flotation
    lift_ratio: float  # F_z / R
    roll_inertia: float = 1.0  # kg m^2
    roll_damping: float = 0.0  # N m s
    roll_stiffness: float = 0.0  # N m/rad
    hull_lever: float = 0.0  # m: KG - d/2, G above the hull's lateral force
    waterline_lever: float = 0.0  # m: KG - d, G above the waterline


def waterplane(contour: np.ndarray) -> tuple[float, float, float]:
    """Area (m^2), centre (x, m) and second moment about the transverse axis through that
    centre (m^4) of a closed waterline contour (n, 2), x forward."""
    x, y = contour[:, 0], contour[:, 1]
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    cross = x * y1 - x1 * y
    area = 0.5 * cross.sum()
    centre = (cross * (x + x1)).sum() / (6.0 * area)
    second = (cross * (x * x + x * x1 + x1 * x1)).sum() / 12.0
    return abs(area), float(centre), abs(second) - abs(area) * centre**2


def roll_period(length: float, beam: float, draught: float, gm: float) -> float:
    """Natural roll period (s) of the IMO Intact Stability Code (2008, Part A, 2.3.4):
    T = 2 C B / sqrt(GM), C = 0.373 + 0.023 B/d - 0.043 L/100, all in metres."""
    c = 0.373 + 0.023 * beam / draught - 0.043 * length / 100.0
    return 2.0 * c * beam / math.sqrt(gm)


def _oscillator(mass: float, stiffness: float, damping_ratio: float) -> float:
    """The damping (per unit rate) of ``damping_ratio`` of critical."""
    return 2.0 * damping_ratio * math.sqrt(stiffness * mass)


def compile_motions(length: float, beam: float, draught: float, displacement: float, density: float, g: float,
                    stem_angle: float, friction: float, motions: Motions) -> MotionsModel:
    """The heave, roll and pitch model of a hull of length, beam, draught (m) and volume
    displacement (m^3), in water of ``density`` (kg/m^3); stem angle (rad), ice-hull
    friction and the ship file's ``Motions`` (module docstring)."""
    area, centre, second = waterplane(waterline_contour(length, beam))
    mass = 2.0 * density * displacement  # with the added mass
    inertia = mass * (motions.gyration_y * length) ** 2
    k_heave, k_pitch = density * g * area, density * g * second
    s, c = math.sin(stem_angle), math.cos(stem_angle)
    model = MotionsModel(mass, _oscillator(mass, k_heave, motions.heave_damping), k_heave,
                         inertia, _oscillator(inertia, k_pitch, motions.pitch_damping), k_pitch,
                         0.5 * length - centre, max(0.0, (c - friction * s) / (s + friction * c)))
    gm, kg = motions.metacentric_height, motions.centre_of_gravity_height
    if gm is None or kg is None:
        return model
    k_roll = density * g * displacement * gm
    roll_inertia = k_roll * (roll_period(length, beam, draught, gm) / (2.0 * math.pi)) ** 2
    return MotionsModel(**{**model.__dict__, "roll_inertia": roll_inertia, "roll_stiffness": k_roll,
                           "roll_damping": _oscillator(roll_inertia, k_roll, motions.roll_damping),
                           "hull_lever": kg - 0.5 * draught, "waterline_lever": kg - draught})


def heeling_moment(model: MotionsModel, hull_sway: float, external_sway: float) -> float:
    """Roll moment (N m, + starboard down) about G of the hull's and rudder's lateral force
    and the external one (N, + to starboard), from where they act (module docstring)."""
    return -hull_sway * model.hull_lever - external_sway * model.waterline_lever


def step_motions(model: MotionsModel, eta: np.ndarray, nu: np.ndarray, bow_resistance: float, heel: float,
                 h: float) -> None:
    """Advance heave, roll and pitch by h s (semi-implicit Euler) under the lift of the
    bow's ice resistance (N, >= 0) and a heeling moment (N m, ``heeling_moment``).
    ``eta[2]`` is down (m), ``eta[3]`` roll (rad, starboard down), ``eta[4]`` pitch (rad,
    bow up), ``nu[2:5]`` their rates: the 6-DOF layout of ``ShipData``."""
    lift = model.lift_ratio * bow_resistance
    up, rate = -eta[2], -nu[2]
    rate += h * (lift - model.heave_damping * rate - model.heave_stiffness * up) / model.heave_mass
    eta[2], nu[2] = -(up + h * rate), -rate
    if model.roll_stiffness > 0.0:
        nu[3] += h * (heel - model.roll_damping * nu[3] - model.roll_stiffness * eta[3]) / model.roll_inertia
        eta[3] += h * nu[3]
    moment = lift * model.stem_lever
    nu[4] += h * (moment - model.pitch_damping * nu[4] - model.pitch_stiffness * eta[4]) / model.pitch_inertia
    eta[4] += h * nu[4]
