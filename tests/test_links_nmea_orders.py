"""NMEA 0183 and orders as real equipment sends them: autopilot talkers, port-only ROR,
twin-engine telegraphs, sentences that are not orders, heading that gpsd accepts, the UDP
copy per link, alarm texts that fit ALR, and no Modbus link-down alarm before a real failure."""
import datetime as dt
import math
import socket
import time

import pynmea2
import pytest
import serial
from conftest import free_port
from gpsd_client import gpsd, gpsd_version
from links_helpers import STATE, node_config, open_hub, paced_write, pty_pair, tick, wait_for
from modbus_console import ModbusConsole
from pydantic import ValidationError

from bridge_node.links.arbiter import OrderArbiter
from bridge_node.links.messages import ALARM_TEXT_MAX, Alarm, ControlInput
from bridge_node.links.hub import LINK_DOWN_ALARM, LinkHub
from bridge_node.links.nmea0183.sentences import ETL, PRC, ROR, SentenceError, parse_order, render_alarm
from bridge_node.links.settings import NAME_MAX, ArbitrationSettings
from bridge_node.exercise.order_refusals import REFUSED_TEXT
from sim_core.ship.orders import OrderKind


def kind_of(line: str, **kw) -> str | list:
    try:
        return parse_order(line, 0.0, "test", **kw)
    except SentenceError as exc:
        return exc.kind


def ror(talker: str, stbd: str, stbd_status: str, port: str = "", port_status: str = "V") -> str:
    return str(ROR(talker, "ROR", (stbd, stbd_status, port, port_status, "B")))


@pytest.mark.parametrize("talker", ["AG", "AP", "RC", "II", "IN"])
def test_autopilot_and_console_talkers_are_taken_by_default(talker):
    [order] = parse_order(ror(talker, "12.5", "A"), 0.0, "test")
    assert order.kind == OrderKind.RUDDER and order.value == pytest.approx(math.radians(12.5))


def test_other_talkers_only_when_allowed():
    assert kind_of(ror("GP", "5.0", "A")) == "talker_not_allowed"
    assert kind_of(ror("AP", "5.0", "A"), allowed_talkers=frozenset({"RC"})) == "talker_not_allowed"
    assert len(kind_of(ror("GP", "5.0", "A"), allowed_talkers=None)) == 1  # allowed_talkers = "any"
    with pytest.raises(ValidationError, match="allowed_talkers"):
        node_config([{"type": "nmea0183", "name": "n", "allowed_talkers": []}])


def test_port_only_starboard_only_and_twin_rudder_orders():
    [port_only] = parse_order("$RCROR,,V,-6.0,A*" + f"{_xor(',,V,-6.0,A', 'RCROR'):02X}", 0.0, "t")
    assert port_only.value == pytest.approx(math.radians(-6.0))
    [stbd_only] = parse_order(ror("RC", "4.0", "A", "", "V"), 0.0, "t")
    assert stbd_only.value == pytest.approx(math.radians(4.0))
    [twin] = parse_order(ror("RC", "-22.0", "A", "34.0", "A"), 0.0, "t")  # twin rudders move as one: their mean
    assert twin.value == pytest.approx(math.radians(6.0))
    assert kind_of(ror("RC", "4.0", "V", "-6.0", "V")) == "invalid_status"
    assert kind_of(ror("RC", "", "V", "nan", "A")) == "bad_field"


def _xor(fields: str, address: str) -> int:
    value = 0
    for c in address + fields:
        value ^= ord(c)
    return value


WELL_FORMED_NOT_ORDERS = [
    "!AIVDM,1,1,,A,13u?etPv2;0n:dDPwUM1U1Cb069D,0*24",  # AIS from a transponder on the same line
    str(pynmea2.GGA("GP", "GGA", ("120000.000", "7400.07407", "N", "02000.32593", "E", "1", "12", "0.8", "15.000",
                                  "M", "25.000", "M", "1.0", "0000", "extra", "fields", "from", "a", "receiver"))),
    str(pynmea2.RMC("GN", "RMC", ("120000.00", "A", "7400.0741", "N", "02000.3259", "E", "8.4", "125.0", "010126",
                                  "", "", "A", "V"))),
    "$IIXYZ,1,2,3*" + f"{_xor(',1,2,3', 'IIXYZ'):02X}",  # a type neither this node nor pynmea2 knows
    "$PGRME,15.0,M,45.0,M,25.0,M*" + f"{_xor(',15.0,M,45.0,M,25.0,M', 'PGRME'):02X}",  # proprietary
    str(ETL("RC", "ETL", ("120000.00", "A", "02", "30", "E", "0"))),  # the engine room's answer-back
]


@pytest.mark.parametrize("line", WELL_FORMED_NOT_ORDERS)
def test_well_formed_sentences_that_are_not_orders_are_ignored(line):
    assert kind_of(line) == "ignored"


