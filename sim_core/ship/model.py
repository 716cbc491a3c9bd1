"""3-DOF MMG manoeuvring model (surge, sway, yaw) with steering gear, engine and ice load;
heave, roll and pitch (``sim_core.ship.motions``).

The MMG standard form of Yasukawa & Yoshimura (2015): hull, propeller and rudder forces
about midship, with the centre of gravity at x_G. ``compile_ship`` turns the particulars
(config units) into a static ``ShipModel`` in SI; ``ShipData`` is the small per-step state;
``step(model, data, dt)`` advances it (fixed-step RK4, sub-stepped to <= 0.1 s, so it is
stable at 60 Hz and at coarse replay steps alike).

Frames: earth x north, y east, z down; heading psi from north, clockwise positive; body u
forward, v to starboard, r clockwise. Rudder angle positive to starboard (turns the ship to
starboard); shaft speed negative astern. SI units inside: m, s, rad, kg, N, rev/s.

Two mistakes seen in public MMG codes are avoided and tested: the wake-fraction change with
beta_P is 1 - w_P = (1 - w_P0)(1 + (1 - exp(-C1 |beta_P|))(C2 - 1)) with the parenthesis
closing after (C2 - 1); and the rudder position x_R is dimensional (x'_R L) in N_R.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sim_core.frames.hull_contour import BOW_FRACTION, STERN_FRACTION
from sim_core.material import IceMaterial
from sim_core.ship.particulars import TELEGRAPH_POSITIONS, ShipParticulars
from sim_core.ship.resistance import LEVEL_ICE, OPEN_WATER, LindqvistTerms, bow_normal_angle, breaking_resistance, \
    lindqvist_terms, submersion_resistance
from sim_core.ship.rubble_resistance import BowForm, brash_channel_resistance, channel_speed_factor
from sim_core.ship.motions import MotionsModel, compile_motions, heeling_moment, step_motions

MAX_SUBSTEP = 0.1  # s
_U_MIN = 0.05  # m/s: floor of U where the hull's r^3 terms divide by U
_U_ICE = 0.01  # m/s: ice resistance fades in over this speed (static friction, no reversal)
_RPM_SNAP = 0.2 / 60.0  # rev/s: shaft speed counts as reached within 0.2 rpm


@dataclass(frozen=True)
class ShipModel:
    """Static, compiled ship (SI). Build with ``compile_ship``."""

    particulars: ShipParticulars
    material: IceMaterial  # the ice it breaks and the one sea water (rho) it floats in
    rho: float
    L: float
    B: float
    d: float
    mass: float
    x_g: float
    inv_sway_yaw: np.ndarray  # inverse of the 2x2 sway-yaw mass matrix
    surge_mass: float
    mass_plus_my: float
    mass_plus_mx: float
    hull: tuple  # (R0, Xvv, Xvr, Xrr, Xvvvv, Yv, Yr, Yvvv, Yvvr, Yvrr, Yrrr, Nv, Nr, Nvvv, Nvvr, Nvrr, Nrrr)
    d_p: float
    x_p: float  # non-dimensional (enters beta_P = beta - x'_P r')
    dp_over_hr: float  # propeller diameter / rudder span, D_P / H_R (MMG eta)
    x_r: float  # m
    x_h: float  # m
    rudder_limit: float  # rad
    rudder_rate: float  # rad/s
    telegraph_rps: dict
    rps_ahead_max: float
    rps_astern_max: float  # negative
    stem_angle: float
    waterline_angle: float
    bow_surface: tuple  # the bow's normal angle psi (rad) and sin(alpha): how pieces turn against it
    bow: BowForm  # for the brash channel's resistance
    motions: MotionsModel  # heave, roll and pitch


@dataclass
class ShipData:
    """Per-step state of one ship. Pose and velocity carry 6 DOF: surge, sway and yaw from
    the MMG model; heave, roll and pitch from the ice's lift at the bow and the lateral
    forces' heel (``sim_core.ship.motions``)."""

    eta: np.ndarray = field(default_factory=lambda: np.zeros(6))  # north, east, down m; roll, pitch, yaw rad
    nu: np.ndarray = field(default_factory=lambda: np.zeros(6))  # u, v, w m/s; p, q, r rad/s
    rudder: float = 0.0  # rad
    rudder_order: float = 0.0  # rad
    rps: float = 0.0  # shaft speed, rev/s
    rps_order: float = 0.0
    rotation: int = 0  # direction the engine last turned: +1 ahead, -1 astern, 0 never
    reverse_wait: float = 0.0  # s spent at rest waiting to reverse
    external: np.ndarray = field(default_factory=lambda: np.zeros(3))  # X, Y N; N N m at midship
    current: np.ndarray = field(default_factory=lambda: np.zeros(2))  # the water's velocity, north, east m/s
    ice_drift: np.ndarray = field(default_factory=lambda: np.zeros(2))  # the ice's through the water, north, east m/s
    steering_pumps: int = 2  # pumps of the steering gear working: 2 the design rate, 1 half, 0 the rudder stuck
    power_share: float = 1.0  # share of the engine's power available: 0 blackout, 1 all
    ice_h: float = 0.0  # local level-ice thickness, m
    ice_condition: int = OPEN_WATER
    ice_resistance: float = 0.0  # N, last step (>= 0, opposing the motion)
    brash_resistance: float = 0.0  # N at 5 knots: the brash at the bow (``rubble_resistance``)
    keel_load: float = 0.0  # N: the ridge keel at the bow
    _ice_terms: tuple = (None, None, 0.0)  # cache: (h, LindqvistTerms, channel resistance N at 5 knots)


