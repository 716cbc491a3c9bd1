"""CAN link on python-can's virtual bus and on slcan over a pty: console orders in, NMEA 2000
out, checked with an independent decoder (the nmea2000 package and its canboat database)."""
import math
import threading
import time

import can
import pytest
from links_helpers import CONSOLE, STATE, console_frame, node_config, open_hub, pty_pair, rudder_order_pgn, tick, wait_for
from nmea2000.decoder import NMEA2000Decoder

from bridge_node.links.hub import LinkHub
from bridge_node.links.can.n2k_frames import identifier


@pytest.fixture
def can_hub(request):
    channel = f"icebridge-test-{request.node.name}"
    cfg = node_config([{"type": "can", "name": "helm_can", "channel": channel, "allowed_sources": [0x42, 0x10]}],
                      rudder=["helm_can"],
                      engine=["helm_can"])
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        peer = can.Bus(interface="virtual", channel=channel)
        yield hub, peer
        peer.shutdown()


def test_identifier_matches_the_protocol_reference():
    assert identifier(2, 127245, 0x23) == 0x09F10D23


def test_console_orders_over_virtual_can(can_hub):
    hub, peer = can_hub
    peer.send(console_frame("HelmOrder", RudderOrder=-22.5, Status=1, Counter=1))
    peer.send(console_frame("EngineOrder", Engine=0, Lever=0, TelegraphPosition=3, Mode=1))
    d = tick(hub, STATE, time.monotonic())
    assert d.controls.rudder == pytest.approx(math.radians(-22.5))
    assert d.controls.telegraph == "half_ahead"
    peer.send(console_frame("EngineOrder", Engine=0, Lever=-40, TelegraphPosition=0, Mode=0))
    peer.send(rudder_order_pgn(math.radians(10.0)))  # an NMEA 2000 helm: PGN 127245 angle order
    d = tick(hub, STATE, time.monotonic())
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
    d = tick(hub, STATE, time.monotonic())
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
    tick(hub, STATE, time.monotonic())
    out = decoded_outputs(peer)
    assert set(out) == {60928, 127245, 127488, 127489, 127250, 127251, 127257, 129025, 129026}  # the claim, outputs
    assert out[127245][1] == 0x09F10D23  # priority 2, our source address 0x23
    assert out[127245][0]["position"] == pytest.approx(STATE.rudder_angle, abs=1e-4)
    assert out[127245][0]["angleOrder"] is None  # not available
    assert out[127488][0]["speed"] == pytest.approx(STATE.shaft_rps * 60, abs=0.25)
    assert out[127489][0]["discreteStatus1"] in ("", [], None, 0)  # fast packet reassembled; no alarms
    assert out[127250][0]["heading"] == pytest.approx(STATE.heading, abs=1e-4)
    assert out[127251][0]["rate"] == pytest.approx(STATE.rate_of_turn, abs=3.2e-8)
    assert out[127257][1] >> 26 == 3  # the attitude at canboat's priority 3
    assert out[127257][0]["yaw"] == pytest.approx(STATE.heading - 2.0 * math.pi * (STATE.heading > math.pi), abs=1e-4)
    assert out[127257][0]["pitch"] == pytest.approx(STATE.pitch, abs=1e-4)
    assert out[127257][0]["roll"] == pytest.approx(STATE.roll, abs=1e-4)
    assert out[129025][0]["latitude"] == pytest.approx(74.0012345, abs=1e-7)
    assert out[129025][0]["longitude"] == pytest.approx(20.0054321, abs=1e-7)
    assert out[129026][0]["cog"] == pytest.approx(STATE.course_over_ground, abs=1e-4)
    assert out[129026][0]["sog"] == pytest.approx(STATE.speed_over_ground, abs=0.01)


