"""Ship particulars: the config schema of a ship for the MMG manoeuvring model.

Names follow Yasukawa & Yoshimura (2015), "Introduction of MMG standard method for ship
maneuvering predictions", J. Mar. Sci. Technol. 20:37-52. Primed quantities are
non-dimensional (forces by 0.5 rho L d U^2, moments by 0.5 rho L^2 d U^2, masses by
0.5 rho L^2 d, inertia by 0.5 rho L^4 d, positions by L). Angles here are in degrees, speeds
in knots and shaft speeds in rpm, because people write them so; ``compile_ship`` converts
everything to SI once.
"""
from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from sim_core.params import Params

TELEGRAPH_POSITIONS = (
    "crash_astern", "full_astern", "half_astern", "slow_astern", "dead_slow_astern", "stop",
    "dead_slow_ahead", "slow_ahead", "half_ahead", "full_ahead", "navigation_full_ahead",
)


class HullDerivatives(Params):
    """Hull force derivatives (non-dimensional) of the MMG standard form."""

    R0: float = Field(gt=0.0, lt=0.2, description="resistance coefficient R'_0")
    X_vv: float
    X_vr: float
    X_rr: float
    X_vvvv: float
    Y_v: float = Field(lt=0.0)
    Y_r: float
    Y_vvv: float
    Y_vvr: float
    Y_vrr: float
    Y_rrr: float
    N_v: float = Field(lt=0.0)
    N_r: float = Field(lt=0.0)
    N_vvv: float
    N_vvr: float
    N_vrr: float
    N_rrr: float


class Propeller(Params):
    """Single fixed-pitch propeller. K_T(J) = k0 + k1 J + k2 J^2 ahead; astern (shaft
    reversed) K_T = ka0 + ka1 J with J = u (1 - w_P) / (|n| D) (ship still going ahead)."""

    diameter: float = Field(gt=0.1, lt=20.0, description="D_P, m")
    x_p: float = Field(gt=-0.8, lt=0.0, description="x'_P, propeller position / L")
    t_p: float = Field(ge=0.0, lt=0.6, description="thrust deduction t_P")
    w_p0: float = Field(ge=0.0, lt=0.8, description="wake fraction in straight motion w_P0")
    k0: float = Field(gt=0.0, lt=1.0)
    k1: float
    k2: float
    ka0: float = Field(gt=0.0, lt=1.0, description="astern K_T at J = 0")
    ka1: float = Field(0.1, description="astern K_T slope with J")
    wake_c1: float = Field(2.0, ge=0.0, description="C_1 of the wake change with beta_P")
    wake_c2_plus: float = Field(1.6, ge=1.0, description="C_2 for beta_P > 0")
    wake_c2_minus: float = Field(1.1, ge=1.0, description="C_2 for beta_P < 0")


class Rudder(Params):
    """Rudder, hull-rudder interaction and steering gear."""

    area: float = Field(gt=0.1, lt=500.0, description="A_R, m2")
    height: float = Field(gt=0.1, lt=40.0, description="H_R, m")
    x_r: float = Field(-0.5, ge=-0.6, lt=0.0, description="x'_R, rudder position / L")
    t_r: float = Field(ge=0.0, lt=1.0, description="steering resistance deduction t_R")
    a_h: float = Field(ge=0.0, lt=1.5, description="rudder force increase factor a_H")
    x_h: float = Field(gt=-0.8, lt=0.0, description="x'_H, position of the extra lateral force / L")
    gamma_r_plus: float = Field(gt=0.0, lt=1.5, description="flow straightening gamma_R, beta_R > 0")
    gamma_r_minus: float = Field(gt=0.0, lt=1.5, description="flow straightening gamma_R, beta_R < 0")
    l_r: float = Field(lt=0.0, gt=-2.0, description="l'_R, effective longitudinal coordinate")
    epsilon: float = Field(gt=0.5, lt=2.0, description="wake ratio rudder/propeller epsilon")
    kappa: float = Field(gt=0.0, lt=1.0, description="propeller slipstream factor kappa")
    f_alpha: float = Field(gt=0.5, lt=8.0, description="rudder lift gradient f_alpha")
    max_angle_deg: float = Field(35.0, gt=5.0, le=70.0, description="rudder limit, deg")
    rate_deg_s: float = Field(
        2.33, gt=0.5, le=20.0,
        description="steering-gear rate, deg/s (SOLAS: 35 deg to 30 deg other side in <= 28 s: >= 2.322)",
    )


class Engine(Params):
    """Engine and telegraph. rpm per telegraph position (negative astern); the shaft speed
    follows the order as a first-order lag with a rate limit; reversing waits at rest."""

    telegraph_rpm: dict[str, float]
    time_constant_s: float = Field(8.0, gt=0.0, le=120.0, description="shaft speed time constant, s")
    rate_limit_rpm_s: float = Field(10.0, gt=0.0, le=500.0, description="max shaft acceleration, rpm/s")
    reverse_delay_s: float = Field(10.0, ge=0.0, le=120.0, description="stop-to-reverse delay, s")

    @model_validator(mode="after")
    def _positions(self) -> "Engine":
        unknown = sorted(set(self.telegraph_rpm) - set(TELEGRAPH_POSITIONS))
        missing = sorted(set(TELEGRAPH_POSITIONS) - set(self.telegraph_rpm))
        if unknown:
            raise ValueError(f"unknown telegraph position(s) {unknown}; allowed: {', '.join(TELEGRAPH_POSITIONS)}")
        if missing:
            raise ValueError(f"telegraph_rpm lacks position(s) {missing}")
        rpm = [self.telegraph_rpm[p] for p in TELEGRAPH_POSITIONS]
        if any(b < a for a, b in zip(rpm, rpm[1:])) or self.telegraph_rpm["stop"] != 0.0:
            raise ValueError("telegraph_rpm must rise from crash_astern to navigation_full_ahead, stop = 0")
        return self


