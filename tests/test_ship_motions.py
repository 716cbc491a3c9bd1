"""Heave, roll and pitch (issue 28, item 3: the bow rises as it rides up on the ice, the ship
heels in a turn, and the eye on the bridge moves with it): the hydrostatics of the
waterplane, the static and dynamic response, the heel in a turn, and the channels' cameras
moving with the ship."""
import math

import numpy as np
import pytest

from bridge_node.node.config import load_ship
from bridge_node.render.camera import channel_camera
from bridge_node.render.settings import ChannelSettings
from sim_core.ship.model import compile_ship, mmg_forces, new_ship_data, order_rudder, step
from sim_core.ship.motions import roll_period, step_motions, waterplane


@pytest.fixture(scope="module")
def ship():
    return compile_ship(load_ship("polar_cargo", None))


def test_the_waterplane_of_a_box_and_of_the_hull():
    box = np.array([[50.0, -10.0], [50.0, 10.0], [-50.0, 10.0], [-50.0, -10.0]])
    area, centre, second = waterplane(box)
    assert area == pytest.approx(2000.0) and centre == pytest.approx(0.0, abs=1e-9)
    assert second == pytest.approx(20.0 * 100.0**3 / 12.0)
    shifted = waterplane(box + [10.0, 0.0])
    assert shifted[1] == pytest.approx(10.0) and shifted[2] == pytest.approx(second)  # about its own centre


def test_a_steady_bow_load_settles_at_the_hydrostatic_offsets(ship):
    v = ship.motions
    eta, nu = np.zeros(6), np.zeros(6)
    load = 2.0e6  # N of bow resistance
    for _ in range(2400):  # 240 s
        step_motions(v, eta, nu, load, 0.0, 0.1)
    lift = v.lift_ratio * load
    assert -eta[2] == pytest.approx(lift / v.heave_stiffness, rel=0.01)  # up by F / (rho g A_wp)
    assert eta[4] == pytest.approx(lift * v.stem_lever / v.pitch_stiffness, rel=0.01)  # bow up
    # the stem raked 25 deg with friction 0.1 lifts 1.68 N per newton of resistance
    phi, mu = math.radians(25.0), 0.1
    assert v.lift_ratio == pytest.approx((math.cos(phi) - mu * math.sin(phi)) / (math.sin(phi) + mu * math.cos(phi)))


def test_released_without_damping_it_oscillates_at_its_natural_periods(ship):
    v = ship.motions.__class__(**{**ship.motions.__dict__, "heave_damping": 0.0, "pitch_damping": 0.0,
                                  "roll_damping": 0.0})
    eta, nu = np.array([0.0, 0.0, -0.5, 0.02, 0.01, 0.0]), np.zeros(6)
    h, heave, roll, pitch = 0.01, [], [], []
    for _ in range(6000):
        step_motions(v, eta, nu, 0.0, 0.0, h)
        heave.append(-eta[2])
        roll.append(eta[3])
        pitch.append(eta[4])
    p = ship.particulars
    imo = roll_period(p.length, p.beam, p.draught, p.motions.metacentric_height)
    for series, mass, stiffness, expected in ((heave, v.heave_mass, v.heave_stiffness, (6.0, 10.0)),
                                              (pitch, v.pitch_inertia, v.pitch_stiffness, (6.0, 10.0)),
                                              (roll, v.roll_inertia, v.roll_stiffness, (0.98 * imo, 1.02 * imo))):
        s = np.asarray(series)
        crossings = np.nonzero(np.diff(np.sign(s)) > 0)[0]  # upward zero crossings
        period = np.diff(crossings).mean() * h
        assert period == pytest.approx(2.0 * math.pi * math.sqrt(mass / stiffness), rel=0.02)
        assert expected[0] < period < expected[1]  # heave and pitch: merchant hulls; roll: the IMO's period
        assert abs(s).max() == pytest.approx(abs(s[:10]).max(), rel=0.02)  # undamped: no decay
    # the Intact Stability Code's C for B/d 2.67, L 150 m: 0.370, so T = 2 C B / sqrt(GM) = 14.5 s
    assert imo == pytest.approx(2.0 * 0.3698 * 24.0 / math.sqrt(1.5), rel=1e-3)


