"""CAN link on python-can's virtual bus and on slcan over a pty: console orders in, NMEA 2000
out, checked with an independent decoder (the nmea2000 package and its canboat database)."""
import math
import time

import can
import cantools
import pytest
from nmea2000.decoder import NMEA2000Decoder

from bridge_node.config import DEFAULT_CONFIG
from bridge_node.link_hub import LinkHub
from bridge_node.links.n2k_frames import identifier
from links_helpers import node_config, pty_pair, wait_for
from sim_core.ship_outputs import ShipOutputs

CONSOLE = cantools.database.load_file(str(DEFAULT_CONFIG.parent / "console.dbc"))
STATE = ShipOutputs(time=10.0, north=100.0, east=50.0, latitude=math.radians(74.0012345),
                    longitude=math.radians(20.0054321), heading=math.radians(123.4), course_over_ground=math.radians(125.0),
                    speed_over_ground=4.321, speed_longitudinal=4.3, speed_transverse=-0.2, rate_of_turn=math.radians(0.35),
                    rudder_angle=math.radians(-12.3), shaft_rps=1.234, ice_resistance=1.5e5)


def console_frame(name: str, source: int = 0x42, **values) -> can.Message:
    spec = CONSOLE.get_message_by_name(name)
    pgn = {"HelmOrder": 0xFF50, "EngineOrder": 0xFF51}[name]
    return can.Message(arbitration_id=identifier(6, pgn, source), data=spec.encode(values), is_extended_id=True)


def rudder_order_pgn(angle_rad: float, source: int = 0x10) -> can.Message:
    raw = int(round(angle_rad / 1e-4)) & 0xFFFF
    data = bytes([0, 0xF8 | (1 if angle_rad > 0 else 2), raw & 0xFF, raw >> 8, 0xFF, 0x7F, 0xFF, 0xFF])
    return can.Message(arbitration_id=identifier(2, 127245, source), data=data, is_extended_id=True)


@pytest.fixture
def can_hub(request):
    channel = f"icebridge-test-{request.node.name}"
    cfg = node_config([{"type": "can", "name": "helm_can", "channel": channel}], rudder=["helm_can"],
                      engine=["helm_can"])
    hub = LinkHub(cfg, None)
    hub.open()
    peer = can.Bus(interface="virtual", channel=channel)
    yield hub, peer
    peer.shutdown()
    hub.close()


def test_identifier_matches_the_protocol_reference():
    assert identifier(2, 127245, 0x23) == 0x09F10D23


def test_console_orders_over_virtual_can(can_hub):
    hub, peer = can_hub
    peer.send(console_frame("HelmOrder", RudderOrder=-22.5, Status=1, Counter=1))
    peer.send(console_frame("EngineOrder", Engine=0, Lever=0, TelegraphPosition=3, Mode=1))
    d = hub.tick(STATE, time.monotonic())
    assert d.controls.rudder == pytest.approx(math.radians(-22.5))
    assert d.controls.telegraph == "half_ahead"
    peer.send(console_frame("EngineOrder", Engine=0, Lever=-40, TelegraphPosition=0, Mode=0))
    peer.send(rudder_order_pgn(math.radians(10.0)))  # an NMEA 2000 helm: PGN 127245 angle order
    d = hub.tick(STATE, time.monotonic())
    assert d.controls.lever == -40.0
    assert d.controls.rudder == pytest.approx(math.radians(10.0), abs=1e-4)


def test_bad_frames_are_counted_and_dropped(can_hub):
    hub, peer = can_hub
    peer.send(can.Message(arbitration_id=identifier(6, 0xFF50, 0x42), data=b"\x01", is_extended_id=True))  # DLC 1
    peer.send(console_frame("HelmOrder", RudderOrder=0.0, Status=0, Counter=1))  # status invalid
    raw = CONSOLE.get_message_by_name("HelmOrder").encode({"RudderOrder": 0.0, "Status": 1, "Counter": 1})
    peer.send(can.Message(arbitration_id=identifier(6, 0xFF50, 0x42), data=b"\x10\x27" + raw[2:],
                          is_extended_id=True))  # 1000.0 deg: out of range
    peer.send(can.Message(arbitration_id=0x123, data=b"\x00", is_extended_id=False))
    d = hub.tick(STATE, time.monotonic())
    assert d.controls.rudder is None
    errors = hub.links[0].health().errors
    assert errors["wrong_dlc"] == 1 and errors["invalid_status"] == 1 and errors["out_of_range"] == 1
    assert errors["unknown_frame"] == 1


