"""Heave, roll and pitch of free floes from buoyancy (paper §2.3 and its future work).

Per floe: (m (1 + C_a)) z'' = rho_s g V_sub - m g - c_z z', and I phi'' = M_B - c phi' for
roll and pitch, with M_B the moment of the buoyancy force about the centre of mass.
V_sub and the centre of buoyancy come from clipping the floe's triangles at the water plane
(``buoyancy``). Rotations use the small-angle form (Euler rates = body rates); the
hydrostatics themselves are exact at any angle. Semi-implicit Euler, sub-stepped.
"""
from __future__ import annotations

import numba
import numpy as np

from sim_core.ice.buoyancy import _floe_submerged


@numba.njit(cache=True, parallel=True)
def vertical_step(rows, gcell, tris, tri_start, mass, inertia, damping, added_mass,
                  rho_g, g, heave, roll, pitch, heave_rate, roll_rate, pitch_rate, dt, n_sub):
    """Advance heave/roll/pitch of floe rows by dt (n_sub semi-implicit sub-steps)."""
    h = dt / n_sub
    for k in numba.prange(len(rows)):
        i = rows[k]
        c = gcell[i]
        acc = np.zeros(4)
        m = mass[c]
        for _ in range(n_sub):
            _floe_submerged(tris, tri_start[c], tri_start[c + 1], heave[i], roll[i], pitch[i], acc)
            vol = acc[0] / 6.0
            fb = rho_g * vol
            xb = acc[1] / (4.0 * acc[0]) if acc[0] > 0.0 else 0.0
            yb = acc[2] / (4.0 * acc[0]) if acc[0] > 0.0 else 0.0
            fz = fb - m * g - damping[c, 0] * heave_rate[i]
            mx = yb * fb - damping[c, 1] * roll_rate[i]
            my = -xb * fb - damping[c, 2] * pitch_rate[i]
            heave_rate[i] += h * fz / (m * (1.0 + added_mass))
            roll_rate[i] += h * mx / inertia[c, 0]
            pitch_rate[i] += h * my / inertia[c, 1]
            heave[i] += h * heave_rate[i]
            roll[i] += h * roll_rate[i]
            pitch[i] += h * pitch_rate[i]
