"""Serial NMEA 0183 link over a real pty pair (socat): console sentences in at real baud
pacing, instrument sentences out (parsed back with pynmea2), and the UDP mirror on loopback."""
import math
import os
import socket
import time

import pynmea2
import pytest
import serial
from links_helpers import STATE, bare_pty, node_config, open_hub, order_collector, paced_write, pty_pair, tick, wait_for

from bridge_node.links.hub import LinkHub
from bridge_node.links.nmea0183.sentences import ETL, PRC, ROR

KNOT = 1852 / 3600


def udp_listener() -> socket.socket:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.settimeout(0.5)
    return s


@pytest.mark.parametrize("baud", [4800, 38400])
def test_console_orders_and_instrument_outputs_over_a_pty(tmp_path, baud):
    udp = udp_listener()
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = node_config([{"type": "nmea0183", "name": "nmea", "port": node_end, "baudrate": baud,
                            "udp_output": True, "udp_port": udp.getsockname()[1], "rates": {"RMC": 1, "GGA": 1, "VTG": 0, "ZDA": 0,
                            "HDT": 5, "ROT": 1, "RSA": 1, "RPM": 1, "VBW": 0, "XDR": 0}}],
                          rudder=["nmea"], engine=["nmea"])
        hub = LinkHub(cfg.links, cfg.arbitration)
        open_hub(hub)
        console = serial.Serial(console_end, baud, timeout=0)
        try:
            paced_write(console, [str(ROR("RC", "ROR", ("-22.0", "A", "", "V", "B"))),
                                  str(ETL("RC", "ETL", ("120000.00", "O", "02", "30", "B", "0")))], baud)
            got, collect = order_collector(hub, STATE)
            wait_for(lambda: "rudder" in got and "telegraph" in got, poll=collect)
            assert got["rudder"] == pytest.approx(math.radians(-22.0))
            assert got["telegraph"] == "slow_ahead"
            paced_write(console, [str(PRC("RC", "PRC", ("-45.0", "A", "", "V", "", "V", "B", "0")))], baud)
            wait_for(lambda: "lever" in got, poll=collect)
            assert got["lever"] == -45.0
            # instrument sentences on the line: parse every one with pynmea2 (checksums checked)
            text = b""
            deadline = time.monotonic() + 1.5
            while time.monotonic() < deadline:
                tick(hub, STATE, time.monotonic())
                text += console.read(4096)
                time.sleep(0.02)
        finally:
            console.close()
            hub.close()
    msgs = {}
    for line in text.decode().split("\r\n"):
        if line:
            m = pynmea2.parse(line, check=True)
            msgs[m.sentence_type] = m
            assert m.talker == {"RMC": "GP", "GGA": "GP", "HDT": "IN", "ROT": "IN"}.get(m.sentence_type, "II")
    assert float(msgs["HDT"].heading) == pytest.approx(123.4, abs=0.05)
    assert float(msgs["RSA"].rsa_starboard) == pytest.approx(-12.3, abs=0.05)
    assert float(msgs["RPM"].speed) == pytest.approx(STATE.shaft_rps * 60, abs=0.05)
    assert float(msgs["ROT"].rate_of_turn) == pytest.approx(0.35 * 60, abs=0.05)
    assert msgs["GGA"].latitude == pytest.approx(74.0012345, abs=1e-5)
    assert msgs["GGA"].longitude == pytest.approx(20.0054321, abs=1e-5)
    assert msgs["RMC"].spd_over_grnd == pytest.approx(STATE.speed_over_ground / KNOT, abs=0.05)
    # the same stream on UDP, on loopback
    datagrams = set()
    try:
        while True:
            datagrams.add(pynmea2.parse(udp.recv(200).decode().strip(), check=True).sentence_type)
    except socket.timeout:
        pass
    udp.close()
    assert {"RMC", "GGA", "HDT", "ROT", "RSA", "RPM"} <= datagrams


def test_bad_sentences_on_the_line_are_counted_not_fatal(tmp_path):
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = node_config([{"type": "nmea0183", "name": "nmea", "port": node_end,
                            "allowed_talkers": ["RC"]}], rudder=["nmea"])
        hub = LinkHub(cfg.links, cfg.arbitration)
        open_hub(hub)
        console = serial.Serial(console_end, 38400, timeout=0)
        try:
            good = str(ROR("RC", "ROR", ("5.0", "A", "", "V", "B")))
            console.write(b"\x00\xff garbage\r\n$RCROR,5.0,A,,V,B*00\r\n$RCROR,5.0,A\r\n"
                          + str(ROR("XX", "ROR", ("5.0", "A", "", "V", "B"))).encode() + b"\r\n"
                          + str(ROR("RC", "ROR", ("nan", "A", "", "V", "B"))).encode() + b"\r\n"
                          + str(ROR("RC", "ROR", ("500", "A", "", "V", "B"))).encode() + b"\r\n"
                          + good.encode() + b"\r\n")
            got = []
            wait_for(lambda: got, poll=lambda: got.extend(
                [r for r in [tick(hub, STATE, time.monotonic()).controls.rudder] if r is not None]))
        finally:
            console.close()
            hub.close()
    assert got == [pytest.approx(math.radians(5.0))]
    e = hub.links[0].health().errors
    assert e["malformed"] == 1 and e["bad_checksum"] == 1 and e["no_checksum"] == 1
    assert e["talker_not_allowed"] == 1 and e["bad_field"] == 1 and e["out_of_range"] == 1


def test_a_far_end_that_never_reads_does_not_block_the_loop():
    """The console never reads its end: the line's buffers fill, then the writer's queue;
    every publish still returns, the sentences beyond are dropped and counted, and the link
    still takes orders. A bare pty: socat's relay would itself stall on the full end."""
    with bare_pty() as (node_end, console):
        cfg = node_config([{"type": "nmea0183", "name": "nmea", "port": node_end, "baudrate": 38400}],
                          rudder=["nmea"])
        hub = LinkHub(cfg.links, cfg.arbitration)
        open_hub(hub)
        try:
            now = time.monotonic()
            for _ in range(2000):  # 2000 s of output on a simulated clock: about 1 MB, never read
                now += 1.0
                tick(hub, STATE, now)
            health = hub.links[0].health()
            assert health.connected and health.errors["send_failed"] > 0
            assert health.outputs > 0
            os.write(console, str(ROR("RC", "ROR", ("7.0", "A", "", "V", "B"))).encode() + b"\r\n")
            got = []

            def poll() -> None:
                nonlocal now
                now += 0.01
                rudder = tick(hub, STATE, now).controls.rudder
                got.extend([rudder] if rudder is not None else [])
            wait_for(lambda: got, poll=poll)
        finally:
            hub.close()
    assert got[0] == pytest.approx(math.radians(7.0))
    assert hub.links[0].health().errors["send_failed"] > 1000


def test_output_rates_beyond_the_baud_budget_are_a_config_error():
    from pydantic import ValidationError

    with pytest.raises(ValidationError, match="more than 384"):
        node_config([{"type": "nmea0183", "name": "nmea", "port": "/dev/null", "baudrate": 4800,
                      "rates": {"HDT": 20, "GGA": 5}}])
    with pytest.raises(ValidationError, match="not a loopback address"):
        node_config([{"type": "nmea0183", "name": "nmea", "udp_host": "192.168.1.20"}])