def test_only_what_cannot_be_framed_is_malformed():
    assert len(WELL_FORMED_NOT_ORDERS[1]) > 82  # a long GGA is still well formed
    for line in ["garbage", "$GPGGA,1,2*ZZ", "$gpgga,1*00", "$GP$GGA,1*00", "$*00"]:
        assert kind_of(line) == "malformed", line
    assert kind_of("$IIXYZ,1,2,3*00") == "bad_checksum"  # framed, but corrupted: not merely ignored


def test_twin_engine_console_over_a_pty_drives_the_configured_engine_only(tmp_path):
    """Engines 1 and 2 alternate on the line, ETL and PRC; the link takes engine 1's only."""
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = node_config([{"type": "nmea0183", "name": "nmea", "port": node_end, "engine": 1,
                            "rates": {k: 0 for k in ("RMC", "GGA", "VTG", "ZDA", "HDT", "ROT", "RSA", "RPM", "VBW",
                                                     "XDR")}}],
                          engine=["nmea"])
        hub = LinkHub(cfg.links, cfg.arbitration)
        open_hub(hub)
        console = serial.Serial(console_end, 38400, timeout=0)
        telegraphs, levers = [], []
        try:
            for k in range(4):
                paced_write(console, [str(ETL("RC", "ETL", ("120000.00", "O", "04", "30", "B", "1"))),
                                      str(ETL("RC", "ETL", ("120000.00", "O", "00", "30", "B", "2")))], 38400)
                wait_for(lambda: hub.links[0].health().errors["other_engine"] >= k + 1,
                         poll=lambda: telegraphs.append(tick(hub, STATE, time.monotonic()).controls.telegraph))
            paced_write(console, [str(PRC("AP", "PRC", ("-30.0", "A", "", "V", "", "V", "B", "2"))),
                                  str(PRC("AP", "PRC", ("55.0", "A", "", "V", "", "V", "B", "1")))], 38400)
            wait_for(lambda: 55.0 in levers,
                     poll=lambda: levers.append(tick(hub, STATE, time.monotonic()).controls.lever))
        finally:
            console.close()
            hub.close()
    assert {t for t in telegraphs if t is not None} == {"full_ahead"}  # never flipped to engine 2's stop
    assert -30.0 not in levers
    assert hub.links[0].health().errors["other_engine"] == 5
    assert hub.order_counts == {"nmea/telegraph/1": 4, "nmea/lever/1": 1}


def test_non_order_traffic_on_the_line_is_ignored_not_malformed(tmp_path):
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = node_config([{"type": "nmea0183", "name": "nmea", "port": node_end}], rudder=["nmea"])
        hub = LinkHub(cfg.links, cfg.arbitration)
        open_hub(hub)
        console = serial.Serial(console_end, 38400, timeout=0)
        got = []
        try:
            paced_write(console, WELL_FORMED_NOT_ORDERS + ["#garbage", ror("AG", "-3.0", "A")], 38400)
            wait_for(lambda: got, poll=lambda: got.extend(
                [r for r in [tick(hub, STATE, time.monotonic()).controls.rudder] if r is not None]))
        finally:
            console.close()
            hub.close()
    assert got == [pytest.approx(math.radians(-3.0))]
    assert dict(hub.links[0].health().errors) == {"ignored": len(WELL_FORMED_NOT_ORDERS), "malformed": 1}


def gpsd_headings(talkers: dict, tmp_path) -> list:
    """Run the node's UDP output into a real gpsd; the headings gpsd reports."""
    with gpsd(tmp_path) as (udp_port, collect):
        cfg = node_config([{"type": "nmea0183", "name": "instruments", "udp_port": udp_port, "talkers": talkers}])
        with LinkHub(cfg.links, cfg.arbitration) as hub:
            # two fixes and a heading; without a heading, four fixes (gpsd reports a fix and a
            # heading as they come: on a loaded machine two fixes can come before the heading)
            reports = collect(lambda: tick(hub, STATE, time.monotonic()), 5.0,
                              lambda r: sum(x["class"] == "TPV" for x in r) >= (2 if any(x["class"] == "ATT"
                                                                                         for x in r) else 4))
    assert any(r["class"] == "TPV" and r.get("lat") == pytest.approx(74.0012345, abs=1e-5) for r in reports)
    return [r["heading"] for r in reports if r["class"] == "ATT" and "heading" in r]


def test_gpsd_shows_the_heading_of_the_default_talkers(tmp_path):
    """gpsd as Debian 12 ships it (3.22) takes the default HDT; a gyro's HE talker it drops."""
    headings = gpsd_headings({}, tmp_path)
    assert headings and all(h == pytest.approx(123.4, abs=0.05) for h in headings)
    if gpsd_version() < (3, 24):
        assert gpsd_headings({"HDT": "HE"}, tmp_path) == []  # why HE is no longer the default


def udp_socket() -> socket.socket:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.settimeout(0.3)
    return s


def received(s: socket.socket) -> set[str]:
    types = set()
    try:
        while True:
            types.add(pynmea2.parse(s.recv(200).decode().strip()).sentence_type)
    except socket.timeout:
        return types


