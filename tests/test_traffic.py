"""The traffic picture: vessels scripted in the exercise and vessels of a replayed AIS log
go out on a real NMEA link (UDP on the loopback) as !AIVDM that pyais decodes to their
position, course, speed and name, moving as scripted or logged; a session record's DIS
vessels are heard again when it is replayed; bad traffic configs name the file, key, value
and what is allowed."""
import math
import socket
import time

import numpy as np
import pytest
from conftest import free_port
from links_helpers import STATE, node_config, tick, wait_for
from pyais import encode_dict
from test_links_ais import QUIET, messages
from opendis.PduFactory import createPdu
from opendis.RangeCoordinates import GPS
from test_links_dis import datagrams, other_simulator_pdu, receiver

from bridge_node.links.hub import LinkHub
from bridge_node.node.config import ConfigError, load_config
from bridge_node.traffic.settings import ScriptedVessel
from bridge_node.links.dis.kind import read_dis_log
from bridge_node.replay.session import SessionSource, read_session
from bridge_node.node.traffic_setup import traffic_picture
from bridge_node.traffic.sources import ScriptedMotion, replay_traffic
from sim_core.frames.geodesy import geodetic_to_local, local_to_geodetic
from sim_core.frames.units import KNOT

ORIGIN = math.radians(74.0), math.radians(20.0)  # the default [exercise] origin
LOG_T0 = 1_767_000_000.0  # unix s of the log's first report
LOGGED = 230999001
START = math.radians(74.01), math.radians(20.02)  # the logged vessel's first position


def ais_log(path, speed_kn: float = 8.0) -> None:
    """An AIS log (unix time, then the sentence) of one vessel steaming north from
    74.01 N 20.02 E, reporting every 10 s, and its static data; pyais encodes it."""
    lines = [f"{LOG_T0 - 1:.1f} {s}" for s in encode_dict(
        {"type": 5, "mmsi": LOGGED, "shipname": "LOGGED ONE", "to_bow": 40, "to_stern": 20, "to_port": 6,
         "to_starboard": 6}, talker_id="AI", sentence_type="VDM", seq_id=1)]
    for k in range(4):
        lat, _ = local_to_geodetic(speed_kn * KNOT * 10.0 * k, 0.0, *START)
        lines += [f"{LOG_T0 + 10 * k:.1f} {s}" for s in encode_dict(
            {"type": 1, "mmsi": LOGGED, "lat": math.degrees(lat), "lon": 20.02, "speed": speed_kn, "course": 0.0, "heading": 0,
             "second": (10 * k) % 60}, talker_id="AI", sentence_type="VDM")]
    path.write_text("\n".join(lines) + "\n")


def config(folder, traffic: str):
    path = folder / "node.toml"
    path.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n' + traffic)
    return path


SCRIPTED = ('[[traffic.vessels]]\nmmsi = 230000001\nname = "SCRIPTED ONE"\nlength = 80.0\nbeam = 14.0\n'
            'speed_kn = 9.0\nnorth = 500.0\neast = 200.0\ncourse_deg = 90.0\n')


