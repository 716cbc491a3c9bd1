"""AIS on the NMEA 0183 outputs: own ship as !AIVDO types 1 and 5, other vessels as !AIVDM,
at the class A reporting intervals; decoded by pyais and by a real gpsd reading the UDP
output."""
import dataclasses
import datetime as dt
import math
import socket
import time

import pytest
from gpsd_client import gpsd
from links_helpers import STATE, node_config, tick
from pyais import decode

from bridge_node.links.nmea0183.ais import AisReporter, AisSettings, report_interval
from bridge_node.links.messages import Vessel
from bridge_node.links.hub import LinkHub
from sim_core.frames.units import KNOT

AIS = {"mmsi": 257123450, "name": "POLAR CARGO", "call_sign": "LAXX7", "imo": 9123456, "ship_type": 70,
       "to_bow": 20, "to_stern": 130, "to_port": 10, "to_starboard": 12, "draught": 9.5, "destination": "LONGYEARBYEN"}
QUIET = {k: 0 for k in ("RMC", "GGA", "VTG", "ZDA", "HDT", "ROT", "RSA", "RPM", "VBW", "XDR")}
OTHER = Vessel(key="dis:1.2.3", mmsi=200123456, name="Icebreaker 1", time=0.0, latitude=math.radians(74.01),
               longitude=math.radians(20.02), heading=math.radians(271.0), course_over_ground=math.radians(270.0),
               speed_over_ground=5.0, rate_of_turn=0.0, length=110.0, beam=24.0)
UTC = dt.datetime(2026, 1, 2, 12, 34, 56, tzinfo=dt.timezone.utc)


def messages(sentences: list[str]) -> list:
    """pyais decodes, joining multi-sentence messages by their sequential message id."""
    out, parts = [], {}
    for s in sentences:
        fields = s.split(",")
        if fields[1] == "1":
            out.append((s[:6], decode(s).asdict()))
        else:
            parts.setdefault(fields[3], []).append(s)
            if len(parts[fields[3]]) == int(fields[1]):
                out.append((s[:6], decode(*parts.pop(fields[3])).asdict()))
    return out


def test_own_ship_as_aivdo_types_1_and_5_decode_to_the_ship():
    got = messages(AisReporter(AisSettings(**AIS)).own_ship(STATE, 0.0, UTC))
    assert [(talker, m["msg_type"]) for talker, m in got] == [("!AIVDO", 1), ("!AIVDO", 5)]
    pos, static = got[0][1], got[1][1]
    assert pos["mmsi"] == 257123450 and pos["status"] == 0 and pos["second"] == 56
    assert pos["lat"] == pytest.approx(74.0012345, abs=1e-4 / 60) and pos["lon"] == pytest.approx(20.0054321, abs=1e-4 / 60)
    assert pos["speed"] == pytest.approx(STATE.speed_over_ground / KNOT, abs=0.05)
    assert pos["course"] == pytest.approx(125.0, abs=0.05) and pos["heading"] == 123
    assert pos["turn"] == pytest.approx(math.degrees(STATE.rate_of_turn) * 60, rel=0.15)  # ROT_AIS quantisation
    assert (static["shipname"], static["callsign"], static["imo"], static["destination"]) == \
        ("POLAR CARGO", "LAXX7", 9123456, "LONGYEARBYEN")
    assert (static["to_bow"], static["to_stern"], static["to_port"], static["to_starboard"]) == (20, 130, 10, 12)
    assert static["draught"] == pytest.approx(9.5)


@pytest.mark.parametrize("speed_kn,turning,interval", [(8.0, False, 10.0), (8.0, True, 10 / 3), (18.0, False, 6.0),
                                                        (18.0, True, 2.0), (25.0, False, 2.0)])
