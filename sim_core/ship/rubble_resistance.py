"""Resistance of ice rubble the world does not lay out as bodies: brash in an old channel,
and the keel of a pressure ridge.

**Brash channel**: the Finnish-Swedish ice class rules' channel resistance (Riska, Wilhelmson,
Englund & Leiviskä 1997, "Performance of merchant vessels in ice in the Baltic", Winter
Navigation Research Board report 52; as adopted in the rules: Traficom, "Ice class
regulations and the application thereof", section 3.2.2). For brash of thickness H_M in mid
channel, at the rules' speed of 5 knots:

  R_CH = C1 + C2 + C3 C_mu (H_F + H_M)^2 (B + C_psi H_F) + C4 L_PAR H_F^2
         + C5 (L T / B^2)^3 A_wf / L
  H_F = 0.26 + (H_M B)^0.5                              (the brash pushed to the sides), m
  psi = arctan(tan phi_2 / sin alpha)
  C_mu = 0.15 cos phi_2 + sin psi sin alpha,  at least 0.45
  C_psi = 0.047 psi - 2.115 (psi in degrees),  0 where psi <= 45 deg
  C3 = 845 kg/(m^2 s^2), C4 = 42 kg/(m^2 s^2), C5 = 825 kg/s^2, 5 <= (L T / B^2)^3 <= 20

C1 and C2 are the IA Super class's consolidated layer on top of the brash; a simulated old
channel is unconsolidated brash, so they are 0. The rules give R_CH at 5 knots only. Away
from it the resistance follows the speed factor of Lindqvist's submersion term, which is
also the displacement of broken pieces along the hull: (1 + 9.4 v / sqrt(g L)), normalised
to 1 at 5 knots (our choice, documented in docs/design/regimes.md).

**Ridge keel**: the passive failure of the keel's rubble (a Mohr-Coulomb material) in front
of a face of width w; Dolgopolov, Afanasiev, Korenkov & Panfilov (1975), "Effect of
hummocked ice on the piers of marine hydraulic structures", IAHR Ice Symposium, Hanover NH,
the form ISO 19906 adopts for first-year ridge keels:

  F_K = mu_phi h_k w (h_k mu_phi gamma_e / 2 + 2 c) (1 + h_k / (6 w))
  mu_phi = tan(45 deg + phi / 2),  gamma_e = (1 - e) (rho_w - rho_i) g

with h_k the keel depth the face meets, phi the rubble's angle of internal friction, c its
cohesion and e its porosity. For a ship, w is the beam and h_k the keel depth down to the
draught (the hull meets no rubble below its keel). The model is static: it does not grow
with speed. A vertical face is the model's idealisation; a ship's raked bow fails the keel
with less force, so this is the upper end for a ship.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from sim_core.frames.units import KNOT

FSICR_SPEED = 5.0 * KNOT  # m/s: the rules' channel resistance holds at 5 knots
C3, C4, C5 = 845.0, 42.0, 825.0  # kg/(m^2 s^2), kg/(m^2 s^2), kg/s^2 (Riska et al. 1997)


@dataclass(frozen=True)
class BowForm:
    """The hull data the channel resistance needs: L, B, T (m), the bow angle phi_2 and the
    waterline angle alpha (rad), the bow's length L_BOW, the parallel midbody's length L_PAR
    (m) and the bow's waterline area A_wf (m^2)."""

    length: float
    beam: float
    draught: float
    bow_angle: float
    waterline_angle: float
    bow_length: float
    parallel_length: float
    bow_waterline_area: float


def brash_channel_resistance(hm: float, hull: BowForm) -> float:
    """R_CH (N) at 5 knots in a channel of brash H_M = hm m thick in mid channel (0 for
    hm <= 0); Riska et al. (1997), module docstring.

    Parameters
    ----------
    hm : brash thickness in mid channel, m
    hull : the ship's bow form

    Returns
    -------
    The channel resistance, N.
    """
    if hm <= 0.0:
        return 0.0
    b, phi2, alpha = hull.beam, hull.bow_angle, hull.waterline_angle
    hf = 0.26 + math.sqrt(hm * b)
    psi = math.atan(math.tan(phi2) / math.sin(alpha))
    c_mu = max(0.45, 0.15 * math.cos(phi2) + math.sin(psi) * math.sin(alpha))
    psi_deg = math.degrees(psi)
    c_psi = 0.047 * psi_deg - 2.115 if psi_deg > 45.0 else 0.0
    slender = min(max((hull.length * hull.draught / b**2) ** 3, 5.0), 20.0)
    return (C3 * c_mu * (hf + hm) ** 2 * (b + c_psi * hf) + C4 * hull.parallel_length * hf**2
            + C5 * slender * hull.bow_waterline_area / hull.length)


def channel_speed_factor(speed: float, length: float, g: float) -> float:
    """The channel resistance at ``speed`` (m/s) over that at 5 knots: Lindqvist's (1989)
    submersion factor (1 + 9.4 v / sqrt(g L)), normalised at 5 knots."""
    froude = 9.4 / math.sqrt(g * length)
    return (1.0 + froude * abs(speed)) / (1.0 + froude * FSICR_SPEED)


def keel_resistance(keel_depth: float, width: float, friction_angle: float, cohesion: float, porosity: float,
                    water_density: float, ice_density: float, g: float) -> float:
    """F_K (N) of a ridge keel's rubble against a face ``width`` m wide meeting ``keel_depth``
    m of it (Dolgopolov et al. 1975, module docstring); 0 for no depth.

    Parameters
    ----------
    keel_depth : h_k, m
    width : w, m
    friction_angle : phi, the rubble's angle of internal friction, rad
    cohesion : c, Pa
    porosity : e, the share of voids in the keel
    water_density, ice_density : kg/m^3
    g : m/s^2

    Returns
    -------
    The keel load, N.
    """
    if keel_depth <= 0.0:
        return 0.0
    mu_phi = math.tan(math.pi / 4.0 + friction_angle / 2.0)
    gamma_e = (1.0 - porosity) * (water_density - ice_density) * g
    h = keel_depth
    return mu_phi * h * width * (h * mu_phi * gamma_e / 2.0 + 2.0 * cohesion) * (1.0 + h / (6.0 * width))
