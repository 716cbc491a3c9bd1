"""Sea-ice and sea-water material constants, and derived plate quantities (SI units)."""
from __future__ import annotations

from pydantic import Field

from sim_core.params import Params


class IceMaterial(Params):
    """Mechanical constants of level sea ice and the water it floats on.

    Defaults: Lubbad & Løset's ice (paper Table 2) and the paper's §2.3 sea water
    (rho_s = 1027 kg/m3, g = 9.826 m/s2 at 70 deg N). ``water_density`` is the one sea-water
    density of the exercise: the ship's hull and the floes float in the same water.
    """

    density: float = Field(900.0, gt=700.0, lt=1000.0, description="ice density, kg/m3")
    youngs_modulus: float = Field(3.0e9, gt=1.0e8, le=2.0e10, description="E, Pa")
    poisson_ratio: float = Field(0.33, gt=0.0, lt=0.5, description="nu, -")
    flexural_strength: float = Field(500.0e3, gt=1.0e4, le=5.0e6, description="sigma_f, Pa")
    water_density: float = Field(1027.0, gt=990.0, lt=1050.0, description="rho_s, kg/m3")
    gravity: float = Field(9.826, gt=9.7, lt=9.9, description="g, m/s2")
    hull_friction: float = Field(0.1, ge=0.0, le=1.0, description="ice-hull friction coefficient, -")


def characteristic_length(h: float, mat: IceMaterial) -> float:
    """Characteristic length l_c of a floating elastic plate of thickness h (m), in m.

    l_c = (E h^3 / (12 (1 - nu^2) rho_w g))^(1/4).
    """
    d = mat.youngs_modulus * h**3 / (12.0 * (1.0 - mat.poisson_ratio**2))
    return (d / (mat.water_density * mat.gravity)) ** 0.25