def test_scripted_and_logged_vessels_go_out_as_aivdm(tmp_path):
    ais_log(tmp_path / "traffic.nmea")
    rx = receiver()
    rates = "\n".join(f"{k} = 0" for k in QUIET)
    links = (f'[[links]]\ntype = "nmea0183"\nname = "plotter"\nudp_port = {rx.getsockname()[1]}\n[links.rates]\n'
             f'{rates}\n[links.ais]\nmmsi = 257123450\nto_bow = 20\nto_stern = 130\nto_port = 10\nto_starboard = 12\n')
    path = config(tmp_path, f'[traffic]\nais_logs = ["traffic.nmea"]\n{SCRIPTED}{links}')
    cfg = load_config(path)
    with LinkHub(cfg.links, cfg.arbitration, traffic=traffic_picture(cfg, path)) as hub:
        for now in (100.0, 100.1, 115.0):  # reports due at 0 s, then 10 s later (under 14 kn)
            hub.poll(now)
            hub.publish(STATE, now)
    reports = [m for talker, m in messages([d.decode().strip() for d in datagrams(rx)]) if talker == "!AIVDM"]
    rx.close()
    by_mmsi = {}
    for m in reports:
        by_mmsi.setdefault((m["mmsi"], m["msg_type"]), []).append(m)
    # the scripted vessel: from (500 m N, 200 m E) east at 9 kn; at 0 s and at 15 s
    for m, t in zip(by_mmsi[(230000001, 1)], (0.0, 15.0)):
        lat, lon = local_to_geodetic(500.0, 200.0 + 9.0 * KNOT * t, *ORIGIN)
        assert m["lat"] == pytest.approx(math.degrees(lat), abs=1e-4 / 60)
        assert m["lon"] == pytest.approx(math.degrees(lon), abs=1e-4 / 60)
        assert m["course"] == 90.0 and m["heading"] == 90 and m["speed"] == 9.0
    assert len(by_mmsi[(230000001, 1)]) == 2
    assert by_mmsi[(230000001, 5)][0]["shipname"] == "SCRIPTED ONE"
    assert by_mmsi[(230000001, 5)][0]["to_bow"] + by_mmsi[(230000001, 5)][0]["to_stern"] == 80
    # the logged vessel: its first report plays at the first tick, then it moves as logged
    first, later = by_mmsi[(LOGGED, 1)]
    assert first["lat"] == pytest.approx(74.01, abs=1e-4 / 60) and first["lon"] == pytest.approx(20.02, abs=1e-4 / 60)
    assert first["speed"] == pytest.approx(8.0, abs=0.1)  # under way from its first report
    north, _ = geodetic_to_local(math.radians(later["lat"]), math.radians(later["lon"]), *START)
    assert north == pytest.approx(8.0 * KNOT * 15.0, abs=0.5)
    assert later["speed"] == pytest.approx(8.0, abs=0.1) and later["course"] == pytest.approx(0.0, abs=0.2)
    assert later["heading"] == 0 and later["lon"] == pytest.approx(20.02, abs=1e-4 / 60)
    static = by_mmsi[(LOGGED, 5)][0]
    assert static["shipname"] == "LOGGED ONE" and static["to_bow"] + static["to_stern"] == 60


def test_scripted_waypoints_are_steamed_in_turn():
    boat = ScriptedVessel(mmsi=230000002, length=20.0, beam=5.0, speed_kn=10.0,
                          waypoints=[[0.0, 0.0], [1000.0, 0.0], [1000.0, 500.0]])
    v = 10.0 * KNOT
    path, loop = ScriptedMotion(boat), ScriptedMotion(boat.model_copy(update={"loop": True}))
    assert path.at(500.0 / v) == pytest.approx((500.0, 0.0, 0.0, v))
    assert path.at(1200.0 / v) == pytest.approx((1000.0, 200.0, math.pi / 2, v))
    assert path.at(2000.0 / v) == pytest.approx((1000.0, 500.0, math.pi / 2, 0.0))  # arrived: stopped
    # looped: back from the last waypoint to the first (1118 m), then round again
    back = math.hypot(1000.0, 500.0)
    assert loop.at((1500.0 + 0.5 * back) / v)[:2] == pytest.approx((500.0, 250.0))
    assert loop.at((3000.0 + back) / v) == pytest.approx(loop.at(1500.0 / v))


@pytest.mark.parametrize("traffic, says", [
    (("[[traffic.vessels]]\nmmsi = 230000001\nlength = 80.0\nbeam = 14.0\nspeed_kn = 45.0\nnorth = 0.0\n"
      "east = 0.0\ncourse_deg = 0.0\n"), "traffic.vessels.0.speed_kn = 45.0: Input should be less than or equal to 40"),
    ("[[traffic.vessels]]\nmmsi = 230000001\nlength = 80.0\nbeam = 14.0\nspeed_kn = 5.0\nwaypoints = [[0.0, 0.0]]\n",
     "traffic.vessels.0: vessel 230000001: give at least 2 waypoints"),
    (("[[traffic.vessels]]\nmmsi = 230000001\nlength = 80.0\nbeam = 14.0\nspeed_kn = 5.0\n"
      "waypoints = [[0.0, 0.0], [5.0]]\n"), "traffic.vessels.0.waypoints.1 = [5.0]: List should have at least 2 items"),
    ("[traffic]\nais_logs = [\"missing.nmea\"]\n", "traffic.ais_logs.0 = 'missing.nmea': no such file"),
    ("[traffic]\nais_logs = [\"empty.nmea\"]\n", "traffic.ais_logs.0 = 'empty.nmea': no position reports of other"),
])
def test_traffic_config_errors_name_file_key_value_and_range(tmp_path, traffic, says):
    (tmp_path / "empty.nmea").write_text("$GPZDA,120000.00,02,01,2026,00,00*6B\n")
    path = config(tmp_path, traffic)
    with pytest.raises(ConfigError) as err:
        traffic_picture(load_config(path), path)
    assert str(err.value).startswith(str(path)) and says in str(err.value)


