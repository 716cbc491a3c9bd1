"""When an intact cell breaks free: the hull touches it, or a moving neighbour loads it past
its capacity. Capacities are physical and depend on thickness and impact speed.

The edge's load capacity is the bending load of a floating ice wedge, F_s = C_w sigma_f h^2.
C_w comes from the paper's Table 3 (Lubbad & Løset: four 45-degree wedges fail at 81 kN each
for h = 1 m and sigma_f = 500 kPa, so C_w = 0.162). Loaded to F_s, the edge stores the elastic
energy F_s^2 / (2 k), with k = rho_w g l_c^2 the edge stiffness of a floating plate (l_c its
characteristic length).

A contact breaks the edge when the kinetic energy it takes out of the striking floe reaches
that energy: J v_n / 2 >= F_s^2 / (2 k). J is the contact's normal impulse. v_n is the
impact speed: the striker's approach speed, or J / m (the normal velocity the contact took
out of it), whichever is larger. So the impulse capacity is J_cap(h, v_n) = F_s^2 / (k v_n).
It falls with impact speed, so a faster ship breaks a wider band. It grows as
h^4 / h^1.5 = h^2.5 against a floe mass growing as h, so thicker ice needs faster impacts:
the critical speed sqrt(K / m) is about 0.3 m/s for 0.2 m ice and 0.7 m/s for 1.0 m ice.

A floe jammed between the hull and the level ice takes a large impulse (the kinematic hull
has infinite mass). Through J / m that breaks the edge, which is how rigid colliders
conduct cracking, and why mesh colliders, whose faces touch, conduct it far too widely
(paper §3.2). A quasi-static test J / dt >= F_s is not used: it depends on the step size.
"""
from __future__ import annotations

import numpy as np

from sim_core.material import IceMaterial, characteristic_length

WEDGE_COEFFICIENT = 0.162  # 81 kN / (500 kPa * 1 m^2), paper Table 3


def static_capacity(h: float | np.ndarray, mat: IceMaterial, c_w: float = WEDGE_COEFFICIENT):
    """Quasi-static breaking force F_s = C_w sigma_f h^2, N."""
    return c_w * mat.flexural_strength * np.asarray(h) ** 2


def impact_constant(h: float | np.ndarray, mat: IceMaterial, c_w: float = WEDGE_COEFFICIENT):
    """K in J_cap = K / v_n: F_s^2 / (rho_w g l_c^2), N^2 s^2 / (kg m) = N s * m/s."""
    h = np.asarray(h, dtype=float)
    lc = np.vectorize(lambda x: characteristic_length(float(x), mat))(h)
    return static_capacity(h, mat, c_w) ** 2 / (mat.water_density * mat.gravity * lc**2)


def breaks(impulse: np.ndarray, approach_speed: np.ndarray, striker_mass: np.ndarray,
           k_impact: np.ndarray) -> np.ndarray:
    """True where a contact breaks the cell: J v_n >= K, v_n = max(approach speed, J / m)."""
    return impulse * np.maximum(approach_speed, impulse / striker_mass) >= k_impact
