"""Several own ships, each on its own bridge (issue 31): every ship obeys only its own
console, sends its own state on its own links, sees the others in its traffic picture, and
fails safe alone when its bridge loses its link. The consoles are python-can virtual buses
in the test's threads; the node runs its real-time loop; AIS goes out on UDP loopback and
is decoded with pyais. A config that gives two ships one link, a ship no links, or two ships
one place is refused with the file, key and value."""
import argparse
import dataclasses
import json
import math
import socket
import subprocess
import sys
import threading
import time
from contextlib import ExitStack
from types import SimpleNamespace

import can
import numpy as np
import pytest
from conftest import exercise_toml
from station_helpers import canvas_pixel, near, screenshot
from links_helpers import console_frame
from nmea2000.decoder import NMEA2000Decoder
from pyais import decode as decode_ais

from bridge_node.commands import ctl
from bridge_node.commands.render_snapshot import other_ships
from bridge_node.common.errors import UserError
from bridge_node.common.network import free_port
from bridge_node.exercise.tick_record import TICKS_FILE
from bridge_node.hil.run_console import RunConsole
from bridge_node.control.client import request
from bridge_node.control.commands import command_from_record, command_record
from bridge_node.control.endpoint import ControlEndpoint
from bridge_node.control.queue import CommandQueue
from bridge_node.control.settings import ControlSettings
from bridge_node.control.status import exercise_status
from bridge_node.exercise.fleet import Bridge
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import ConfigError, NodeConfig, load_config
from bridge_node.node.bridges import open_bridges
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.replay.engine import Playback, run_replay
from bridge_node.node.fleet_session import session_source
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.session import FLEET_FOLDER, RecordedSession
from bridge_node.station.events import EventLog, describe
from bridge_node.station.harness import chromium, http, start, stop, wait_until
from bridge_node.stream.codec import CodecError, decode, encode
from bridge_node.stream.follow import FollowedShip, followed_model
from sim_core.frames.geodesy import local_to_geodetic
from sim_core.frames.units import KNOT
from sim_core.instructor import Reposition
from sim_core.world import Controls, snapshot, step

MMSI_A, MMSI_B = 230000001, 230000002
TRAFFIC_RGB = (47, 210, 122)  # MAP_COLORS.traffic in the station's map.js


def _helm(name: str, channel: str, timeout_s: float) -> dict:
    return {"type": "can", "name": name, "channel": channel, "allowed_sources": [0x42], "timeout_s": timeout_s}


def _fleet_config(tmp_path, ais_port: int, second_east: float | None = None) -> NodeConfig:
    """Two ships 150 m apart at the ice edge, each steered over its own virtual CAN bus
    (the first's console stale after 0.3 s, the second's after 1 s: a loaded machine's
    pauses do not fail it); the first also sends AIS on UDP ``ais_port``."""
    base = load_config()
    cfg = base.model_dump() | {
        "ice_field": base.ice_field.model_dump() | {"width": 400.0, "height": 400.0},
        "paths": base.paths.model_dump() | {"cache_dir": str(tmp_path / "tiles")}, "console": None,
        "ship": {"name": base.ship.name, "mmsi": MMSI_A},
        "exercise": base.exercise.model_dump() | {"start_north": -60.0, "start_east": 100.0},
        "links": [_helm("helm_a", "fleet-a", 0.3),
                  {"type": "nmea0183", "name": "ais_a", "udp_port": ais_port,
                   "ais": {"mmsi": MMSI_A, "to_bow": 80, "to_stern": 70, "to_port": 11, "to_starboard": 11}}],
        "arbitration": {"rudder": ["helm_a"], "engine": ["helm_a"], "fail_safe_after_s": 0.5},
        "ships": [{"name": base.ship.name, "mmsi": MMSI_B, "ais_name": "FOLLOWER",
                   "start_north": -60.0, "start_east": 250.0 if second_east is None else second_east,
                   "start_speed_kn": 4.0, "links": [_helm("helm_b", "fleet-b", 1.0)],
                   "arbitration": {"rudder": ["helm_b"], "engine": ["helm_b"], "fail_safe_after_s": 0.5}}]}
    return NodeConfig.model_validate(cfg)


