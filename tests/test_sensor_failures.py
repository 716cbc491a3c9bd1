"""The instructor's sensor failures: what the instruments read (gyro frozen or offset, GNSS
lost or jumping, speed log frozen) while the ship, its picture and the other simulators go
on with the truth; a lost fix reads as no fix on every output (NMEA 0183, NMEA 2000, AIS)."""
import dataclasses
import datetime as dt
import math
import socket
import time

import pynmea2
import pytest
from conftest import free_port
from links_helpers import STATE, node_config
from opendis.PduFactory import createPdu
from opendis.RangeCoordinates import GPS
from pyais import decode

from bridge_node.control.commands import CommandError, command_from_record, command_record, parse_command
from bridge_node.exercise.listeners import LinkOutputs
from bridge_node.exercise.tick import TickOutcome
from bridge_node.links.nmea0183.ais import position_report
from bridge_node.links.can.link import _n2k_fields, dbc_path, load_dbc
from bridge_node.links.hub import LinkHub
from bridge_node.links.nmea0183.sentences import render_outputs
from bridge_node.node.config import load_config
from bridge_node.node.world_setup import open_water_world
from sim_core.instructor import Reposition
from sim_core.ship.sensors import JUMP_PERIOD_S, SensorFailure
from sim_core.world import Controls, step

DT = 1.0 / 30.0
NAMES = ["RMC", "GGA", "VTG", "HDT", "ROT", "VBW"]


def run(commands_at: dict[int, tuple], steps: int, rudder: float = 0.0):
    """The default ship in open water at 6 m/s, rudder ``rudder`` rad, full ahead, with
    commands at steps; returns the events of every step."""
    model, data = open_water_world(load_config(), None)
    start = Reposition(float(data.ship.eta[0]), float(data.ship.eta[1]), 0.0, 6.0, at_once=True)
    out = []
    for k in range(steps):
        commands = (start,) * (k == 0) + commands_at.get(k, ())
        out.append(step(model, data, DT, Controls(rudder=rudder, telegraph="full_ahead"), commands))
    return model, data, out


def test_a_frozen_gyro_holds_its_heading_and_an_offset_gyro_reads_off_by_it():
    _, _, events = run({30: (SensorFailure("gyro", "frozen"),), 600: (SensorFailure("gyro", "offset", 0.1),)},
                       660, rudder=math.radians(20.0))
    held = events[29].ship.heading  # (a command is applied at its step's start)
    for e in events[30:600]:
        assert e.readings.heading == held and e.readings.rate_of_turn == 0.0
    assert math.radians(5.0) < events[599].ship.heading < math.pi  # the ship turned under the frozen gyro
    last = events[-1]
    assert last.readings.heading == pytest.approx((last.ship.heading + 0.1) % (2 * math.pi))
    assert last.readings.rate_of_turn == last.ship.rate_of_turn


def test_a_jumping_fix_jumps_by_its_size_the_same_in_every_run_and_repairs():
    failure = (SensorFailure("gnss", "jumping", 300.0),)
    _, _, first = run({5: failure, int(2 * JUMP_PERIOD_S / DT): (SensorFailure("gnss", "ok"),)}, 700)
    _, _, again = run({5: failure}, 30)
    jumps = [math.hypot(e.readings.north - e.ship.north, e.readings.east - e.ship.east) for e in first[5:600]]
    assert all(j == pytest.approx(300.0) for j in jumps)
    offsets = {(round(e.readings.north - e.ship.north, 6), round(e.readings.east - e.ship.east, 6))
               for e in first[5:600]}
    assert len(offsets) >= 2  # a new direction every JUMP_PERIOD_S
    assert [e.readings for e in first[:30]] == [e.readings for e in again]
    assert first[-1].instruments is None and first[-1].readings == first[-1].ship  # repaired: the truth again


def test_a_frozen_log_holds_the_speeds_it_had():
    _, _, events = run({10: (SensorFailure("log", "frozen"),)}, 900)
    assert events[-1].ship.speed_longitudinal > events[9].ship.speed_longitudinal + 0.1  # the ship sped up
    assert events[-1].readings.speed_longitudinal == events[9].ship.speed_longitudinal