def test_a_turn_heels_the_ship_in_then_out_by_the_steady_turn_heel(ship):
    """The rudder's kick heels the ship into the turn, then it heels out by the Intact
    Stability Code's moment of a steady turn, the centripetal force at half the draught."""
    d = new_ship_data(ship, speed=7.0)
    order_rudder(ship, d, math.radians(20.0))  # to starboard
    roll = []
    for _ in range(6000):  # 600 s
        step(ship, d, 0.1)
        roll.append(d.eta[3])
    u, r, m = d.nu[0], d.nu[5], ship.motions
    assert r > 0.0 and max(roll[:100]) > math.radians(0.2)  # first starboard down: into the turn
    steady = -ship.mass_plus_mx * u * r * m.hull_lever / m.roll_stiffness
    assert roll[-1] == pytest.approx(steady, rel=0.05) and roll[-1] < -math.radians(0.5)  # out of the turn
    level = ship.particulars.model_copy(update={"motions": ship.particulars.motions.model_copy(
        update={"metacentric_height": None})})
    upright = compile_ship(level)
    d = new_ship_data(upright, speed=7.0)
    order_rudder(upright, d, math.radians(20.0))
    for _ in range(600):
        step(upright, d, 0.1)
    assert d.eta[3] == 0.0 and d.nu[5] > 0.0  # a ship file without GM: no roll


def test_a_side_load_at_the_waterline_heels_the_ship(ship):
    """The ice's side load acts at the waterline, the hull's resistance to the sway it drives
    at half the draught: once the ship drifts steadily the two make a couple of about F d / 2
    (the hull's force is not all of the push: the ship turns as it drifts), and the ship heels
    by it, the side pushed from down."""
    d = new_ship_data(ship)
    push = 2.0e6  # N to starboard
    d.external[1] = push
    for _ in range(3000):  # 300 s
        step(ship, d, 0.1)
    assert d.nu[1] > 0.0  # drifting to starboard
    hull = mmg_forces(ship, d.nu[0], d.nu[1], d.nu[5], d.rudder, d.rps)[1]
    assert hull == pytest.approx(-push, rel=0.15)
    m = ship.motions
    assert d.eta[3] == pytest.approx((-hull * m.hull_lever - push * m.waterline_lever) / m.roll_stiffness, rel=0.01)
    assert d.eta[3] == pytest.approx(push * 0.5 * ship.d / m.roll_stiffness, rel=0.15)  # starboard down


def test_the_camera_moves_with_the_ship(ship):
    c = ChannelSettings(name="ahead", width=640, height=360, eye=[-50.0, 0.0, 25.0])
    level = channel_camera(c, c.eye, 100.0, 200.0, 0.7, 20_000.0)
    pitched = channel_camera(c, c.eye, 100.0, 200.0, 0.7, 20_000.0, heave=0.3, pitch=math.radians(1.0))
    # the eye 50 m aft of midship: down by 50 sin(1 deg), up by the heave
    assert pitched.eye[2] - level.eye[2] == pytest.approx(0.3 - 50.0 * math.sin(math.radians(1.0)) + 25.0 * (
        math.cos(math.radians(1.0)) - 1.0), abs=1e-9)
    far = np.array([200.0 + 10_000.0 * math.sin(0.7), 100.0 + 10_000.0 * math.cos(0.7), level.eye[2], 1.0])
    y_level, y_pitched = ((cam.view_proj @ far)[1] / (cam.view_proj @ far)[3] for cam in (level, pitched))
    assert y_level == pytest.approx(0.0, abs=1e-6)  # dead ahead at eye height: the middle row
    assert y_pitched < -0.9 * math.tan(math.radians(1.0)) / math.tan(c.vfov() / 2)  # bow up: the horizon lower
    rolled = channel_camera(c, c.eye, 100.0, 200.0, 0.7, 20_000.0, roll=math.radians(2.0))
    assert rolled.eye[2] - level.eye[2] == pytest.approx(25.0 * (math.cos(math.radians(2.0)) - 1.0), abs=1e-9)
    right = np.array([*(level.eye[:2] + 10_000.0 * np.array([math.sin(0.7 + 0.3), math.cos(0.7 + 0.3)])),
                      level.eye[2], 1.0])
    y_level, y_rolled = ((cam.view_proj @ right)[1] / (cam.view_proj @ right)[3] for cam in (level, rolled))
    assert y_rolled > y_level + 0.01  # starboard down: the horizon on the right rises in the picture
