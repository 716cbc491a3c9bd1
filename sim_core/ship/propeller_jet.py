"""The propeller's jet: the wash that churns the broken ice astern (and ahead, going astern).

The jet leaves the propeller with the slipstream speed of momentum theory (the actuator
disc of Rankine 1865 and Froude 1889): a disc of diameter D giving thrust T while advancing
at V_A through the water accelerates it, far behind the disc, by
U_0 = sqrt(V_A^2 + 8 T / (rho pi D^2)) - V_A, in a slipstream of half the disc's area,
D_0 = D / sqrt(2). At the bollard (V_A = 0) this is U_0 = 1.6 n D sqrt(K_T), the efflux speed
Blaauw & van de Kaa (1978, "Erosion of bottom and sloping banks caused by the screw race of
manoeuvring ships", Delft Hydraulics publication 202) take for a propeller's jet, with
D_0 = 0.71 D.

Beyond the propeller the jet spreads as a free, submerged, axisymmetric jet (Albertson,
Dai, Jensen & Rouse 1950, "Diffusion of submerged jets", Trans. ASCE 115): past the zone
of flow establishment, 6.2 D_0, the centreline speed falls as U_0 6.2 D_0 / x and the
profile across the jet is Gaussian, u = u_m exp(-r^2 / (2 (0.081 x)^2)). Here that profile
holds from the propeller on, the centreline speed capped at U_0: within the zone of
establishment it is too narrow near the axis, but the floes float at the surface, 1.5 D_0 or
more above the shaft of a ship's propeller, where the jet arrives only as it spreads.

The jet is left out beyond 25 D_0 (99 m for the default ship), where its centreline speed
has fallen to a quarter. Under way the hull's frictional wake, which the ship drags forward,
carries back the momentum the jet adds: the far wake of a self-propelled ship carries none,
its thrust equalling its resistance. So the still-water jet overstates the far wash of a ship
under way (and leaves out some of it at the bollard), and floes it pushed would be kept
moving far astern, each a body the contact engine steps. Other simplifications, all of them
the still-water jet's: the ship's own advance (a jet behind a moving ship is swept back into
a trail), the hull and the free surface above the jet, and the rudder, which deflects it,
are not modelled. The shaft's depth is not in the ship
file: its axis is put 0.55 D above the keel (a tip clearance of 5 % of D).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ESTABLISHED = 6.2  # x / D_0 where the zone of flow establishment ends (Albertson et al. 1950)
SPREAD = 0.081  # the Gaussian's standard deviation over x (Albertson et al. 1950)
REACH = 25.0  # x / D_0 beyond which the jet is left out (its centreline at 25 % of U_0): module docstring
AXIS_HEIGHT = 0.55  # shaft axis above the keel over D


@dataclass(frozen=True)
class PropellerJet:
    """One propeller's jet in the ice world: where it starts (world m, x east, y north), the
    unit vector it flows along, its efflux speed U_0 (m/s, relative to the water), its
    diameter D_0 (m) and the depth of its axis below the surface (m)."""

    origin: np.ndarray
    axis: np.ndarray
    speed: float
    diameter: float
    depth: float


def slipstream_speed(thrust: float, advance: float, diameter: float, density: float) -> float:
    """Momentum theory's far slipstream speed U_0 (m/s) behind a disc of ``diameter`` (m)
    giving ``thrust`` (N, >= 0) while advancing at ``advance`` (m/s, >= 0) through water of
    ``density`` (kg/m^3)."""
    return math.sqrt(advance * advance + 8.0 * thrust / (density * math.pi * diameter * diameter)) - advance


def propeller_jet(origin: np.ndarray, heading: np.ndarray, thrust: float, advance: float, diameter: float,
                  draught: float, density: float) -> PropellerJet | None:
    """The jet of a propeller at ``origin`` (world m) on a ship heading along the unit world
    vector ``heading``, giving ``thrust`` (N; negative: astern, the jet flows forward) while
    its inflow is ``advance`` (m/s, + ahead); propeller diameter and draught in m. None while
    it gives no thrust."""
    if thrust == 0.0:
        return None
    ahead = thrust > 0.0
    inflow = max(0.0, advance if ahead else -advance)
    speed = slipstream_speed(abs(thrust), inflow, diameter, density)
    axis = -np.asarray(heading, dtype=np.float64) if ahead else np.asarray(heading, dtype=np.float64)
    return PropellerJet(np.asarray(origin, dtype=np.float64), axis, speed, diameter / math.sqrt(2.0),
                        draught - AXIS_HEIGHT * diameter)


def jet_velocity(jet: PropellerJet, xy: np.ndarray) -> np.ndarray:
    """The jet's water velocity (n, 2), m/s, at the surface at points ``xy`` (n, 2), world
    m: along the jet's axis, Albertson's Gaussian about it at the axis's depth; zero ahead of
    the propeller and beyond ``REACH`` D_0."""
    rel = np.asarray(xy, dtype=np.float64) - jet.origin
    along = rel @ jet.axis
    across = rel[:, 0] * jet.axis[1] - rel[:, 1] * jet.axis[0]
    inside = (along > 0.0) & (along < REACH * jet.diameter)
    x = np.where(inside, along, 1.0)
    centre = jet.speed * np.minimum(1.0, ESTABLISHED * jet.diameter / x)
    sigma = SPREAD * x
    speed = np.where(inside, centre * np.exp(-(across * across + jet.depth * jet.depth) / (2.0 * sigma * sigma)), 0.0)
    return speed[:, None] * jet.axis[None, :]
