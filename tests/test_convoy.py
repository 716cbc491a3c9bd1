"""The convoy watch (issue 31, item 3 in part): the ship ahead and the ship astern, vessels of
the traffic picture named by MMSI, go out on a real NMEA link (UDP on the loopback) as TTM
tracked targets that pynmea2 reads back (distance, bearing, CPA and TCPA as the relative
plot gives them), an ALR alarm is raised while one is closer than the limit and cleared
when it is not, and bad convoy configs name the file, key and value."""
import dataclasses
import math

import pynmea2
import pytest
from links_helpers import STATE
from test_links_ais import QUIET
from test_links_dis import datagrams, receiver

from bridge_node.links.convoy import closest_approach
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import ConfigError, load_config
from bridge_node.node.traffic_setup import traffic_picture
from sim_core.frames.geodesy import local_to_geodetic
from sim_core.frames.units import KNOT

ORIGIN = math.radians(74.0), math.radians(20.0)  # the default [exercise] origin
AHEAD = ('[[traffic.vessels]]\nmmsi = 230000001\nname = "BREAKER, ONE"\nlength = 100.0\nbeam = 22.0\n'
         'speed_kn = 2.0\nnorth = 600.0\neast = 200.0\ncourse_deg = 0.0\n')


def own_ship(north: float, speed: float) -> object:
    """The own ship at (north, 200 m east) of the exercise origin, steaming north."""
    lat, lon = local_to_geodetic(north, 200.0, *ORIGIN)
    return dataclasses.replace(STATE, north=north, east=200.0, latitude=lat, longitude=lon, heading=0.0,
                               course_over_ground=0.0, speed_over_ground=speed)


@pytest.mark.parametrize("north, east, vn, ve, cpa, tcpa", [
    (1000.0, 0.0, -5.0, 0.0, 0.0, 200.0),  # head on
    (1000.0, 100.0, -5.0, 0.0, 100.0, 200.0),  # passing 100 m to starboard
    (1000.0, 100.0, 5.0, 0.0, 100.0, -200.0),  # opening: the closest point was 200 s ago
    (300.0, 400.0, 0.0, 0.0, 500.0, 0.0),  # no relative motion: the distance stays
])
def test_closest_approach_is_the_relative_plots(north, east, vn, ve, cpa, tcpa):
    assert closest_approach(north, east, vn, ve) == pytest.approx((cpa, tcpa), abs=1e-9)


def test_the_ship_ahead_goes_out_as_ttm_and_its_distance_alarm_as_alr(tmp_path):
    rx = receiver()
    rates = "\n".join(f"{k} = 0" for k in QUIET)
    links = f'[[links]]\ntype = "nmea0183"\nname = "radar"\nudp_port = {rx.getsockname()[1]}\n[links.rates]\n{rates}\n'
    path = tmp_path / "node.toml"
    path.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n[traffic]\n' + AHEAD +
                    '[convoy]\nahead_mmsi = 230000001\nmin_distance_m = 600.0\n' + links)
    cfg = load_config(path)
    with LinkHub(cfg.links, cfg.arbitration, traffic=traffic_picture(cfg, path), convoy=cfg.convoy) as hub:
        hub.poll(100.0)
        hub.publish(own_ship(100.0, 5.0), 100.0)  # 500 m astern of the breaker, closing
        first = [pynmea2.parse(d.decode().strip()) for d in datagrams(rx)]
        hub.poll(101.5)
        hub.publish(own_ship(-200.0, 5.0), 101.5)  # dropped back: 800 m, and the breaker 1.5 s on
        later = [pynmea2.parse(d.decode().strip()) for d in datagrams(rx)]
    rx.close()
    ttm = next(m for m in first if m.sentence_type == "TTM")
    assert ttm.talker == "RA" and ttm.target_number == 1 and ttm.name == "BREAKER  ONE" and ttm.status == "T"
    assert float(ttm.distance) * 1852.0 == pytest.approx(500.0, abs=1.0)
    assert float(ttm.bearing) == pytest.approx(0.0, abs=0.1) and ttm.brg_ref == "T"
    assert float(ttm.speed) == pytest.approx(2.0, abs=0.05) and float(ttm.cog) == pytest.approx(0.0, abs=0.1)
    closing = 5.0 - 2.0 * KNOT
    assert float(ttm.dist_cpa) == pytest.approx(0.0, abs=0.001)
    assert float(ttm.time_cpa) == pytest.approx(500.0 / closing / 60.0, abs=0.05)
    alarm = next(m for m in first if m.sentence_type == "ALR")
    assert alarm.data[1:3] == ["300", "A"] and alarm.data[4] == "convoy: ship ahead at 500 m (limit 600 m)"
    cleared = next(m for m in later if m.sentence_type == "ALR")
    assert cleared.data[1:3] == ["300", "V"] and cleared.data[4] == "convoy: ship ahead at 802 m again"
    distance = float(next(m for m in later if m.sentence_type == "TTM").distance) * 1852.0
    assert distance == pytest.approx(800.0 + 2.0 * KNOT * 1.5, abs=1.0)


@pytest.mark.parametrize("convoy, says", [
    ("[convoy]\nmin_distance_m = 200.0\n", ["convoy", "give ahead_mmsi, astern_mmsi or both"]),
    ("[convoy]\nahead_mmsi = 230000001\nastern_mmsi = 230000001\n", ["one ship cannot be both"]),
    ("[convoy]\nahead_mmsi = 12\n", ["convoy.ahead_mmsi", "12", "100000000"]),
    ("[convoy]\nahead_mmsi = 230000001\nmin_distance_m = -5.0\n", ["convoy.min_distance_m", "-5.0", "greater than 0"]),
])
def test_a_bad_convoy_names_file_key_and_value(tmp_path, convoy, says):
    path = tmp_path / "node.toml"
    path.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n' + convoy)
    with pytest.raises(ConfigError) as refused:
        load_config(path)
    for word in [str(path), *says]:
        assert word in str(refused.value), str(refused.value)