def test_udp_copy_is_per_link_and_off_for_serial_links_by_default(tmp_path):
    a, b, c = udp_socket(), udp_socket(), udp_socket()
    with pty_pair(tmp_path) as (node_end, _):
        cfg = node_config([
            {"type": "nmea0183", "name": "plotter", "udp_port": a.getsockname()[1]},  # UDP only: on
            {"type": "nmea0183", "name": "console", "port": node_end, "udp_port": b.getsockname()[1]},  # off
            {"type": "nmea0183", "name": "ecdis", "udp_port": c.getsockname()[1], "udp_output": False},
        ])
        with LinkHub(cfg.links, cfg.arbitration) as hub:
            tick(hub, STATE, time.monotonic())
    assert {"RMC", "HDT"} <= received(a)
    assert received(b) == set() and received(c) == set()
    for s in (a, b, c):
        s.close()


def test_two_links_sending_to_one_udp_port_is_a_config_error():
    with pytest.raises(ValidationError) as err:
        node_config([{"type": "nmea0183", "name": "a"}, {"type": "nmea0183", "name": "b"}])
    assert "links.1.udp_port = 10110" in str(err.value) and "'a'" in str(err.value)
    node_config([{"type": "nmea0183", "name": "a"}, {"type": "nmea0183", "name": "b", "udp_port": 10111}])


def test_every_alarm_text_fits_alr_whole_with_the_longest_link_names():
    """Every alarm the node raises, with link names of the longest allowed length, goes out
    as an ALR sentence of at most 82 characters whose text field is the whole text."""
    a, b = "a" * NAME_MAX, "b" * NAME_MAX
    arb = OrderArbiter(ArbitrationSettings(rudder=[a, b], engine=[a, b], fail_safe_after_s=0.5), {a: 1.0, b: 1.0})
    alarms = []
    arb.feed([ControlInput(0.0, a, OrderKind.RUDDER, 0.1), ControlInput(0.5, b, OrderKind.RUDDER, 0.2),
              ControlInput(0.0, a, OrderKind.TELEGRAPH, "stop")])
    for now in (0.0, 1.2, 2.0, 3.0, 3.5):
        alarms += arb.decide(now).alarms
    arb.feed([ControlInput(3.6, a, OrderKind.RUDDER, 0.1)])
    alarms += arb.decide(3.6).alarms
    alarms += [Alarm(LINK_DOWN_ALARM, f"link {a} down", True), Alarm(LINK_DOWN_ALARM, f"link {a} up", False)]
    alarms += [Alarm(n, t, True) for n, t in REFUSED_TEXT.items()]
    assert {x.number for x in alarms} >= {101, 102, 111, 112, 121, 122, LINK_DOWN_ALARM}
    assert {f"rudder source stale; now {b}", f"rudder source {a} in use"} <= {x.text for x in alarms}
    for alarm in alarms:
        line = render_alarm(alarm, dt.datetime(2026, 1, 1, 23, 59, 59, 990000, tzinfo=dt.timezone.utc))
        assert len(line) + 2 <= 82, line
        assert pynmea2.parse(line, check=True).data[-1] == alarm.text
    with pytest.raises(ValueError, match="at most"):
        Alarm(1, "x" * (ALARM_TEXT_MAX + 1), True)
    with pytest.raises(ValidationError, match="at most 24"):
        node_config([{"type": "nmea0183", "name": "n" * (NAME_MAX + 1)}])


def accepts(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
    except OSError:
        return False
    return True


def test_modbus_link_raises_no_down_alarm_while_starting_only_after_a_real_failure():
    console = ModbusConsole("tcp")
    console.start()
    try:
        wait_for(lambda: accepts(console.port))  # the console is up: a refused connection would be a failure
        cfg = node_config([{"type": "modbus", "name": "io", "port": console.port, "poll_hz": 50,
                            "registers": [{"order": "rudder", "address": 0}]}], rudder=["io"])
        with LinkHub(cfg.links, cfg.arbitration) as hub:
            wait_for(lambda: hub.links[0].connected, poll=lambda: tick(hub, STATE, time.monotonic()))
            assert LINK_DOWN_ALARM not in {a.number for _, a in hub.alarm_log}  # not while it started
            console.stop()
            wait_for(lambda: LINK_DOWN_ALARM in hub.active_alarms, timeout=5.0,
                     poll=lambda: tick(hub, STATE, time.monotonic()))
    finally:
        console.stop()
    dead = node_config([{"type": "modbus", "name": "io", "port": free_port(),
                         "registers": [{"order": "rudder", "address": 0}]}])
    with LinkHub(dead.links, dead.arbitration) as hub:  # no console at all: its refused connect is a failure
        wait_for(lambda: LINK_DOWN_ALARM in hub.active_alarms, poll=lambda: tick(hub, STATE, time.monotonic()))
        assert hub.errors()["connect_failed"] >= 1
