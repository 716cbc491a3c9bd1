"""Heave and pitch of the hull under the ice's vertical load at the bow: what makes the bow
rise as the ship rides up on the ice and breaks through, and the eye on the bridge with it.

The planar manoeuvring model (``sim_core.ship.model``) holds heave, roll and pitch at
zero; this adds heave and pitch as two uncoupled, linear mass-spring-dampers about the
floating position, with the hydrostatic restoring of a surface vessel (Fossen 2011,
"Handbook of Marine Craft Hydrodynamics and Motion Control", section 4.2.1):

  (m + A33) z'' + B33 z' + rho g A_wp z = F_z
  (I55 + A55) theta'' + B55 theta' + rho g I_L theta = F_z (x_stem - x_F)

z up, theta bow up; A_wp, I_L and x_F the area, longitudinal second moment and centre of
the waterplane (taken from the waterline the ice world gives the hull, ``waterline_contour``;
rho g I_L is rho g V GM_L with GM_L ~ BM_L = I_L / V, as for ships BM_L is a hull's length,
KB - KG a few metres). The added mass and inertia are taken equal to the mass and inertia,
the order of magnitude of ship hulls in heave and pitch (Journée & Massie 2001, "Offshore
Hydromechanics", chapter 6), and the damping as ratios of critical (``Motions``).

The ice pushes the bow up: a normal force N on the stem, raked at phi to the waterline,
with hull friction mu, has the horizontal component N (sin phi + mu cos phi) that resists
the ship and the vertical one N (cos phi - mu sin phi), the decomposition of Lindqvist's
(1989) crushing term. So the bow's ice resistance R lifts the bow by
F_z = R (cos phi - mu sin phi) / (sin phi + mu cos phi).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim_core.frames.hull_contour import waterline_contour


@dataclass(frozen=True)
class VerticalModel:
    """Heave and pitch of one hull (SI): inertias with added inertia, dampings, hydrostatic
    stiffnesses, the stem's lever about the centre of flotation and the lift per newton of
    bow resistance."""

    heave_mass: float  # kg
    heave_damping: float  # N s/m
    heave_stiffness: float  # N/m
    pitch_inertia: float  # kg m^2
    pitch_damping: float  # N m s
    pitch_stiffness: float  # N m/rad
    stem_lever: float  # m: stem forward of the centre of flotation
    lift_ratio: float  # F_z / R


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


def compile_vertical(length: float, beam: float, displacement: float, density: float, g: float,
                     stem_angle: float, friction: float, heave_damping: float, pitch_damping: float,
                     gyration_y: float) -> VerticalModel:
    """The heave and pitch model of a hull of length, beam (m), volume displacement (m^3),
    in water of ``density`` (kg/m^3); stem angle (rad), ice-hull friction, damping ratios
    and the pitch radius of gyration over L (module docstring)."""
    area, centre, second = waterplane(waterline_contour(length, beam))
    mass = 2.0 * density * displacement  # with the added mass
    inertia = mass * (gyration_y * length) ** 2
    k_heave, k_pitch = density * g * area, density * g * second
    s, c = math.sin(stem_angle), math.cos(stem_angle)
    return VerticalModel(mass, 2.0 * heave_damping * math.sqrt(k_heave * mass), k_heave,
                         inertia, 2.0 * pitch_damping * math.sqrt(k_pitch * inertia), k_pitch,
                         0.5 * length - centre, max(0.0, (c - friction * s) / (s + friction * c)))


def step_vertical(model: VerticalModel, eta: np.ndarray, nu: np.ndarray, bow_resistance: float, h: float) -> None:
    """Advance heave and pitch by h s (semi-implicit Euler) under the lift of the bow's ice
    resistance (N, >= 0). ``eta[2]`` is down (m), ``eta[4]`` pitch (rad, bow up), ``nu[2]``,
    ``nu[4]`` their rates: the 6-DOF layout of ``ShipData``."""
    lift = model.lift_ratio * bow_resistance
    up, rate = -eta[2], -nu[2]
    rate += h * (lift - model.heave_damping * rate - model.heave_stiffness * up) / model.heave_mass
    eta[2], nu[2] = -(up + h * rate), -rate
    moment = lift * model.stem_lever
    nu[4] += h * (moment - model.pitch_damping * nu[4] - model.pitch_stiffness * eta[4]) / model.pitch_inertia
    eta[4] += h * nu[4]