def compile_ship(p: ShipParticulars, material: IceMaterial | None = None) -> ShipModel:
    """Precompute the SI model of a ship from its particulars, in the sea water (and ice) of
    ``material``."""
    material = material or IceMaterial()
    rho, L, d = material.water_density, p.length, p.draught
    mass = rho * p.displacement
    half = 0.5 * rho * L * L * d
    m_x, m_y, j_z = p.m_x * half, p.m_y * half, p.j_z * half * L * L
    i_zg = mass * (p.gyration_z * L) ** 2
    sway_yaw = np.array([[mass + m_y, p.x_g * mass], [p.x_g * mass, i_zg + p.x_g**2 * mass + j_z]])
    h = p.hull
    rpm = p.engine.telegraph_rpm
    stem, waterline = math.radians(p.ice.stem_angle_deg), math.radians(p.ice.waterline_angle_deg)
    return ShipModel(
        particulars=p, material=material, rho=rho, L=L, B=p.beam, d=d, mass=mass, x_g=p.x_g,
        inv_sway_yaw=np.linalg.inv(sway_yaw), surge_mass=mass + m_x,
        mass_plus_my=mass + m_y, mass_plus_mx=mass + m_x,
        hull=(h.R0, h.X_vv, h.X_vr, h.X_rr, h.X_vvvv, h.Y_v, h.Y_r, h.Y_vvv, h.Y_vvr, h.Y_vrr,
              h.Y_rrr, h.N_v, h.N_r, h.N_vvv, h.N_vvr, h.N_vrr, h.N_rrr),
        d_p=p.propeller.diameter, x_p=p.propeller.x_p, dp_over_hr=p.propeller.diameter / p.rudder.height,
        x_r=p.rudder.x_r * L, x_h=p.rudder.x_h * L,
        rudder_limit=math.radians(p.rudder.max_angle_deg), rudder_rate=math.radians(p.rudder.rate_deg_s),
        telegraph_rps={k: v / 60.0 for k, v in rpm.items()},
        rps_ahead_max=rpm["navigation_full_ahead"] / 60.0, rps_astern_max=rpm["crash_astern"] / 60.0,
        stem_angle=stem, waterline_angle=waterline,
        bow_surface=(bow_normal_angle(stem, waterline), math.sin(waterline)), bow=bow_form(p),
        motions=compile_motions(L, p.beam, d, p.displacement, rho, material.gravity, stem, material.hull_friction,
                                p.motions),
    )