def test_a_lost_fix_is_no_fix_on_nmea_0183_nmea_2000_and_ais():
    lost = dataclasses.replace(STATE, fix_valid=False)
    now = dt.datetime(2026, 4, 1, 10, 40, tzinfo=dt.timezone.utc)
    rmc, gga, vtg, hdt, *_ = [pynmea2.parse(s) for s in render_outputs(NAMES, lost, now, {})]
    assert rmc.status == "V" and rmc.lat == "" and rmc.lon == "" and rmc.mode_indicator == "N"
    assert gga.gps_qual == 0 and gga.lat == ""
    assert vtg.faa_mode == "N" and vtg.spd_over_grnd_kts is None
    assert float(hdt.heading) == pytest.approx(math.degrees(STATE.heading), abs=0.05)  # the gyro still reads
    db = load_dbc(dbc_path("nmea2000.dbc"))
    position = db.get_message_by_name("PositionRapid")
    raw = position.decode(position.encode(_n2k_fields("position", lost, 0), strict=False), decode_choices=False,
                          scaling=False)
    assert raw["Latitude"] == raw["Longitude"] == 0x7FFFFFFF
    cog_sog = db.get_message_by_name("CogSogRapid")
    raw = cog_sog.decode(cog_sog.encode(_n2k_fields("cog_sog", lost, 0), strict=False), decode_choices=False,
                         scaling=False)
    assert raw["Cog"] == raw["Sog"] == 0xFFFF
    report = decode(*position_report(257123450, lost, now, "VDO")).asdict()
    assert (report["lat"], report["lon"], report["speed"], report["course"]) == (91.0, 181.0, 102.3, 360.0)


def test_the_instruments_read_the_failure_and_dis_carries_the_truth():
    """A real world step with the fix lost and the gyro offset: an NMEA link's RMC says no
    fix and its HDT the offset heading, while the DIS link's PDU has where the ship is."""
    model, data = open_water_world(load_config(), None)
    nmea_rx, dis_rx = (socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(2))
    for s in (nmea_rx, dis_rx):
        s.bind(("127.0.0.1", 0))
        s.settimeout(1.0)
    cfg = node_config([{"type": "nmea0183", "name": "ecdis", "udp_port": nmea_rx.getsockname()[1],
                        "rates": {k: 0 for k in ("GGA", "VTG", "ZDA", "ROT", "RSA", "RPM", "VBW", "XDR")}},
                       {"type": "dis", "name": "dis", "listen_port": free_port(),
                        "send_to": [f"127.0.0.1:{dis_rx.getsockname()[1]}"]}])
    commands = (SensorFailure("gnss", "lost"), SensorFailure("gyro", "offset", math.radians(30.0)))
    events = step(model, data, DT, Controls(), commands)
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        now = time.monotonic()
        hub.poll(now)
        LinkOutputs(hub).on_step(TickOutcome(events, Controls(), (), now, None))
        sentences = {}
        while len(sentences) < 2:
            for line in nmea_rx.recv(4096).decode().split():
                msg = pynmea2.parse(line)
                sentences[msg.sentence_type] = msg
        pdu = createPdu(dis_rx.recv(4096))
    nmea_rx.close()
    dis_rx.close()
    assert sentences["RMC"].status == "V"
    truth = events.ship
    assert float(sentences["HDT"].heading) == pytest.approx((math.degrees(truth.heading) + 30.0) % 360.0, abs=0.05)
    loc = pdu.entityLocation
    lat, lon, *_ = GPS().ecef2llarpy(loc.x, loc.y, loc.z, 0.0, 0.0, 0.0)
    assert lat == pytest.approx(truth.latitude, abs=1e-8) and lon == pytest.approx(truth.longitude, abs=1e-8)


@pytest.mark.parametrize("message, words", [
    ({"command": "sensor_failure", "sensor": "gyro", "mode": "lost"}, ["'lost'", "gyro's: ok, frozen, offset"]),
    ({"command": "sensor_failure", "sensor": "gyro", "mode": "offset"}, ["offset_deg (-180 to 180)"]),
    ({"command": "sensor_failure", "sensor": "gyro", "mode": "offset", "offset_deg": 200.0}, ["offset_deg = 200.0"]),
    ({"command": "sensor_failure", "sensor": "log", "mode": "frozen", "jump_m": 50.0}, ["jump_m (10 to 2000)"]),
    ({"command": "sensor_failure", "sensor": "radar", "mode": "ok"}, ["sensor = \"radar\"", "'gyro'"]),
])
def test_a_bad_sensor_failure_is_refused_naming_what_is_allowed(message, words):
    with pytest.raises(CommandError) as refused:
        parse_command(message)
    for word in words:
        assert word in str(refused.value), str(refused.value)


def test_sensor_failures_become_world_commands_and_round_trip_as_records():
    model, data = open_water_world(load_config(), None)
    gyro = parse_command({"command": "sensor_failure", "sensor": "gyro", "mode": "offset", "offset_deg": -12.5})
    gnss = parse_command({"command": "sensor_failure", "sensor": "gnss", "mode": "jumping"})
    assert gyro.to_world(model, data) == SensorFailure("gyro", "offset", math.radians(-12.5))
    assert gnss.to_world(model, data) == SensorFailure("gnss", "jumping", 200.0)
    for command in (gyro.to_world(model, data), gnss.to_world(model, data)):
        assert command_from_record(command_record(command)) == command
    with pytest.raises(CommandError):
        command_from_record({"type": "SensorFailure", "sensor": "gyro", "mode": "jumping", "amount": 1.0})