def _console(channel: str, rudder: float, lever: float, until, stop: threading.Event) -> threading.Thread:
    """A console thread giving ``rudder`` deg and ``lever`` % every 0.1 s while ``until()``."""
    bus = can.Bus(interface="virtual", channel=channel)

    def give() -> None:
        with bus:
            while not stop.is_set() and until():
                bus.send(console_frame("HelmOrder", RudderOrder=rudder, Status=1, Counter=0))
                bus.send(console_frame("EngineOrder", Engine=0, Lever=lever, TelegraphPosition=0, Mode=0))
                stop.wait(0.1)
    return threading.Thread(target=give, daemon=True)


_HEARD: dict[str, float | None] = {}  # channel -> the last heading (PGN 127250, rad) the node sent on it


def _listen(channel: str, stop: threading.Event) -> threading.Thread:
    """A listener on a console's bus, noting the headings the node sends there."""
    bus, dec = can.Bus(interface="virtual", channel=channel), NMEA2000Decoder()
    _HEARD[channel] = None

    def hear() -> None:
        with bus:
            while not stop.is_set():
                msg = bus.recv(timeout=0.05)
                m = dec.decode(msg) if msg is not None else None
                if m is not None and m.PGN == 127250:
                    _HEARD[channel] = {f.id: f.value for f in m.fields}["heading"]
    return threading.Thread(target=hear, daemon=True)


@pytest.fixture(scope="module")
def live_fleet(tmp_path_factory):
    """Four seconds of two ships on their bridges, recorded: bridge A's console falls silent
    at 2 s. The config, model, world at the end, record folder, each hub's alarms and
    traffic picture, and the AIS ship A sent."""
    tmp_path = tmp_path_factory.mktemp("fleet")
    ais = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ais.bind(("127.0.0.1", 0))
    ais.settimeout(0.2)
    cfg = _fleet_config(tmp_path, ais.getsockname()[1])
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    stop, record = threading.Event(), tmp_path / "session"
    threads = [_console("fleet-a", 35.0, 80.0, lambda: data.time < 2.0, stop),  # bridge A's link goes at 2 s
               _console("fleet-b", -20.0, 50.0, lambda: True, stop), _listen("fleet-a", stop), _listen("fleet-b", stop)]
    with LinkHub(cfg.links, cfg.arbitration, record) as hub_a, \
            LinkHub(cfg.ships[0].links, cfg.ships[0].arbitration, record / FLEET_FOLDER / "1") as hub_b:
        fleet = [Bridge(hub_a, MMSI_A, "LEADER"), Bridge(hub_b, MMSI_B, "FOLLOWER")]
        for t in threads:
            t.start()
        try:
            run_realtime(model, data, hub_a, 30.0, None, should_stop=lambda: data.time >= 4.0 - 1e-9, fleet=fleet)
        finally:
            stop.set()
            for t in threads:
                t.join(2.0)
        hubs = [(set(h.active_alarms), list(h.traffic.current)) for h in (hub_a, hub_b)]
    reports = []
    while True:
        try:
            text = ais.recv(4096).decode()
        except TimeoutError:
            break
        reports += [decode_ais(line).asdict() for line in text.splitlines() if line.startswith("!AIVDM")
                    and line.split(",")[1] == "1"]
    ais.close()
    return SimpleNamespace(cfg=cfg, model=model, data=data, record=record, hubs=hubs, ais=reports, tmp=tmp_path)


def test_each_bridge_steers_its_own_ship_and_only_the_silent_one_fails_safe(live_fleet):
    (alarms_a, picture_a), (alarms_b, picture_b) = live_fleet.hubs
    a, b = live_fleet.data.ships
    # bridge B's orders steer ship B alone; bridge A lost its link and its ship failed safe
    assert b.rudder_order == pytest.approx(math.radians(-20.0)) and b.rps_order > 0.0
    assert a.rudder_order == 0.0 and a.rps_order == 0.0  # midships and stop
    assert {111, 112} <= alarms_a and not alarms_b  # the fail-safe alarms are A's alone
    assert a.eta[5] % (2 * math.pi) < math.pi < b.eta[5] % (2 * math.pi)  # A swung to starboard, B to port
    # each ship's own state on its own bus
    assert _HEARD["fleet-a"] == pytest.approx(a.eta[5] % (2 * math.pi), abs=0.01)
    assert _HEARD["fleet-b"] == pytest.approx(b.eta[5] % (2 * math.pi), abs=0.01)
    # each ship's traffic picture holds the other, where it is
    assert [v.mmsi for v in picture_a] == [MMSI_B] and [v.mmsi for v in picture_b] == [MMSI_A]
    assert picture_a[0].name == "FOLLOWER" and picture_a[0].speed_over_ground > 1.0 * KNOT
    # and ship A's AIS sends ship B, decoded by pyais
    mine = [r for r in live_fleet.ais if r["mmsi"] == MMSI_B and r["msg_type"] == 1]
    assert mine, f"no position report of ship B among {len(live_fleet.ais)} AIS messages"
    b_lat, b_lon = local_to_geodetic(b.eta[0], b.eta[1], *live_fleet.model.origin)
    assert (mine[-1]["lat"], mine[-1]["lon"]) == pytest.approx((math.degrees(b_lat), math.degrees(b_lon)), abs=0.001)
    # two ships at one place: refused, naming the keys
    with pytest.raises(ConfigError, match=r"ships\.0\.start_north/start_east = north -60 m, east 110 m: .*overlaps"):
        start_world(live_fleet.model, _fleet_config(live_fleet.tmp, 10199, second_east=110.0))