def bow_form(p: ShipParticulars) -> BowForm:
    """The bow form of the waterline the ice world gives the hull (``waterline_contour``:
    a parabolic bow over ``BOW_FRACTION`` of the length, whose waterline area is 2/3 of its
    length times the beam), with the stem angle for the bow angle."""
    bow = BOW_FRACTION * p.length
    return BowForm(p.length, p.beam, p.draught, math.radians(p.ice.stem_angle_deg),
                   math.radians(p.ice.waterline_angle_deg), bow,
                   (1.0 - BOW_FRACTION - STERN_FRACTION) * p.length, 2.0 / 3.0 * bow * p.beam)


def level_ice_terms(model: ShipModel, h: float) -> LindqvistTerms:
    """Lindqvist's static terms for this ship in level ice of thickness h (m)."""
    m = model.material
    return lindqvist_terms(h, model.B, model.L, model.d, model.stem_angle, model.waterline_angle, m.flexural_strength,
                           m.youngs_modulus, m.poisson_ratio, m.density, model.rho, m.hull_friction, m.gravity)


def propeller_thrust(model: ShipModel, u: float, v: float, r: float, n: float) -> tuple[float, float, float]:
    """Propeller thrust T (N), K_T and the propeller inflow u_P = u (1 - w_P) (m/s)."""
    pr = model.particulars.propeller
    U = max(math.hypot(u, v), _U_MIN)
    beta = math.atan2(-v, abs(u))
    beta_p = beta - model.x_p * r * model.L / U
    c2 = pr.wake_c2_plus if beta_p > 0.0 else pr.wake_c2_minus
    one_minus_w = (1.0 - pr.w_p0) * (1.0 + (1.0 - math.exp(-pr.wake_c1 * abs(beta_p))) * (c2 - 1.0))
    u_p = u * one_minus_w
    if n == 0.0:
        return 0.0, 0.0, u_p
    j = u_p / (abs(n) * model.d_p)
    kt = pr.k0 + pr.k1 * j + pr.k2 * j * j if n > 0.0 else pr.ka0 + pr.ka1 * j
    thrust = math.copysign(model.rho * n * n * model.d_p**4 * kt, n)
    return thrust, kt, u_p


def mmg_forces(model: ShipModel, u: float, v: float, r: float, delta: float, n: float) -> tuple[float, float, float]:
    """Hull + propeller + rudder forces X, Y (N) and yaw moment N (N m) about midship."""
    (R0, Xvv, Xvr, Xrr, Xvvvv, Yv, Yr, Yvvv, Yvvr, Yvrr, Yrrr,
     Nv, Nr, Nvvv, Nvvr, Nvrr, Nrrr) = model.hull
    rho, L, d = model.rho, model.L, model.d
    U = math.hypot(u, v)
    Ue = max(U, _U_MIN)
    vp, rp = v / Ue, r * L / Ue
    q = 0.5 * rho * L * d
    # Hull: the U^2 of the non-dimensional form is kept inside each term, so the forces stay
    # finite as U -> 0; R'_0 acts against u.
    X_H = q * (-R0 * u * U + Ue * Ue * (Xvv * vp * vp + Xvr * vp * rp + Xrr * rp * rp + Xvvvv * vp**4))
    y_poly = Yv * vp + Yr * rp + Yvvv * vp**3 + Yvvr * vp * vp * rp + Yvrr * vp * rp * rp + Yrrr * rp**3
    n_poly = Nv * vp + Nr * rp + Nvvv * vp**3 + Nvvr * vp * vp * rp + Nvrr * vp * rp * rp + Nrrr * rp**3
    Y_H = q * Ue * Ue * y_poly
    N_H = q * L * Ue * Ue * n_poly

    thrust, kt, u_p = propeller_thrust(model, u, v, r, n)
    p = model.particulars
    X_P = (1.0 - p.propeller.t_p) * thrust

    ru = p.rudder
    if n > 0.0 and kt > 0.0:
        # u_R = eps u_P sqrt(eta (1 + kappa (sqrt(1 + 8 K_T / (pi J^2)) - 1))^2 + 1 - eta), written
        # with s = u_P sqrt(1 + 8 K_T / (pi J^2)) so it stays finite at J = 0 (bollard pull).
        s = math.sqrt(u_p * u_p + 8.0 * kt * (n * model.d_p) ** 2 / math.pi)
        u_r = ru.epsilon * math.sqrt(model.dp_over_hr * (u_p + ru.kappa * (s - u_p)) ** 2
                                      + (1.0 - model.dp_over_hr) * u_p * u_p)
    else:
        u_r = ru.epsilon * u_p
    beta = math.atan2(-v, abs(u))
    beta_r = beta - ru.l_r * rp
    gamma = ru.gamma_r_plus if beta_r > 0.0 else ru.gamma_r_minus
    v_r = U * gamma * beta_r
    alpha_r = delta - math.atan2(v_r, u_r) if (u_r != 0.0 or v_r != 0.0) else delta
    f_n = 0.5 * rho * ru.area * (u_r * u_r + v_r * v_r) * ru.f_alpha * math.sin(alpha_r)
    X_R = -(1.0 - ru.t_r) * f_n * math.sin(delta)
    Y_R = -(1.0 + ru.a_h) * f_n * math.cos(delta)
    N_R = -(model.x_r + ru.a_h * model.x_h) * f_n * math.cos(delta)
    return X_H + X_P + X_R, Y_H + Y_R, N_H + N_R


