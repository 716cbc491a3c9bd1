"""When an intact cell breaks free: the hull touches it, or a moving neighbour loads it past
its capacity. Capacities are physical and depend on thickness and impact speed.

The edge's load capacity is the bending load of a floating ice wedge, F_s = C_w sigma_f h^2.
C_w comes from the paper's Table 3 (Lubbad & Løset: four 45-degree wedges fail at 81 kN each
for h = 1 m and sigma_f = 500 kPa, so C_w = 0.162). Loaded to F_s, the edge stores the elastic
energy F_s^2 / (2 k), with k = rho_w g l_c^2 the edge stiffness of a floating plate (l_c its
characteristic length).

A contact breaks the edge when two things hold.

1. **Energy**: the kinetic energy it takes out of the striking floe reaches that energy:
   J v_n / 2 >= F_s^2 / (2 k). J is the contact's normal impulse. v_n is the impact speed:
   the striker's approach speed, or J / m (the normal velocity the contact took out of it),
   whichever is larger. So the impulse capacity is J_cap(h, v_n) = F_s^2 / (k v_n). It falls
   with impact speed, so a faster ship breaks a wider band, and it grows as h^2.5 against a
   floe mass growing as h: the critical speed sqrt(K / m) is about 0.3 m/s for 0.2 m ice and
   0.7 m/s for 1.0 m ice.
2. **Load**: the striker can load the edge with F_s at all. F_s is a vertical load (the
   wedge bends down or up), and a floe pushed against the edge loads it vertically only by
   riding onto it or being forced under it, as blocks load the parent sheet in pressure
   ridging (Parmerter & Coon 1972, "Model of pressure ridge formation in sea ice", J.
   Geophys. Res. 77(33); Hopkins 1998, "Four stages of pressure ridging", J. Geophys. Res.
   103(C10)). Riding onto the edge, a rigid floe rests at most half its weight on it: with
   its tip on the edge and its far end still at the waterline it is a beam on two supports,
   each carrying m g / 2. Forced under, it pushes up with its net buoyancy
   (rho_w - rho_i) g V, about m g / 7, less. So a floe whose ride-up load
   ``ride_up_share`` m g is below F_s cannot break the edge, however hard it is pushed.

Why the load bound is needed (measured on 3 x 50 m tiles, hybrid colliders, 3 kn, before it
existed): a floe jammed between the kinematic hull (infinite mass) and the level ice takes
whatever impulse stops the hull's penetration. J / m read 0.55-0.86 m/s against approach
speeds of 0.03-0.12 m/s, and the push from behind balanced 0.91-0.99 of the impulse on the
edge: 83-99 % of the contact breaks were such squeezes (43-55 % with the striker on the hull
itself, 69-87 % with it on the hull or pressed by a floe that was). The energy test then passes whatever the edge's
strength: at 1.0 m an edge 12 times stronger (K x 144) still lost 42 cells against 53, and
conduction cracking barely depended on thickness. With the load bound, thin edges (F_s =
3.2 kN at 0.2 m; a mean 0.2 m floe rides up with about 4 kN) still break under squeezes,
while thick ones (81 kN at 1.0 m, against about 40 kN) hold. A floe that holds should then
ride under the edge; the planar contact keeps it jammed instead, and the jam loads the hull
. In the planar model it would stay jammed, and the jam would load the hull with what the
edge no longer takes (the ship slowed from 7.3 to 6 kn in 0.5 m ice and stopped in 1.0 m
ice); so the ice step forces such a floe under the edge, out of planar contact until the
hull has passed, as it does with floes under the bow. A quasi-static test J / dt >= F_s is
not used: it depends on the step size.
"""
from __future__ import annotations

import numba
import numpy as np

from sim_core.material import IceMaterial, characteristic_length

WEDGE_COEFFICIENT = 0.162  # 81 kN / (500 kPa * 1 m^2), paper Table 3
RIDE_UP_SHARE = 0.5  # share of its weight a floe riding onto an edge rests on it


def static_capacity(h: float | np.ndarray, mat: IceMaterial, c_w: float = WEDGE_COEFFICIENT) -> np.ndarray:
    """Quasi-static breaking force F_s = C_w sigma_f h^2, N."""
    return c_w * mat.flexural_strength * np.asarray(h) ** 2


def impact_constant(h: float | np.ndarray, mat: IceMaterial, c_w: float = WEDGE_COEFFICIENT) -> np.ndarray:
    """K in J_cap = K / v_n: F_s^2 / (rho_w g l_c^2), N^2 s^2 / (kg m) = N s * m/s."""
    h = np.asarray(h, dtype=float)
    lc = np.vectorize(lambda x: characteristic_length(float(x), mat))(h)
    return static_capacity(h, mat, c_w) ** 2 / (mat.water_density * mat.gravity * lc**2)


def ride_up_load(mass: np.ndarray, mat: IceMaterial, share: float = RIDE_UP_SHARE) -> np.ndarray:
    """Largest vertical load (N) a floe of mass (kg) puts on an edge it rides onto: share m g."""
    return share * np.asarray(mass) * mat.gravity


@numba.njit(cache=True)
def pushed_hard(impulse: np.ndarray, approach_speed: np.ndarray, striker_mass: np.ndarray,
                k_impact: np.ndarray) -> np.ndarray:
    """The energy test: J v_n >= K, v_n = max(approach speed, J / m); impulse N s, speed
    m/s, mass kg, K N s * m/s (arrays or scalars; compiled, so the ice step's contact
    kernel applies the same test)."""
    return impulse * np.maximum(approach_speed, impulse / striker_mass) >= k_impact


def breaks(impulse: np.ndarray, approach_speed: np.ndarray, striker_mass: np.ndarray, k_impact: np.ndarray,
           striker_load: np.ndarray, edge_capacity: np.ndarray) -> np.ndarray:
    """True where a contact breaks the cell: the energy test (``pushed_hard``) and the load
    test: the striker's ride-up load (N) reaches the edge's capacity F_s (N). A striker
    pushed hard that fails the load test cannot break the edge and is forced under it (the
    ice step takes it out of planar contact until the hull has passed)."""
    return pushed_hard(impulse, approach_speed, striker_mass, k_impact) & (striker_load >= edge_capacity)
