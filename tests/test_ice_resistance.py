import math

import pytest

from ships import ship

from sim_core.ship.model import ice_force, level_ice_terms, new_ship_data
from sim_core.ship.resistance import BROKEN_CHANNEL, LEVEL_ICE, level_ice_resistance, lindqvist_terms
from sim_core.ship.rubble_resistance import brash_channel_resistance, channel_speed_factor

# Reference case: B = 24 m, L = 150 m, T = 9 m, stem phi = 25 deg, waterline alpha = 30 deg,
# mu = 0.1, sigma_f = 500 kPa, E = 3 GPa, nu = 0.33, rho_i = 900, rho_w = 1027, g = 9.826,
# h = 0.8 m, v = 2 m/s. By hand:
#   tan phi = 0.466308, sin alpha = 0.5, tan psi = tan phi / sin alpha = 0.932615,
#   psi = 43.0031 deg, cos psi = 0.731310, cos phi = 0.906308, sin phi = 0.422618
#   R_c = 0.5 * 500e3 * 0.64 * (0.466308 + 0.1 * 0.906308 / 0.731310) / (1 - 0.1 * 0.422618 / 0.731310)
#       = 160000 * 0.590237 / 0.942211                                            = 100 230 N
#   sqrt(E / (12 (1 - nu^2) g rho_w)) = sqrt(3e9 / (12 * 0.8911 * 9.826 * 1027)) = 166.63
#   R_b = 27/64 * 500e3 * 24 * 0.8^1.5 / 166.63 * (0.932615 + 0.1 * 0.906308 / (0.5 * 0.731310))
#         * (1 + 1 / 0.731310) = 21 734 * 1.180470 * 2.367410                     = 60 715 N
#   R_s = 127 * 9.826 * 0.8 * 24 * (9 * 33 / 42 + 0.1 * (105 - 19.3006 - 10.3923 + 9 * 0.906308
#         * 0.731310 * sqrt(5.59896 + 3.0)))  = 23 959.7 * (7.071429 + 0.1 * 94.6196)  = 391 774 N
#   R = (R_c + R_b)(1 + 1.4 * 2 / sqrt(9.826 * 0.8)) + R_s (1 + 9.4 * 2 / sqrt(9.826 * 150))
#     = 160 945 * 1.998636 + 391 774 * 1.489759                                   = 905 299 N
CASE = dict(h=0.8, beam=24.0, length=150.0, draught=9.0, stem_angle=math.radians(25.0),
            waterline_angle=math.radians(30.0), flexural_strength=500e3, youngs_modulus=3e9,
            poisson_ratio=0.33, ice_density=900.0, water_density=1027.0, friction=0.1, g=9.826)


def test_terms_match_hand_computation():
    t = lindqvist_terms(**CASE)
    assert t.crushing == pytest.approx(100230, rel=1e-3)
    assert t.bending == pytest.approx(60715, rel=1e-3)
    assert t.submersion == pytest.approx(391774, rel=1e-3)
    total = level_ice_resistance(t, 2.0, 0.8, 150.0, 9.826)
    assert total == pytest.approx(905299, rel=1e-3)


def test_bending_factor_multiplies_whole_term_and_submersion_keeps_its_root():
    t = lindqvist_terms(**CASE)
    psi = math.atan(math.tan(CASE["stem_angle"]) / math.sin(CASE["waterline_angle"]))
    base = 27 / 64 * 500e3 * 24 * 0.8**1.5 / math.sqrt(3e9 / (12 * (1 - 0.33**2) * 9.826 * 1027))
    bracket = math.tan(psi) + 0.1 * math.cos(CASE["stem_angle"]) / (math.sin(CASE["waterline_angle"]) * math.cos(psi))
    assert t.bending == pytest.approx(base * bracket * (1 + 1 / math.cos(psi)), rel=1e-12)
    assert t.bending != pytest.approx(base * (bracket + 1 + 1 / math.cos(psi)), rel=1e-3)
    # without friction the submersion term is the hydrostatic part alone; with it the root
    # term is sqrt(1/sin^2 phi + 1/tan^2 alpha) = 2.9325, not its square 8.599
    frictionless = lindqvist_terms(**{**CASE, "friction": 0.0})
    assert frictionless.submersion == pytest.approx(127 * 9.826 * 0.8 * 24 * 9 * 33 / 42, rel=1e-12)
    extra = (t.submersion - frictionless.submersion) / (127 * 9.826 * 0.8 * 24 * 0.1)
    root = math.sqrt(1 / math.sin(CASE["stem_angle"]) ** 2 + 1 / math.tan(CASE["waterline_angle"]) ** 2)
    expected = 0.7 * 150 - 9 / math.tan(CASE["stem_angle"]) - 24 / (4 * math.tan(CASE["waterline_angle"])) \
        + 9 * math.cos(CASE["stem_angle"]) * math.cos(psi) * root
    assert extra == pytest.approx(expected, rel=1e-9)


def test_speed_factors_and_thickness():
    t = lindqvist_terms(**CASE)
    assert level_ice_resistance(t, 0.0, 0.8, 150.0, 9.826) == pytest.approx(t.crushing + t.bending + t.submersion)
    assert level_ice_resistance(t, 3.0, 0.8, 150.0, 9.826) > level_ice_resistance(t, 1.0, 0.8, 150.0, 9.826)
    level = level_ice_resistance(t, 2.0, 0.8, 150.0, 9.826)
    assert level_ice_resistance(t, 2.0, 0.0, 150.0, 9.826) == 0.0
    thin = lindqvist_terms(**{**CASE, "h": 0.3})
    assert level_ice_resistance(thin, 2.0, 0.3, 150.0, 9.826) < level


@pytest.mark.parametrize("h", [0.5, 1.0])
def test_a_broken_channel_resists_as_brash_of_its_pieces_by_the_rules(h):
    """In a channel another hull broke, the ship meets the Finnish-Swedish rules' channel
    resistance of its pieces as brash, H_M = the channel's concentration times their
    thickness, with the channel's speed factor; and the bow's share is all of it, as brash."""
    m = ship("polar_cargo")
    speed = 2.5
    d = new_ship_data(m, speed)
    d.ice_h, d.ice_condition = h, BROKEN_CHANNEL
    surge, bow = ice_force(m, d, speed)
    g = m.material.gravity
    hm = m.particulars.ice.channel_concentration * h
    expected = brash_channel_resistance(hm, m.bow) * channel_speed_factor(speed, m.L, g)
    assert -surge == pytest.approx(expected, rel=1e-12) and bow == pytest.approx(expected, rel=1e-12)
    level = level_ice_resistance(level_ice_terms(m, h), speed, h, m.L, g)
    assert expected < 0.5 * level
    d.ice_condition = LEVEL_ICE  # the same ship breaking the ice meets Lindqvist's resistance
    assert -ice_force(m, d, speed)[0] == pytest.approx(level, rel=1e-12)
