"""Heave, roll and pitch of free floes from buoyancy (paper §2.3 and its future work).

Per floe: (m (1 + C_a)) z'' = rho_s g V_sub - m g - c_z z', and I phi'' = M_B - c phi' for
roll and pitch, with M_B the moment of the buoyancy force about the centre of mass.
V_sub and the centre of buoyancy come from clipping the floe's triangles at the water plane
(``buoyancy``). Rotations use the small-angle form (Euler rates = body rates); the
hydrostatics themselves are exact at any angle. Semi-implicit Euler, sub-stepped.

The kernel is compiled twice, serial and parallel over floes. The parallel one pays only
for many floes: on a loaded machine a parallel region waits for its slowest thread, and a
thread that has lost its core costs a scheduler time slice (milliseconds), far more than
clipping a few hundred floes serially.
"""
from __future__ import annotations

import numba
import numpy as np

from sim_core.ice.buoyancy import _floe_submerged


PARALLEL_FROM = 4000  # floes: below this the serial kernel runs
# m, rad, m/s, rad/s: a floe this close to rest at its draft is left alone. Above the
# floor of the state's float32 rounding: a floe stepped from 8 cm and 0.02 rad off its
# draft stops in a fixed point of the rounding within 20 s, 4e-8 off with rates of 2.5e-7,
# and never came within 1e-7: it was stepped for ever, and never rested far from the hull
# (146 of the 180 floes awake beyond 200 m of the hull after 270 s of the pack exercise).
SETTLED = 1e-5


@numba.njit(cache=True)
def settled(i, gcell, z_equilibrium, heave, roll, pitch, heave_rate, roll_rate, pitch_rate) -> bool:
    """Whether row i floats at rest at its draft (within ``SETTLED``). In-plane contact
    does not couple into heave, roll or pitch, so a settled floe stays settled."""
    off = abs(heave[i] - z_equilibrium[gcell[i]]) + abs(roll[i]) + abs(pitch[i])
    rates = abs(heave_rate[i]) + abs(roll_rate[i]) + abs(pitch_rate[i])
    return off <= SETTLED and rates <= SETTLED


def _vertical_kernel(rows, gcell, tris, tri_start, mass, inertia, damping, added_mass,
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


_serial = numba.njit(cache=True)(_vertical_kernel)
_parallel = numba.njit(cache=True, parallel=True)(_vertical_kernel)


def vertical_step(rows: np.ndarray, gcell: np.ndarray, tris: np.ndarray, tri_start: np.ndarray, mass: np.ndarray,
                  inertia: np.ndarray, damping: np.ndarray, added_mass: float, rho_g: float, g: float,
                  heave: np.ndarray, roll: np.ndarray, pitch: np.ndarray, heave_rate: np.ndarray,
                  roll_rate: np.ndarray, pitch_rate: np.ndarray, dt: float, n_sub: int) -> None:
    """Advance heave (m), roll and pitch (rad) and their rates of floe rows (n,) by dt (s)
    in n_sub semi-implicit sub-steps, in place. rho_g: sea water density times g, N/m3."""
    kernel = _parallel if len(rows) >= PARALLEL_FROM else _serial
    kernel(rows, gcell, tris, tri_start, mass, inertia, damping, added_mass, rho_g, g,
           heave, roll, pitch, heave_rate, roll_rate, pitch_rate, dt, n_sub)


def warm_up(tris: np.ndarray, tri_start: np.ndarray, mass: np.ndarray, inertia: np.ndarray,
            damping: np.ndarray) -> None:
    """Load both compiled kernels (numba compiles or loads on first call) for the state's dtypes."""
    rows, f32 = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.float32)
    for kernel in (_serial, _parallel):
        kernel(rows, np.zeros(0, np.int32), tris, tri_start, mass, inertia, damping, 0.5, 1.0e4, 9.81,
               f32, f32, f32, f32, f32, f32, 0.01, 1)