# The ice classes POLARIS rates ships by (IMO MSC.1/Circ.1519, appendix, table 1.1's rows):
# the IACS Polar Classes, the Finnish-Swedish classes, and no ice class
ICE_CLASSES = ("PC1", "PC2", "PC3", "PC4", "PC5", "PC6", "PC7", "IA Super", "IA", "IB", "IC", "none")


class IceHull(Params):
    """The ship's ice class, and hull form data for Lindqvist's level-ice resistance."""

    ice_class: Literal[ICE_CLASSES] = Field("none", description="the ice class of the ship's Polar Ship Certificate")

    stem_angle_deg: float = Field(gt=10.0, lt=90.0, description="phi, stem angle to the waterline")
    waterline_angle_deg: float = Field(gt=5.0, lt=90.0, description="alpha, waterline entrance half-angle")
    channel_concentration: float = Field(
        0.8, ge=0.0, le=1.0, description="share of a broken channel its pieces cover; times their thickness, the "
                                         "brash in mid channel (the Finnish-Swedish rules' H_M) it resists by")


class ShipLook(Params):
    """How the projector channels draw the ship; the simulation does not read it."""

    model_glb: str | None = Field(None, description="GLB of hull and superstructure in the ship frame (m, x forward, "
                                                    "y starboard, z up from the waterline); unset: generated")
    bridge_eye: list[float] = Field(default_factory=lambda: [10.0, 25.0], min_length=2, max_length=2,
                                    description="eye on the bridge's centre line: x forward of midship, z, m")


class Windage(Params):
    """The ship above the waterline, for the wind load (``sim_core.ship.wind``): projected
    areas and the coefficients of Fossen (2011), section 8.1.1, whose typical ranges for
    large ships bound them."""

    frontal_area: float = Field(gt=1.0, lt=20000.0, description="A_Fw, frontal projected area, m2")
    lateral_area: float = Field(gt=1.0, lt=50000.0, description="A_Lw, lateral projected area, m2")
    length_overall: float = Field(gt=10.0, lt=500.0, description="L_oa, m")
    c_x: float = Field(0.7, ge=0.5, le=0.9, description="c_x of C_X = -c_x cos(gamma)")
    c_y: float = Field(0.8, ge=0.7, le=0.95, description="c_y of C_Y = c_y sin(gamma)")
    c_n: float = Field(0.1, ge=0.05, le=0.2, description="c_n of C_N = c_n sin(2 gamma)")


class Motions(Params):
    """Heave, roll and pitch of the hull (``sim_core.ship.motions``): damping ratios, the
    pitch radius of gyration, and the stability that sets the roll (GM and KG for the
    ship's loading condition; without both the ship does not roll). The damping defaults
    are typical of merchant hulls."""

    heave_damping: float = Field(0.2, ge=0.0, le=1.0, description="heave damping ratio, of critical")
    pitch_damping: float = Field(0.2, ge=0.0, le=1.0, description="pitch damping ratio, of critical")
    roll_damping: float = Field(0.1, ge=0.0, le=1.0, description="roll damping ratio, of critical")
    gyration_y: float = Field(0.25, gt=0.1, lt=0.5, description="pitch radius of gyration / L")
    metacentric_height: float | None = Field(None, gt=0.05, le=15.0, description="GM, transverse, m")
    centre_of_gravity_height: float | None = Field(None, gt=0.0, le=60.0, description="KG, above the keel, m")


class ShipParticulars(Params):
    """Everything static about one ship."""

    name: str
    description: str = ""
    length: float = Field(gt=10.0, lt=500.0, description="L_pp, m")
    beam: float = Field(gt=2.0, lt=100.0, description="B, m")
    draught: float = Field(gt=0.5, lt=40.0, description="d, m")
    displacement: float = Field(gt=10.0, lt=1.0e6, description="volume displacement, m3")
    x_g: float = Field(description="x_G, centre of gravity forward of midship, m")
    gyration_z: float = Field(0.25, gt=0.1, lt=0.5, description="yaw radius of gyration / L")
    m_x: float = Field(gt=0.0, lt=0.2, description="m'_x added mass")
    m_y: float = Field(gt=0.0, lt=1.0, description="m'_y added mass")
    j_z: float = Field(gt=0.0, lt=0.2, description="J'_z added inertia")
    service_speed_kn: float = Field(gt=1.0, lt=40.0, description="test speed for trials, kn")
    hull: HullDerivatives
    propeller: Propeller
    rudder: Rudder
    engine: Engine
    ice: IceHull
    look: ShipLook = Field(default_factory=ShipLook)
    motions: Motions = Field(default_factory=Motions)
    windage: Windage | None = Field(None, description="unset: the wind exerts no load on this ship")
