"""Ice resistance on the hull in level ice: Lindqvist (1989).

Lindqvist, G. (1989), "A straightforward method for calculation of ice resistance of
ships", POAC'89. With stem angle phi, waterline entrance half-angle alpha, and the normal
angle psi = arctan(tan phi / sin alpha):

  crushing    R_c = 0.5 sigma_b h^2 (tan phi + mu cos phi / cos psi) / (1 - mu sin phi / cos psi)
  bending     R_b = 27/64 sigma_b B h^1.5 / sqrt(E / (12 (1 - nu^2) g rho_w))
                    * (tan psi + mu cos phi / (sin alpha cos psi)) * (1 + 1 / cos psi)
  submersion  R_s = (rho_w - rho_i) g h B (T (B + T) / (B + 2T)
                    + mu (0.7 L - T / tan phi - B / (4 tan alpha)
                          + T cos phi cos psi sqrt(1 / sin^2 phi + 1 / tan^2 alpha)))
  total       R = (R_c + R_b)(1 + 1.4 v / sqrt(g h)) + R_s (1 + 9.4 v / sqrt(g L))

Two mistakes found in public codes are avoided on purpose and tested: the (1 + 1/cos psi)
factor multiplies the whole bending term, and the submersion term keeps its square root.

A broken channel needs no breaking: its resistance is the Finnish-Swedish rules' channel
formula (``rubble_resistance.brash_channel_resistance``). Open water gives no ice resistance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

OPEN_WATER, LEVEL_ICE, BROKEN_CHANNEL = 0, 1, 2


@dataclass(frozen=True)
class LindqvistTerms:
    """Lindqvist's static terms, N, for one ship and one ice condition."""

    crushing: float
    bending: float
    submersion: float


def bow_normal_angle(stem_angle: float, waterline_angle: float) -> float:
    """psi (rad): the inclination to the horizontal of the bow's surface normal plane at the
    waterline, tan psi = tan phi / sin alpha (Lindqvist 1989), from the stem angle phi and
    the waterline's entrance half-angle alpha (rad)."""
    return math.atan(math.tan(stem_angle) / math.sin(waterline_angle))


def lindqvist_terms(
    h: float, beam: float, length: float, draught: float, stem_angle: float, waterline_angle: float,
    flexural_strength: float, youngs_modulus: float, poisson_ratio: float, ice_density: float,
    water_density: float, friction: float, g: float,
) -> LindqvistTerms:
    """Static crushing, bending and submersion resistance (N). Angles in radians, SI units."""
    phi, alpha, mu = stem_angle, waterline_angle, friction
    psi = bow_normal_angle(phi, alpha)
    cphi, sphi, cpsi = math.cos(phi), math.sin(phi), math.cos(psi)
    crushing = 0.5 * flexural_strength * h * h * (math.tan(phi) + mu * cphi / cpsi) / (1.0 - mu * sphi / cpsi)
    stiffness = math.sqrt(youngs_modulus / (12.0 * (1.0 - poisson_ratio**2) * g * water_density))
    bending = (
        27.0 / 64.0 * flexural_strength * beam * h**1.5 / stiffness
        * (math.tan(psi) + mu * cphi / (math.sin(alpha) * cpsi))
        * (1.0 + 1.0 / cpsi)
    )
    t = draught
    submersion = (water_density - ice_density) * g * h * beam * (
        t * (beam + t) / (beam + 2.0 * t)
        + mu * (
            0.7 * length - t / math.tan(phi) - beam / (4.0 * math.tan(alpha))
            + t * cphi * cpsi * math.sqrt(1.0 / sphi**2 + 1.0 / math.tan(alpha) ** 2)
        )
    )
    return LindqvistTerms(crushing, bending, submersion)


def level_ice_resistance(terms: LindqvistTerms, speed: float, h: float, length: float, g: float) -> float:
    """Level-ice resistance (N, >= 0) at ship speed (m/s, >= 0) in ice h m thick (0 for none)."""
    if h <= 0.0:
        return 0.0
    return breaking_resistance(terms, speed, h, g) + submersion_resistance(terms, speed, length, g)


def submersion_resistance(terms: LindqvistTerms, speed: float, length: float, g: float) -> float:
    """The hull's share of the level-ice resistance (N): the broken pieces' submersion at
    speed (m/s) along a hull ``length`` m long."""
    return terms.submersion * (1.0 + 9.4 * speed / math.sqrt(g * length))


def breaking_resistance(terms: LindqvistTerms, speed: float, h: float, g: float) -> float:
    """The bow's share of the level-ice resistance (N): crushing and bending at speed (m/s)."""
    return (terms.crushing + terms.bending) * (1.0 + 1.4 * speed / math.sqrt(g * h))