def test_a_record_of_two_bridges_replays_each_ship_on_its_own_orders(live_fleet):
    cfg, model, live, record = live_fleet.cfg, live_fleet.model, live_fleet.data, live_fleet.record
    assert (record / FLEET_FOLDER / "1" / TICKS_FILE).is_file()  # ship B's tick log, beside its link traffic
    session = load_inputs([str(record)], None, {}, 1.0 / 30.0)
    assert isinstance(session, RecordedSession) and session.exact
    again = start_world(model, cfg)
    stop = threading.Event()
    listener = _listen("fleet-b", stop)  # ship B's bus: the replay sends ship B's state there
    listener.start()
    with session_source(cfg, session) as source, LinkHub(cfg.links, cfg.arbitration) as out, ExitStack() as stack:
        stats = run_replay(model, again, source, Playback(None), out, None, fleet=open_bridges(cfg, out, None, stack))
    wait_until(lambda: _HEARD["fleet-b"] is not None, 5.0, "ship B's heading on its bus")
    time.sleep(0.3)
    stop.set()
    listener.join(2.0)
    assert stats.steps == 120 and again.time == live.time
    assert _HEARD["fleet-b"] == pytest.approx(again.ships[1].eta[5] % (2 * math.pi), abs=0.01)
    for replayed, ship in zip(again.ships, live.ships):  # each ship on its own bridge's orders, exactly
        np.testing.assert_allclose(replayed.eta, ship.eta, rtol=0.0, atol=1e-9)
        assert (replayed.rudder_order, replayed.rps_order) == (ship.rudder_order, ship.rps_order)
    one_ship = cfg.model_copy(update={"ships": []})
    with pytest.raises(UserError, match="a record of 2 own ship\\(s\\), replayed on an exercise of 1"):
        session_source(one_ship, session)


def _config_error(tmp_path, text: str) -> str:
    path = tmp_path / "fleet.toml"
    default = (load_config.__globals__["DEFAULT_CONFIG"]).read_text()
    path.write_text(default.replace('name = "polar_cargo"      # config/ships/<name>.toml',
                                    'name = "polar_cargo"\nmmsi = 230000001') + text)
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    return str(caught.value)


SECOND = '''
[[ships]]
name = "polar_cargo"
mmsi = 230000002
start_north = -600.0
start_east = 3250.0
'''


def test_two_ships_on_one_link_are_refused(tmp_path):
    shared = SECOND + '[[ships.links]]\nname = "helm_b"\ntype = "can"\ninterface = "slcan"\nchannel = "/dev/pts/7"\n' \
        'allowed_sources = "any"\n'
    # the default config's console is slcan on a pty the run makes; give the first ship a fixed one
    first = '\n[[links]]\nname = "helm_a"\ntype = "can"\ninterface = "slcan"\nchannel = "/dev/pts/7"\n' \
        'allowed_sources = "any"\n'
    text = _config_error(tmp_path, first + shared)
    assert "ships.0.links.0 ('helm_b'): the CAN bus slcan:/dev/pts/7 is also link 'helm_a''s, of ship" in text
    same_name = SECOND + '[[ships.links]]\nname = "instruments"\ntype = "nmea0183"\nudp_port = 10111\n'
    assert "link name 'instruments' is also link 'instruments''s, of ship" in _config_error(tmp_path, same_name)
    same_udp = SECOND + '[[ships.links]]\nname = "b"\ntype = "nmea0183"\nudp_port = 10110\n'
    assert "ships.0.links.0.udp_port = 10110: UDP 127.0.0.1:10110 is also link 'instruments''s" in \
        _config_error(tmp_path, same_udp)


