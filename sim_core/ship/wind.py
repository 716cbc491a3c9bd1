"""The wind load on the ship, by the approximate wind coefficients of large ships in
T. I. Fossen, *Handbook of Marine Craft Hydrodynamics and Motion Control*, Wiley 2011,
section 8.1.1 (the "wind forces and moments" of ships):

    X = 1/2 rho V_rw^2 C_X(gamma) A_Fw,     C_X = -c_x cos(gamma)
    Y = 1/2 rho V_rw^2 C_Y(gamma) A_Lw,     C_Y =  c_y sin(gamma)
    N = 1/2 rho V_rw^2 C_N(gamma) A_Lw L_oa, C_N =  c_n sin(2 gamma)

with the relative wind u_rw = u - u_w, v_rw = v - v_w (body axes, the wind's velocity
u_w, v_w in them), V_rw its speed and gamma = -atan2(v_rw, u_rw) its angle of attack (0:
head wind). A wind from starboard pushes the ship to port (Y < 0). The coefficients and
areas come from the ship file (``Windage``).
"""
from __future__ import annotations

import math

from sim_core.environment import RHO_AIR, Environment
from sim_core.ship.particulars import Windage


def wind_load(windage: Windage | None, u: float, v: float, heading: float,
              environment: Environment) -> tuple[float, float, float]:
    """Wind force and moment on the ship.

    Parameters
    ----------
    windage : the ship's areas and coefficients; None: no load
    u, v : surge and sway over ground, m/s (+ forward, + to starboard)
    heading : rad, clockwise from north
    environment : the wind (speed m/s, direction it blows from, rad)

    Returns
    -------
    X, Y (N, ship axes: + forward, + starboard) and N (N m, + turning to starboard)
    """
    if windage is None or environment.wind_speed == 0.0:
        return 0.0, 0.0, 0.0
    wn, we = environment.wind_north_east()
    c, s = math.cos(heading), math.sin(heading)
    u_rw, v_rw = u - (wn * c + we * s), v - (-wn * s + we * c)
    gamma = -math.atan2(v_rw, u_rw)
    q = 0.5 * RHO_AIR * (u_rw * u_rw + v_rw * v_rw)
    return (-q * windage.c_x * math.cos(gamma) * windage.frontal_area,
            q * windage.c_y * math.sin(gamma) * windage.lateral_area,
            q * windage.c_n * math.sin(2.0 * gamma) * windage.lateral_area * windage.length_overall)
