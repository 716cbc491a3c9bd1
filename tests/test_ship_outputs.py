import json
import math

import pytest
from conftest import run_cli
from ships import ship

from sim_core.frames.geodesy import geodetic_to_local, local_to_geodetic
from sim_core.ship.model import new_ship_data, order_rudder, step
from sim_core.ship.outputs import ship_outputs


def test_geodesy_round_trip_and_scale():
    lat0, lon0 = math.radians(74.0), math.radians(20.0)
    lat, lon = local_to_geodetic(1852.0, 1000.0, lat0, lon0)
    assert math.degrees(lat - lat0) * 60 == pytest.approx(1.0, rel=0.01)  # 1 NM north = 1' of latitude
    n, e = geodetic_to_local(lat, lon, lat0, lon0)
    assert (n, e) == pytest.approx((1852.0, 1000.0), abs=1e-6)


def test_outputs_of_a_turning_ship():
    m = ship("polar_cargo")
    d = new_ship_data(m, 7.0, heading=math.radians(350.0))
    order_rudder(m, d, math.radians(35.0))
    for _ in range(60 * 60):
        step(m, d, 1 / 60)
    out = ship_outputs(d, 60.0, math.radians(74.0), math.radians(20.0))
    assert out.time == 60.0
    assert 0 <= out.heading < 2 * math.pi and 0 <= out.course_over_ground < 2 * math.pi
    assert out.rate_of_turn > 0 and out.rudder_angle == pytest.approx(math.radians(35.0))
    assert out.speed_transverse != 0.0
    # drifting in a turn: course over ground differs from heading by the drift angle
    drift = math.atan2(out.speed_transverse, out.speed_longitudinal)
    off = (out.course_over_ground - out.heading - drift + math.pi) % (2 * math.pi) - math.pi
    assert off == pytest.approx(0, abs=1e-9)
    assert out.speed_over_ground == pytest.approx(math.hypot(out.speed_longitudinal, out.speed_transverse))
    assert out.shaft_rps > 0 and out.ice_resistance == 0.0


def test_trial_cli_json_and_plot(tmp_path):
    res = run_cli("trial", "turning", "--rudder", "10", "--speed", "12", "--json", "--out", str(tmp_path))
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["trial"] == "turning" and out["ship"] == "polar_cargo" and out["approach_speed_kn"] == 12.0
    assert out["imo"]["initial_turning_L"]["pass"] is True
    assert (tmp_path / "trial_turning_polar_cargo.png").stat().st_size > 10_000


@pytest.mark.parametrize("args,needle", [
    (("zigzag", "--rudder", "40"), "--rudder 40.0 is outside the allowed range (0.0, 35.0]"),
    (("crash-stop", "--speed", "-3"), "--speed -3.0 is outside"),
    (("turning", "--ice", "9"), "--ice 9.0 is outside"),
    (("turning", "--ship", "titanic"), "unknown ship 'titanic'; ships available: kvlcc2, polar_cargo"),
])
def test_trial_cli_bad_arguments(args, needle, tmp_path):
    res = run_cli("trial", *args, "--out", str(tmp_path))
    assert res.returncode == 2 and needle in res.stderr and "Traceback" not in res.stderr