def test_a_sessions_dis_vessels_are_heard_again_when_it_is_replayed(tmp_path):
    listen, sim = free_port(), socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    cfg = node_config([{"type": "dis", "name": "dis", "listen_port": listen, "send_to": [f"127.0.0.1:{free_port()}"]},
                       {"type": "nmea0183", "name": "plotter", "udp_port": free_port()}])
    pdu = other_simulator_pdu(74.02, 20.03, math.radians(250.0), 6.0)
    with LinkHub(cfg.links, cfg.arbitration, tmp_path / "session") as hub:
        wait_for(lambda: hub.links[0].connected and hub.links[1].health().outputs,
                 poll=lambda: tick(hub, STATE, time.monotonic()))
        sim.sendto(pdu, ("127.0.0.1", listen))  # after the record's first sentence
        wait_for(lambda: hub.traffic.current, poll=lambda: tick(hub, STATE, time.monotonic()))
        [live] = hub.traffic.current
        heard = hub.links[0].heard
    sim.close()
    records, bad = read_dis_log(tmp_path / "session" / "dis.log")
    [rx] = [r for r in records if r.direction == "rx"]
    assert rx.pdu == pdu and rx.link == "dis" and not bad["torn"] and not bad["malformed"]
    session = read_session(tmp_path / "session", {"nmea.log"}, 0.1)  # no tick log: ticks from the line times
    with SessionSource(cfg.links, cfg.arbitration, session) as source:
        picture = replay_traffic(source, 0, ORIGIN, cfg.replay, cfg.links)
        assert picture.gather([], 50.0) == []  # the record's first tick: not heard yet
        [again] = picture.gather([], 50.0 + rx.unix_time - session.ticks[0].unix + 2.0)  # 2 s after it was
    expected = heard.vessels(live.time + 2.0)[0]  # the live link's own dead reckoning, 2 s on
    assert (again.mmsi, again.name) == (live.mmsi, "ODEN")
    assert again.latitude == pytest.approx(expected.latitude, abs=0.05 / 6.4e6)  # 5 cm: rx logged ms after read
    assert again.longitude == pytest.approx(expected.longitude, abs=0.05 / 1.8e6)
    assert again.heading == pytest.approx(expected.heading) and again.speed_over_ground == pytest.approx(6.0)


def test_dis_sends_the_scripted_vessel_as_an_entity_of_its_own_and_never_echoes_one_heard(tmp_path):
    rx, listen, sim = receiver(), free_port(), socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    links = (f'[[links]]\ntype = "dis"\nname = "dis"\nlisten_port = {listen}\n'
             f'send_to = ["127.0.0.1:{rx.getsockname()[1]}"]\n')
    path = config(tmp_path, "[traffic]\n" + SCRIPTED + links)
    cfg = load_config(path)
    with LinkHub(cfg.links, cfg.arbitration, traffic=traffic_picture(cfg, path)) as hub:
        sim.sendto(other_simulator_pdu(74.02, 20.03, 0.0, 3.0), ("127.0.0.1", listen))  # ODEN, site 3
        wait_for(lambda: len(hub.traffic.current) == 2, poll=lambda: tick(hub, STATE, time.monotonic()))
        for _ in range(3):
            tick(hub, STATE, time.monotonic())
    sim.close()
    pdus = [createPdu(d) for d in datagrams(rx)]
    rx.close()
    by_entity = {(p.entityID.siteID, p.entityID.applicationID, p.entityID.entityID): p for p in pdus}
    assert set(by_entity) == {(1, 1, 1), (1, 1, 2)}  # the own ship, the scripted vessel; not ODEN
    scripted = by_entity[(1, 1, 2)]
    assert scripted.marking.charactersString() == "SCRIPTED ON"  # its name, cut to the marking's 11
    loc, o = scripted.entityLocation, scripted.entityOrientation
    lat, lon, _, _, _, yaw = GPS().ecef2llarpy(loc.x, loc.y, loc.z, o.psi, o.theta, o.phi)
    north, east = geodetic_to_local(lat, lon, *ORIGIN)
    assert north == pytest.approx(500.0, abs=0.01) and 199.99 < east < 215.0  # steaming east from (500, 200)
    assert yaw == pytest.approx(math.pi / 2, abs=1e-5)
    velocity = np.array([scripted.entityLinearVelocity.x, scripted.entityLinearVelocity.y,
                         scripted.entityLinearVelocity.z])
    assert float(np.linalg.norm(velocity)) == pytest.approx(9.0 * KNOT, abs=1e-4)
    assert sum(p.entityID.entityID == 2 for p in pdus) == 1  # steady: one PDU, then the heartbeat's 5 s