def test_a_ships_link_named_as_the_run_console_is_refused(tmp_path):
    path = tmp_path / "console_named.toml"
    path.write_text(load_config.__globals__["DEFAULT_CONFIG"].read_text().replace(
        'name = "polar_cargo"      # config/ships/<name>.toml', 'name = "polar_cargo"\nmmsi = 230000001')
        + SECOND + '[[ships.links]]\nname = "console"\ntype = "nmea0183"\nudp_port = 10111\n')
    with pytest.raises(UserError, match="the console's link is named 'console', as a link of links \\(or of a ship"):
        RunConsole(load_config(path), str(path), tmp_path)


def test_a_ship_without_links_or_an_mmsi_is_refused(tmp_path):
    assert "ships.0.links: ship 230000002 has no links" in _config_error(tmp_path, SECOND)
    path = tmp_path / "no_mmsi.toml"
    path.write_text(load_config.__globals__["DEFAULT_CONFIG"].read_text() + SECOND
                    + '[[ships.links]]\nname = "b"\ntype = "nmea0183"\nudp_port = 10111\n')
    r = subprocess.run([sys.executable, "-m", "bridge_node", "run", "--config", str(path), "--duration", "1"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "ship.mmsi: required when [[ships]] lists other own ships" in r.stderr
    assert str(path) in r.stderr and "Traceback" not in r.stderr


@pytest.fixture(scope="module")
def fleet_run(tmp_path_factory):
    """``icebridge run`` for 12 s, recorded, with a second ship whose bridge is rendered too;
    each ship's instruments on NMEA 0183 (UDP). The config, the summary and the folder."""
    tmp_path = tmp_path_factory.mktemp("fleet_run")
    channel = '[[render.channels]]\nname = "bow"\nwidth = 160\nheight = 90\n'
    path = exercise_toml(tmp_path, channel)
    text = path.read_text().replace('[ship]\nname = "polar_cargo"\n', f'[ship]\nname = "polar_cargo"\nmmsi = {MMSI_A}\n')
    path.write_text(text + f'[[links]]\nname = "a_instruments"\ntype = "nmea0183"\nudp_port = {free_port()}\n'
                    f'[[ships]]\nname = "polar_cargo"\nmmsi = {MMSI_B}\nstart_north = -400.0\n'
                    f'start_east = 250.0\nrender = true\n[[ships.links]]\nname = "b_instruments"\ntype = "nmea0183"\n'
                    f'udp_port = {free_port()}\n')
    r = subprocess.run([sys.executable, "-m", "bridge_node", "run", "--config", str(path), "--duration", "12",
                        "--out", str(tmp_path / "out"), "--json", "--render", "local"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    return path, json.loads(r.stdout), tmp_path


def test_each_bridge_renders_from_its_own_ship_and_the_record_replays_both(fleet_run):
    """Each render process rides its own ship, the run's summary reports both ships, and its
    record replays both."""
    _, summary, tmp_path = fleet_run
    (second,) = summary["other_ships"]
    assert second["north_m"] > -400.0 and second["east_m"] == pytest.approx(250.0, abs=5.0)  # under way
    rendered = {p["ship"]: p for p in summary["render_processes"]}
    assert sorted(rendered) == [0, 1] and all(p["exit"] == 0 and p["frames"] > 0 for p in rendered.values())
    # each process's eyes rode its own ship to the end (a step behind, blended: within a few metres)
    assert rendered[0]["eye_ship"]["north_m"] == pytest.approx(summary["north_m"], abs=3.0)
    assert rendered[1]["eye_ship"]["north_m"] == pytest.approx(second["north_m"], abs=3.0)
    assert (tmp_path / "out" / "ship1" / "panorama.png").is_file()
    # the record replays both ships to where the run left them (its own node.toml: exact)
    r = subprocess.run([sys.executable, "-m", "bridge_node", "replay", summary["record"], "--max", "--render", "none",
                        "--json", "--out", str(tmp_path / "replay")], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    replayed = json.loads(r.stdout)
    assert replayed["end"] == {"north_m": summary["north_m"], "east_m": summary["east_m"]}
    assert replayed["other_ships"] == [{"north_m": second["north_m"], "east_m": second["east_m"]}]


def test_the_debrief_map_plays_back_every_ship(fleet_run):
    config, summary, tmp_path = fleet_run
    (second,) = summary["other_ships"]
    port = free_port()
    station = start(tmp_path, "debrief", "instructor", "--config", str(config), "--record", summary["record"],
                    "--port", str(port))
    try:
        url = f"http://127.0.0.1:{port}/"
        wait_until(lambda: station.poll() is None and http(url)[0] == 200, 120, "the debrief page")
        with chromium() as browser:
            browser.get(url)
            wait_until(lambda: browser.execute_script("return !!(playback.data && map.frame)"), 90, "the record played")
            (shown,) = browser.execute_script("return playback.data.ships")
            assert (shown["k"], shown["name"], shown["length"], shown["beam"]) == (1, "POLAR CARGO", 150.0, 24.0)
            browser.execute_script("seekTo(playback.data.duration); map.setFollow(false); map.cx = arguments[0];"
                                   "map.cy = arguments[1]; map.scale = 1; map.dirty = true;",
                                   second["east_m"], second["north_m"])
            (ship,) = wait_until(lambda: browser.execute_script("return map.frame.traffic"), 10, "the other ship")
            # where its instruments were last told it was (the last RMC, sent up to a second before the end)
            assert math.dist((ship["x"], ship["y"]), (second["east_m"], second["north_m"])) < 8.0
            x, y = (round(v) for v in canvas_pixel(browser, ship["x"], ship["y"]))
            assert near(screenshot(browser)[y - 3:y + 4, x - 3:x + 4], TRAFFIC_RGB, 20).mean() > 0.5
    finally:
        stop(station)


@pytest.fixture(scope="module")
def fleet_world(tmp_path_factory):
    """The two-ship config and its compiled world."""
    cfg = _fleet_config(tmp_path_factory.mktemp("fleet_world"), 10199)
    return cfg, build_world(cfg, None)


def test_a_follower_sees_the_first_ship_as_traffic_and_bad_ship_reports_are_refused(fleet_world):
    cfg, model = fleet_world
    data = start_world(model, cfg)
    for _ in range(5):
        step(model, data, 0.1, [Controls(rudder=0.1), Controls(rudder=-0.2)])
    events, _, traffic = decode(encode(snapshot(model, data)))
    (b,) = events.others
    assert (b.outputs.north, b.outputs.east) == pytest.approx((data.ships[1].eta[0], data.ships[1].eta[1]))
    follow = FollowedShip(1, MMSI_B, (MMSI_A, 150.0, 22.0))
    seen, rows = follow(events, traffic)
    assert seen.ship == b.outputs and seen.others[0].outputs == events.ship
    assert rows.tolist() == [(MMSI_A, events.ship.east, events.ship.north, events.ship.heading,
                              events.ship.speed_over_ground, 150.0, 22.0)]
    assert followed_model(model, 1).ships[0] is model.ships[1]
    p = model.ships[1].particulars  # render-snapshot draws ship B as the stream's traffic does in a run
    assert other_ships(cfg, model, events).tolist() == [(MMSI_B, b.outputs.east, b.outputs.north, b.outputs.heading,
                                                         b.outputs.speed_over_ground, p.length, p.beam)]
    assert exercise_status(events)["other_ships"][0]["north_m"] == pytest.approx(b.outputs.north, abs=1e-3)
    with pytest.raises(ValueError, match="the stream carries 1 ships; ship 1 is none"):
        follow(dataclasses.replace(events, others=()), traffic)
    frames = encode(events)
    header = json.loads(frames[1])
    for bad in ({"ice_load": [1.0]}, {"outputs": header["others"][0]["outputs"] | {"north": float("nan")}},
                {"outputs": {"north": 1.0}}):
        others = [header["others"][0] | bad]
        with pytest.raises(CodecError):
            decode([frames[0], json.dumps(header | {"others": others}).encode(), *frames[2:]])


def test_the_instructor_fails_one_ships_steering_engine_and_gyro(fleet_world):
    cfg, model = fleet_world
    data = start_world(model, cfg)
    settings = ControlSettings(endpoint=f"tcp://127.0.0.1:{free_port()}")
    queue = CommandQueue(settings.queue, settings.per_tick)
    parser = argparse.ArgumentParser()
    ctl.add_arguments(parser)
    gyro = ctl.command_of(parser.parse_args(["sensor-failure", "gyro", "offset", "--offset", "10", "--ship", "1"]))
    with ControlEndpoint(settings, queue, dict, ships=2):
        for command in ({"command": "steering_failure", "pumps_failed": 2, "ship": 1},
                        {"command": "engine_failure", "power_percent": 30.0, "ship": 1}, gyro):
            assert request(settings.endpoint, {"command": command}, None)["ok"]
        refused = request(settings.endpoint, {"command": {"command": "engine_failure", "power_percent": 0.0,
                                                          "ship": 2}}, None)
    assert not refused["ok"] and "ship = 2: this exercise has 2 own ship(s): 0 ([ship]) to 1" in refused["error"]
    applied = queue.take(model, data)
    events = step(model, data, 0.1, None, applied)
    (a, b), records = data.ships, [command_record(c) for c in applied]
    assert (b.steering_pumps, b.power_share) == (0, 0.3) and (a.steering_pumps, a.power_share) == (2, 1.0)
    assert [r["ship"] for r in records] == [1, 1, 1]  # the session record's command log keeps the ship
    assert [command_from_record(r) for r in records] == list(applied)
    # ship B's gyro reads 10 deg high on its instruments; ship A's read true
    report = events.others[0]
    assert report.readings.heading == pytest.approx((report.outputs.heading + math.radians(10.0)) % (2 * math.pi))
    assert events.readings is events.ship
    status = exercise_status(events, data)
    assert status["sensors"]["gyro"] == "ok" and status["other_ships"][0]["sensors"]["gyro"] == "offset"
    assert (status["other_ships"][0]["steering_pumps"], status["other_ships"][0]["power_percent"]) == (0, 30.0)
    log = EventLog()  # the station's: ship B's failures named and kept, the first ship's untouched
    log.on_events(events)
    assert [e["text"] for e in log.since(0)][-1].startswith("ship 1: ")
    first, second = log.failures.ships
    assert (first.steering, first.power, first.sensors["gyro"]) == (2, 1.0, "ok")
    assert (second.steering, second.power, second.sensors["gyro"]) == (0, 0.3, "offset")
    assert log.alarms(0.0, None) == ["ship 1: steering gear: rudder stuck (both pumps failed)",
                                     "ship 1: engine: 30 % power", "ship 1: sensor: gyro offset"]
    repaired = dict(status, seq=status["seq"] + 1, other_ships=[status["other_ships"][0] | {
        "steering_pumps": 2, "power_percent": 100.0, "sensors": {"gyro": "ok", "gnss": "ok", "log": "ok"}}])
    log.on_status(status | {"seq": status["seq"] - 1, "other_ships": repaired["other_ships"]})
    assert log.failures.panel()[1]["pumps_failed"] == 2  # a reply older than the stream's failure is not taken
    log.on_status(repaired)
    assert log.failures.panel() == [{"pumps_failed": 0, "power_percent": 100.0, "sensors": first.sensors}] * 2
    assert log.alarms(0.0, None) == []



def test_the_instructor_moves_one_ship_of_several(fleet_world):
    """``icebridge ctl reposition --ship 1`` moves the second ship alone, once the tiles
    about its new place are prepared; the command log keeps the ship and the instructor's
    event list names it."""
    cfg, model = fleet_world
    data = start_world(model, cfg)
    parser = argparse.ArgumentParser()
    ctl.add_arguments(parser)
    args = parser.parse_args(["reposition", "--north", "350", "--east", "60", "--heading", "90", "--speed", "2",
                              "--ship", "1"])
    settings = ControlSettings(endpoint=f"tcp://127.0.0.1:{free_port()}")
    queue = CommandQueue(settings.queue, settings.per_tick)
    with ControlEndpoint(settings, queue, dict, ships=2):
        assert request(settings.endpoint, {"command": ctl.command_of(args)}, None)["ok"]
    first = data.ships[0].eta.copy()
    commands, moved = queue.take(model, data), None
    for _ in range(200):
        events = step(model, data, 0.1, None, commands)
        commands = ()
        moved = moved or next((c for c in events.commands if isinstance(c, Reposition)), None)
        if moved:
            break
    assert moved is not None and moved.ship == 1 and moved.at_once
    b = data.ships[1]
    assert (b.eta[0], b.eta[1], math.degrees(b.eta[5])) == pytest.approx((350.0, 60.0, 90.0), abs=0.5)
    assert b.nu[0] == pytest.approx(2.0 * KNOT, abs=0.05)
    assert abs(data.ships[0].eta[0] - first[0]) < 50.0 and data.ships[0].eta[1] == pytest.approx(first[1], abs=1.0)
    assert command_from_record(command_record(moved)) == moved
    assert describe(moved) == ("command", "ship 1: ship repositioned to N 350 m, E 60 m, heading 90 deg, 2.0 kn")
