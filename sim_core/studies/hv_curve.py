"""The h-v curve: the speed a ship attains straight ahead in level ice at full power, against
the ice thickness, and the thickness at which it sticks.

The speed is the root of the ship model's own surge balance, so the curve is what the
simulator does, not a separate estimate: the MMG hull and propeller forces (``mmg_forces``,
shaft at navigation full ahead) against Lindqvist's (1989) level-ice resistance
(``sim_core.ship.resistance``). Both sides are monotonic in speed (thrust falls and
resistance grows with it), so the balance has one root, found by bisection. The ship sticks
where the thrust at rest no longer beats the ice's resistance at rest; beyond that
thickness it creeps at under the model's fade-in speed of the ice force (1 cm/s) and makes
way only by ramming.
"""
from __future__ import annotations

import math

import numpy as np

from sim_core.ship.model import ShipModel, level_ice_terms, mmg_forces
from sim_core.ship.resistance import LindqvistTerms, level_ice_resistance

MAX_THICKNESS = 3.0  # m: Lindqvist's method is used up to here
_BISECTIONS = 60


def surge_balance(model: ShipModel, speed: float, thickness: float, rps: float,
                  terms: LindqvistTerms | None = None) -> float:
    """Net surge force (N) on the ship straight ahead at ``speed`` (m/s, >= 0) with the shaft
    at ``rps`` (rev/s) in level ice ``thickness`` (m): the MMG forces less the ice resistance.
    ``terms``: Lindqvist's static terms at that thickness, where the caller has them."""
    ice = 0.0
    if thickness > 0.0:
        ice = level_ice_resistance(terms or level_ice_terms(model, thickness), speed, thickness, model.L,
                                   model.material.gravity)
    return mmg_forces(model, speed, 0.0, 0.0, 0.0, rps)[0] - ice


def attainable_speed(model: ShipModel, thickness: float) -> float:
    """Speed (m/s) the ship holds at full power in level ice of ``thickness`` (m); 0 where
    it sticks."""
    n, terms = model.rps_ahead_max, level_ice_terms(model, thickness)

    def balance(speed: float) -> float:
        return surge_balance(model, speed, thickness, n, terms)

    if balance(0.0) <= 0.0:
        return 0.0
    hi = 1.0
    while balance(hi) > 0.0:
        hi *= 2.0
    lo = 0.0
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if balance(mid) > 0.0 else (lo, mid)
    return 0.5 * (lo + hi)


def sticking_thickness(model: ShipModel) -> float:
    """The level-ice thickness (m) at which the ship at full power stops; ``inf`` if it
    makes way through MAX_THICKNESS."""
    n = model.rps_ahead_max
    if surge_balance(model, 0.0, MAX_THICKNESS, n) > 0.0:
        return math.inf
    lo, hi = 0.0, MAX_THICKNESS
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if surge_balance(model, 0.0, mid, n) > 0.0 else (lo, mid)
    return 0.5 * (lo + hi)


def hv_curve(model: ShipModel, thicknesses: np.ndarray) -> np.ndarray:
    """Attainable speed (m/s) at full power for each level-ice thickness (m).

    Parameters
    ----------
    model : the compiled ship.
    thicknesses : (K,) level-ice thicknesses, m, each in [0, MAX_THICKNESS].

    Returns
    -------
    (K,) speeds, m/s; 0 where the ship sticks.
    """
    return np.array([attainable_speed(model, float(h)) for h in thicknesses])
