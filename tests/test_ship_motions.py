"""Heave and pitch under the ice's lift at the bow (issue 28, item 3: the bow rises as it rides
up on the ice, and the eye on the bridge with it): the hydrostatics of the waterplane, the
static and dynamic response, and the channels' cameras moving with the ship."""
import math

import numpy as np
import pytest

from bridge_node.node.config import load_ship
from bridge_node.render.camera import channel_camera
from bridge_node.render.settings import ChannelSettings
from sim_core.ship.model import compile_ship
from sim_core.ship.vertical import step_vertical, waterplane


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
    v = ship.vertical
    eta, nu = np.zeros(6), np.zeros(6)
    load = 2.0e6  # N of bow resistance
    for _ in range(2400):  # 240 s
        step_vertical(v, eta, nu, load, 0.1)
    lift = v.lift_ratio * load
    assert -eta[2] == pytest.approx(lift / v.heave_stiffness, rel=0.01)  # up by F / (rho g A_wp)
    assert eta[4] == pytest.approx(lift * v.stem_lever / v.pitch_stiffness, rel=0.01)  # bow up
    # the stem raked 25 deg with friction 0.1 lifts 1.68 N per newton of resistance
    phi, mu = math.radians(25.0), 0.1
    assert v.lift_ratio == pytest.approx((math.cos(phi) - mu * math.sin(phi)) / (math.sin(phi) + mu * math.cos(phi)))


def test_released_without_damping_it_oscillates_at_its_natural_periods(ship):
    v = ship.vertical.__class__(**{**ship.vertical.__dict__, "heave_damping": 0.0, "pitch_damping": 0.0})
    eta, nu = np.array([0.0, 0.0, -0.5, 0.0, 0.01, 0.0]), np.zeros(6)
    h, heave, pitch = 0.01, [], []
    for _ in range(3000):
        step_vertical(v, eta, nu, 0.0, h)
        heave.append(-eta[2])
        pitch.append(eta[4])
    for series, mass, stiffness in ((heave, v.heave_mass, v.heave_stiffness), (pitch, v.pitch_inertia,
                                                                              v.pitch_stiffness)):
        s = np.asarray(series)
        crossings = np.nonzero(np.diff(np.sign(s)) > 0)[0]  # upward zero crossings
        period = np.diff(crossings).mean() * h
        assert period == pytest.approx(2.0 * math.pi * math.sqrt(mass / stiffness), rel=0.02)
        assert 6.0 < period < 10.0  # the range of merchant hulls
        assert abs(s).max() == pytest.approx(abs(s[:10]).max(), rel=0.02)  # undamped: no decay


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