def state_derivatives(model: ShipModel, state: tuple, delta: float, n: float, ext: tuple, ice_x: float,
                      forces: tuple[float, float, float] | None = None) -> tuple:
    """Time derivative of (north, east, psi, u, v, r); ``forces``: the MMG forces at this
    state where already computed."""
    _, _, psi, u, v, r = state
    X, Y, N = forces if forces is not None else mmg_forces(model, u, v, r, delta, n)
    X += ext[0] + ice_x
    Y += ext[1]
    N += ext[2]
    m, xg = model.mass, model.x_g
    du = (X + model.mass_plus_my * v * r + xg * m * r * r) / model.surge_mass
    a, b = Y - model.mass_plus_mx * u * r, N - xg * m * u * r
    inv = model.inv_sway_yaw
    dv = inv[0, 0] * a + inv[0, 1] * b
    dr = inv[1, 0] * a + inv[1, 1] * b
    c, s = math.cos(psi), math.sin(psi)
    return (u * c - v * s, u * s + v * c, r, du, dv, dr)


def ice_force(model: ShipModel, data: ShipData, u: float) -> tuple[float, float]:
    """Surge force (N) of the ice resistance, against u, faded in near rest so that it can
    stop the ship but never drive it backwards: Lindqvist's in level ice; in a broken channel
    its pieces as brash (the concentration times their thickness) by the rules' channel
    resistance; plus the brash's and a ridge keel's at the bow. And the bow's share (N, >= 0,
    faded in alike: it lifts the bow): level ice's crushing and bending, the brash, the keel."""
    g = model.material.gravity
    r, bow, brash = data.keel_load, data.keel_load, data.brash_resistance
    if data.ice_condition != OPEN_WATER and data.ice_h > 0.0:
        if data._ice_terms[0] != data.ice_h:
            channel_brash = model.particulars.ice.channel_concentration * data.ice_h
            data._ice_terms = (data.ice_h, level_ice_terms(model, data.ice_h),
                               brash_channel_resistance(channel_brash, model.bow))
        _, terms, channel = data._ice_terms
        if data.ice_condition == LEVEL_ICE:
            breaking = breaking_resistance(terms, abs(u), data.ice_h, g)
            r, bow = r + (breaking + submersion_resistance(terms, abs(u), model.L, g)), bow + breaking
        else:
            brash += channel
    if brash > 0.0:
        pushed = brash * channel_speed_factor(u, model.L, g)
        r, bow = r + pushed, bow + pushed
    data.ice_resistance = r
    fade = min(1.0, abs(u) / _U_ICE)
    return -math.copysign(r, u) * fade, bow * fade