def test_output_rates_are_kept(can_hub):
    hub, peer = can_hub
    t0 = time.monotonic()
    for k in range(21):  # 2 s of 20 Hz ticks on a simulated clock
        tick(hub, STATE, t0 + 0.1 * k)
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
        cfg = node_config([{"type": "can", "name": "slcan", "interface": "slcan", "channel": node_end,
                            "allowed_sources": [0x42]}],
                          rudder=["slcan"], engine=["slcan"])
        hub = LinkHub(cfg.links, cfg.arbitration)
        hub.open()
        console = can.Bus(interface="slcan", channel=console_end, bitrate=250000)
        try:
            console.send(console_frame("HelmOrder", RudderOrder=7.5, Status=1, Counter=2))
            got = []
            wait_for(lambda: got, poll=lambda: got.extend(
                [c for c in [tick(hub, STATE, time.monotonic()).controls.rudder] if c is not None]))
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


def test_a_far_end_that_does_not_read_never_holds_up_the_loop(tmp_path):
    """slcan over a pty pair whose console end nobody reads: python-can drains the port after
    every frame, which would wait for ever; the node's writer thread waits instead, and the
    loop's publishing goes on, the frames it cannot hand over counted as send_failed."""
    with pty_pair(tmp_path) as (node_end, _):
        cfg = node_config([{"type": "can", "name": "helm", "interface": "slcan", "channel": node_end,
                            "allowed_sources": [0x42]}])
        hub = LinkHub(cfg.links, cfg.arbitration)
        done = threading.Event()

        def publish_for_a_while() -> None:
            now = time.monotonic()
            while hub.links[0].health().errors["send_failed"] < 10:  # the writer's queue has filled up
                now += 0.1
                tick(hub, STATE, now)  # 7 to 8 frames a tick
                time.sleep(0.002)  # the pacer's wait, in which the writer thread runs
            done.set()
        with hub:
            publisher = threading.Thread(target=publish_for_a_while, daemon=True)
            publisher.start()
            publisher.join(60.0)
            assert done.is_set(), "the loop's publish is stuck in a write"
            assert hub.links[0].health().outputs > 256  # the pty's buffers filled, then the queue


def test_a_silent_serial_line_never_holds_up_the_poll(tmp_path):
    """python-can's 'serial' adapter waits for its port's timeout (100 ms by default) in every
    receive, even one asked not to wait. The node receives on a reader thread: the loop's
    ticks never call the bus's receive themselves (python-can's own bus, its calls noted by
    thread), its reader does, and an order sent after them still comes in, and the node's
    frames go out on the line (their timestamps as the line's 32-bit milliseconds)."""
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = node_config([{"type": "can", "name": "line", "interface": "serial", "channel": node_end,
                            "allowed_sources": [0x42]}], rudder=["line"], engine=["line"])
        hub = LinkHub(cfg.links, cfg.arbitration)
        open_hub(hub)
        console = can.Bus(interface="serial", channel=console_end)
        try:
            assert hub.links[0].health().connected
            bus, receivers = hub.links[0].device.bus, set()
            receive = bus.recv

            def noted_recv(*args, **kwargs):
                receivers.add(threading.current_thread().name)
                return receive(*args, **kwargs)
            bus.recv = noted_recv
            for _ in range(20):
                tick(hub, STATE, time.monotonic())
            wait_for(lambda: receivers)  # the reader's receive in hand when noted_recv came ends
            assert threading.current_thread().name not in receivers
            assert receivers == {"can-read-line"}
            console.send(console_frame("HelmOrder", RudderOrder=-4.0, Status=1, Counter=1))
            got = []
            wait_for(lambda: got, poll=lambda: got.extend(
                [c for c in [tick(hub, STATE, time.monotonic()).controls.rudder] if c is not None]))
            assert got[0] == pytest.approx(math.radians(-4.0))
            heard = [m for m in iter(lambda: console.recv(timeout=0.5), None)]
            assert heard and all(m.is_extended_id for m in heard)
            assert hub.links[0].health().reconnects == 0
        finally:
            console.shutdown()
            hub.close()