def test_class_a_reporting_intervals(speed_kn, turning, interval):
    """Over 120 s on a simulated clock, ticked at 10 Hz: type 1 every ``interval``, type 5 once."""
    state = dataclasses.replace(STATE, speed_over_ground=speed_kn * KNOT,
                                rate_of_turn=math.radians(10 / 60 if turning else 1 / 60))  # 10 or 1 deg/min
    assert report_interval(state.speed_over_ground, state.rate_of_turn) == pytest.approx(interval)
    reporter = AisReporter(AisSettings(**AIS))
    types = [m["msg_type"] for k in range(1200) for _, m in messages(reporter.own_ship(state, 0.1 * k, UTC))]
    assert types.count(1) == math.ceil(120.0 / interval - 1e-9) and types.count(5) == 1


def test_other_vessels_as_aivdm_at_their_own_intervals():
    reporter = AisReporter(AisSettings(**AIS))
    fast = dataclasses.replace(OTHER, key="dis:1.2.4", mmsi=200123457, speed_over_ground=20 * KNOT)
    sent = [m for k in range(600) for m in messages(reporter.others([OTHER, fast], 0.1 * k, UTC))]
    assert {talker for talker, _ in sent} == {"!AIVDM"}
    by_mmsi = {}
    for _, m in sent:
        by_mmsi.setdefault((m["mmsi"], m["msg_type"]), []).append(m)
    assert len(by_mmsi[(200123456, 1)]) == 6 and len(by_mmsi[(200123457, 1)]) == 10  # 10 s and 6 s over 60 s
    pos, static = by_mmsi[(200123456, 1)][0], by_mmsi[(200123456, 5)][0]
    assert pos["lat"] == pytest.approx(74.01, abs=1e-4 / 60) and pos["heading"] == 271
    assert pos["speed"] == pytest.approx(5.0 / KNOT, abs=0.05)
    assert static["shipname"] == "ICEBREAKER 1" and static["to_bow"] + static["to_stern"] == 110
    assert not AisReporter(AisSettings(**AIS, other_vessels=False)).others([OTHER], 0.0, UTC)


def test_gpsd_decodes_the_own_ship_from_the_udp_output(tmp_path):
    """A real gpsd reading the link's UDP stream reports the own ship's AIS messages."""
    with gpsd(tmp_path) as (udp_port, collect):
        cfg = node_config([{"type": "nmea0183", "name": "plotter", "udp_port": udp_port, "rates": QUIET,
                            "ais": AIS}])
        with LinkHub(cfg.links, cfg.arbitration) as hub:
            t0 = time.monotonic()
            ticks = iter(range(10**6))
            reports = collect(lambda: tick(hub, STATE, t0 + 10.0 * next(ticks)), 5.0,
                              lambda r: {1, 5} <= {x.get("type") for x in r if x["class"] == "AIS"})
    ais = {r["type"]: r for r in reports if r["class"] == "AIS"}
    assert ais[1]["mmsi"] == 257123450 and ais[1]["lat"] == pytest.approx(74.0012345, abs=1e-4 / 60)
    assert ais[1]["heading"] == 123 and ais[1]["speed"] == pytest.approx(STATE.speed_over_ground / KNOT, abs=0.05)
    assert ais[5]["shipname"] == "POLAR CARGO" and ais[5]["to_stern"] == 130


def test_ais_config_errors_name_the_key():
    from pydantic import ValidationError

    with pytest.raises(ValidationError, match="ais.mmsi"):
        node_config([{"type": "nmea0183", "name": "p", "ais": AIS | {"mmsi": 1234}}])
    with pytest.raises(ValidationError, match="ais.name"):
        node_config([{"type": "nmea0183", "name": "p", "ais": AIS | {"name": "lower case"}}])


def test_no_ais_without_its_table():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.settimeout(0.3)
    cfg = node_config([{"type": "nmea0183", "name": "p", "udp_port": s.getsockname()[1], "rates": QUIET}])
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        tick(hub, STATE, time.monotonic())
    with pytest.raises(socket.timeout):
        s.recv(200)
    s.close()
