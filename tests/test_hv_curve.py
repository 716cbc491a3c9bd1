"""The ship's limits in level ice (issue 27, items 1 and 3): its ice class, from the ship file
(the default ship is PC5), and the h-v curve: the speed the default ship attains at full
power in level ice falls with the thickness, and the ship simulated at full ahead behaves as
the curve says: it holds the curve's speed in thinner ice and sticks in thicker."""
import json
import math

import numpy as np
import pytest
from conftest import run_cli

from bridge_node.node.config import DEFAULT_CONFIG, ConfigError, load_config, load_ship
from sim_core.frames.units import KNOT
from sim_core.ship.model import compile_ship, new_ship_data, order_telegraph, step
from sim_core.ship.resistance import LEVEL_ICE
from sim_core.studies.hv_curve import attainable_speed, hv_curve, sticking_thickness, surge_balance


@pytest.fixture(scope="module")
def ship():
    cfg = load_config()
    return compile_ship(load_ship(cfg.ship.name), cfg.ice_material)


def _simulated_speed(model, thickness: float, start: float, seconds: float = 900.0) -> float:
    """Speed (m/s) of the ship at navigation full ahead in level ice after ``seconds``."""
    data = new_ship_data(model, start)
    data.ice_h, data.ice_condition = thickness, LEVEL_ICE
    assert order_telegraph(model, data, "navigation_full_ahead") is None
    for _ in range(int(seconds / 0.5)):
        step(model, data, 0.5)
    return float(data.nu[0])


def test_the_curve_falls_with_thickness_to_the_sticking_thickness(ship):
    stuck_at = sticking_thickness(ship)
    assert 0.5 < stuck_at < 3.0  # a Polar Class 5 ship breaks metre-thick ice, not any
    h = np.linspace(0.0, 1.3 * stuck_at, 27)
    v = hv_curve(ship, h)
    assert np.all(np.diff(v) <= 0.0) and np.all(np.diff(v[h < stuck_at]) < 0.0)
    assert v[0] > 10.0 * KNOT and np.all(v[h > stuck_at] == 0.0)
    for thickness, speed in zip(h[1:6], v[1:6]):  # each speed is a root of the model's own surge balance
        assert abs(surge_balance(ship, speed, thickness, ship.rps_ahead_max)) < 1.0  # N


@pytest.mark.parametrize("share", [0.3, 0.7])
def test_the_simulated_ship_holds_the_curves_speed_below_the_sticking_thickness(ship, share):
    thickness = share * sticking_thickness(ship)
    expected = attainable_speed(ship, thickness)
    assert _simulated_speed(ship, thickness, start=0.5 * expected) == pytest.approx(expected, rel=0.02)


def test_the_simulated_ship_sticks_beyond_the_curve(ship):
    thickness = 1.2 * sticking_thickness(ship)
    assert _simulated_speed(ship, thickness, start=3.0) < 0.01  # m/s: it creeps at most, under the ice's grip


def test_trial_hv_prints_the_curve_and_plots_it(ship, tmp_path):
    r = run_cli("trial", "hv", "--json", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    result = json.loads(r.stdout)
    speeds = [row["speed_kn"] for row in result["curve"]]
    assert speeds == sorted(speeds, reverse=True) and speeds[-1] == 0.0
    assert math.isclose(result["sticking_thickness_m"], sticking_thickness(ship), rel_tol=1e-6)
    png = tmp_path / result["plot"].rsplit("/", 1)[-1]
    assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    table = run_cli("trial", "hv", "--out", str(tmp_path))
    assert table.returncode == 0 and "sticks" in table.stdout



def test_the_ship_file_gives_the_ice_class(ship, tmp_path):
    assert ship.particulars.ice.ice_class == "PC5"
    (tmp_path / "ships").mkdir()
    text = (DEFAULT_CONFIG.parent / "ships" / "polar_cargo.toml").read_text()
    (tmp_path / "ships" / "odd.toml").write_text(text.replace('ice_class = "PC5"', 'ice_class = "PC9"'))
    with pytest.raises(ConfigError) as err:
        load_ship("odd", tmp_path / "node.toml")
    message = str(err.value)
    assert "odd.toml" in message and "ice.ice_class = 'PC9'" in message and "PC5" in message