def _steering_gear(model: ShipModel, data: ShipData, dt: float) -> None:
    """The rudder towards its order at the gear's rate: two pumps running together give the
    design rate, each half of it, so with one failed the rudder moves at half the rate and
    with both failed it stays where it is."""
    step = model.rudder_rate * dt * data.steering_pumps / 2.0
    data.rudder += min(max(data.rudder_order - data.rudder, -step), step)


def _sign(x: float) -> int:
    return (x > 0.0) - (x < 0.0)


def _engine(model: ShipModel, data: ShipData, dt: float) -> None:
    """Shaft speed: first-order lag toward the order, rate-limited. A reversal first runs the
    shaft down to rest, then holds it there for the reversing delay before starting the
    other way; ``data.rotation`` remembers the last direction turned."""
    e = model.particulars.engine
    order, n = data.rps_order, data.rps
    # the propeller law: power grows as the cube of shaft speed, so a share of the power
    # turns the shaft at most at the cube root of that share of full speed
    cap = data.power_share ** (1.0 / 3.0)
    order = min(max(order, model.rps_astern_max * cap), model.rps_ahead_max * cap)
    want = _sign(order)
    target = order
    if n != 0.0 and _sign(n) != want:
        target = 0.0
    elif n == 0.0 and want != 0 and data.rotation not in (0, want):
        data.reverse_wait += dt
        if data.reverse_wait < e.reverse_delay_s:
            target = 0.0
    change = (target - n) * (1.0 - math.exp(-dt / e.time_constant_s))
    limit = e.rate_limit_rpm_s / 60.0 * dt
    n += min(max(change, -limit), limit)
    if abs(target - n) < _RPM_SNAP:
        n = target
    if n != 0.0:
        data.rotation = _sign(n)
        data.reverse_wait = 0.0
    data.rps = n


def step(model: ShipModel, data: ShipData, dt: float) -> None:
    """Advance the ship by dt seconds (sub-stepped to <= MAX_SUBSTEP). Orders, the ice
    condition, ``data.external``, ``current`` and ``ice_drift`` are held constant over dt.
    ``nu`` is the velocity through the water (the MMG model's); a uniform current carries
    the ship with the water, so its position moves by the current on top (the relative-
    velocity form of Fossen 2011, section 10.3, for an irrotational, constant current). The
    ice resists the surge over the ice (less the ice's drift through the water)."""
    if not (dt > 0.0 and math.isfinite(dt)):
        raise ValueError(f"step dt must be a positive number of seconds, got {dt!r}")
    n_sub = max(1, math.ceil(dt / MAX_SUBSTEP - 1e-9))
    h = dt / n_sub
    ext = (float(data.external[0]), float(data.external[1]), float(data.external[2]))
    eta, nu, (ice_n, ice_e) = data.eta, data.nu, data.ice_drift.tolist()
    for _ in range(n_sub):
        _steering_gear(model, data, h)
        _engine(model, data, h)
        s0 = (eta[0], eta[1], eta[5], nu[0], nu[1], nu[5])
        ice_x, bow = ice_force(model, data, s0[3] - ice_n * math.cos(s0[2]) - ice_e * math.sin(s0[2]))
        forces = mmg_forces(model, s0[3], s0[4], s0[5], data.rudder, data.rps)
        heel = heeling_moment(model.motions, forces[1], ext[1])
        k1 = state_derivatives(model, s0, data.rudder, data.rps, ext, ice_x, forces)
        k2 = state_derivatives(model, tuple(a + 0.5 * h * b for a, b in zip(s0, k1)), data.rudder, data.rps, ext, ice_x)
        k3 = state_derivatives(model, tuple(a + 0.5 * h * b for a, b in zip(s0, k2)), data.rudder, data.rps, ext, ice_x)
        k4 = state_derivatives(model, tuple(a + h * b for a, b in zip(s0, k3)), data.rudder, data.rps, ext, ice_x)
        s1 = [a + h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4) for a, b1, b2, b3, b4 in zip(s0, k1, k2, k3, k4)]
        eta[0], eta[1], eta[5], nu[0], nu[1], nu[5] = s1
        eta[0] += h * data.current[0]
        eta[1] += h * data.current[1]
        step_motions(model.motions, eta, nu, bow, heel, h)