def decoded_outputs(peer: can.BusABC) -> dict:
    dec, out = NMEA2000Decoder(), {}
    while (msg := peer.recv(timeout=0.05)) is not None:
        m = dec.decode(msg)
        if m is not None:
            out[m.PGN] = ({f.id: f.value for f in m.fields}, msg.arbitration_id)
    return out


def test_outputs_decode_with_an_independent_decoder(can_hub):
    hub, peer = can_hub
    hub.tick(STATE, time.monotonic())
    out = decoded_outputs(peer)
    assert set(out) == {127245, 127488, 127489, 127250, 127251, 129025, 129026}
    assert out[127245][1] == 0x09F10D23  # priority 2, our source address 0x23
    assert out[127245][0]["position"] == pytest.approx(STATE.rudder_angle, abs=1e-4)
    assert out[127245][0]["angleOrder"] is None  # not available
    assert out[127488][0]["speed"] == pytest.approx(STATE.shaft_rps * 60, abs=0.25)
    assert out[127489][0]["discreteStatus1"] in ("", [], None, 0)  # fast packet reassembled; no alarms
    assert out[127250][0]["heading"] == pytest.approx(STATE.heading, abs=1e-4)
    assert out[127251][0]["rate"] == pytest.approx(STATE.rate_of_turn, abs=3.2e-8)
    assert out[129025][0]["latitude"] == pytest.approx(74.0012345, abs=1e-7)
    assert out[129025][0]["longitude"] == pytest.approx(20.0054321, abs=1e-7)
    assert out[129026][0]["cog"] == pytest.approx(STATE.course_over_ground, abs=1e-4)
    assert out[129026][0]["sog"] == pytest.approx(STATE.speed_over_ground, abs=0.01)


def test_output_rates_are_kept(can_hub):
    hub, peer = can_hub
    t0 = time.monotonic()
    for k in range(21):  # 2 s of 20 Hz ticks on a simulated clock
        hub.tick(STATE, t0 + 0.1 * k)
    counts = {}
    while (msg := peer.recv(timeout=0.05)) is not None:
        pgn = (msg.arbitration_id >> 8) & 0x3FFFF
        counts[pgn] = counts.get(pgn, 0) + 1
    # over 2 s (ticks landing on due times may fall either side by rounding: +-1)
    assert abs(counts[127250] - 21) <= 1  # 10 Hz
    assert abs(counts[129026] - 9) <= 1  # 4 Hz
    assert counts[127489] % 4 == 0 and abs(counts[127489] // 4 - 5) <= 1  # 2 Hz, 4 fast-packet frames each


def test_console_over_slcan_on_a_pty(tmp_path):
    """The node on slcan, as with a USB-CAN adapter; the console on the other end of the pty."""
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = node_config([{"type": "can", "name": "slcan", "interface": "slcan", "channel": node_end}],
                          rudder=["slcan"], engine=["slcan"])
        hub = LinkHub(cfg, None)
        hub.open()
        console = can.Bus(interface="slcan", channel=console_end, bitrate=250000)
        try:
            console.send(console_frame("HelmOrder", RudderOrder=7.5, Status=1, Counter=2))
            got = []
            wait_for(lambda: got, poll=lambda: got.extend(
                [c for c in [hub.tick(STATE, time.monotonic()).controls.rudder] if c is not None]))
            assert got[0] == pytest.approx(math.radians(7.5))
            heading = None
            dec = NMEA2000Decoder()
            deadline = time.monotonic() + 2.0
            while heading is None and time.monotonic() < deadline:
                msg = console.recv(timeout=0.1)
                m = dec.decode(msg) if msg is not None else None
                if m is not None and m.PGN == 127250:
                    heading = {f.id: f.value for f in m.fields}["heading"]
            assert heading == pytest.approx(STATE.heading, abs=1e-4)
        finally:
            console.shutdown()
            hub.close()