def new_ship_data(model: ShipModel, speed: float = 0.0, rps: float | None = None, heading: float = 0.0) -> ShipData:
    """Ship at rest or steaming straight at speed (m/s) on heading (rad); the shaft turns at
    rps (default: the open-water equilibrium for that speed)."""
    data = ShipData()
    data.nu[0] = speed
    data.eta[5] = heading
    n = equilibrium_rps(model, speed) if rps is None else rps
    data.rps = data.rps_order = n
    data.rotation = 0 if n == 0.0 else (1 if n > 0 else -1)
    return data


def equilibrium_rps(model: ShipModel, speed: float, ice_h: float = 0.0, ice_condition: int = OPEN_WATER) -> float:
    """Shaft speed (rev/s) holding a steady straight course at speed (m/s), found by
    bisection on the surge force; capped at navigation full ahead."""
    if speed <= 0.0:
        return 0.0
    probe = ShipData(ice_h=ice_h, ice_condition=ice_condition)
    ice_x, _ = ice_force(model, probe, speed)

    def surge(n: float) -> float:
        return mmg_forces(model, speed, 0.0, 0.0, 0.0, n)[0] + ice_x

    lo, hi = 0.0, model.rps_ahead_max
    if surge(hi) < 0.0:
        return hi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if surge(mid) < 0.0 else (lo, mid)
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class OrderRejection:
    """An order the ship did not take as given: ``refused`` (not obeyed at all, the previous
    order held) or clamped to a limit; ``order`` is "rudder", "telegraph" or "lever"."""

    order: str
    refused: bool
    text: str


def order_rudder(model: ShipModel, data: ShipData, angle: float) -> OrderRejection | None:
    """Set the rudder order (rad, + starboard). Returns None if taken as given, else why it
    was clamped or refused (a NaN or infinite order keeps the previous one)."""
    if not math.isfinite(angle):
        return OrderRejection("rudder", True, f"rudder order {angle!r} rejected (not a number); holding "
                                              f"{math.degrees(data.rudder_order):.1f} deg")
    lim = model.rudder_limit
    data.rudder_order = min(max(angle, -lim), lim)
    if data.rudder_order != angle:
        return OrderRejection("rudder", False, f"rudder order {math.degrees(angle):.1f} deg clamped to the "
                                               f"{math.degrees(lim):.0f} deg limit")
    return None


def order_telegraph(model: ShipModel, data: ShipData, position: str) -> OrderRejection | None:
    """Set the engine order from a telegraph position name. Unknown names are refused."""
    if position not in model.telegraph_rps:
        return OrderRejection("telegraph", True, f"unknown telegraph position {position!r} rejected; "
                                                 f"allowed: {', '.join(TELEGRAPH_POSITIONS)}")
    data.rps_order = model.telegraph_rps[position]
    return None


def order_lever(model: ShipModel, data: ShipData, percent: float) -> OrderRejection | None:
    """Set the engine order from a continuous lever, -100..100 %: +100 % is navigation full
    ahead, -100 % crash astern, linear in between. Out-of-range values are clamped; NaN is
    refused."""
    if not math.isfinite(percent):
        return OrderRejection("lever", True, f"lever {percent!r} % rejected (not a number)")
    p = min(max(percent, -100.0), 100.0)
    data.rps_order = p / 100.0 * (model.rps_ahead_max if p >= 0.0 else -model.rps_astern_max)
    if p != percent:
        return OrderRejection("lever", False, f"lever {percent:.1f} % clamped to {p:.0f} %")
    return None
