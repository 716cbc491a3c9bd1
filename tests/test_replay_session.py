"""A recorded run re-simulated from its session record: consoles on a real pty pair (NMEA
0183 helm), a virtual CAN bus (telegraph) and Modbus TCP (lever) steer the ship through the
ice in real time; the record, replayed through the node's own link code, gives the same
track, the same broken cells and the same NMEA outputs."""
import math
import threading

import can
import numpy as np
import serial
from conftest import exercise_config
from links_helpers import console_frame, pty_pair
from modbus_console import ModbusConsole
from replay_logs import sentence

from bridge_node.links.hub import LinkHub
from bridge_node.links.record_reader import read_nmea_log
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.exercise.tick_record import TICKS_FILE, read_ticks
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.replay.engine import Playback, run_replay
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.session import RecordedSession, SessionSource
from sim_core.ice.floes import BreakCause

RATE = 30.0
TIME_FIELDS = {"RMC": (1, 9), "GGA": (1,), "ZDA": (1, 2, 3, 4), "ALR": (1,)}  # wall-clock fields, by sentence


def _config(tmp_path, port: str, modbus_port: int):
    base = exercise_config(tmp_path / "tiles", 300.0, 300.0, 50.0, start_north=-60.0)
    return type(base).model_validate(base.model_dump() | {
        "ice_field": base.ice_field.model_dump() | {"thickness": 0.3},
        "links": [{"type": "nmea0183", "name": "helm", "port": port, "udp_output": False},
                  {"type": "can", "name": "telegraph", "channel": "icebridge-replay-test", "allowed_sources": [0x42]},
                  {"type": "modbus", "name": "lever", "port": modbus_port, "poll_hz": 20,
                   "registers": [{"order": "lever", "address": 1}]}],
        "arbitration": {"rudder": ["helm"], "engine": ["telegraph", "lever"], "fail_safe": "hold"}})


def _wait(clock, at: float, stop: threading.Event) -> None:
    while clock() < at and not stop.is_set():
        stop.wait(0.005)


def _helm(port: str, stop: threading.Event, clock) -> None:
    """A helmsman on NMEA 0183: starboard 20, then 25, with noise on the line."""
    script = [(0.2, sentence("RCROR,20.0,A,,V,B")), (0.5, "garbage on the line"),
              (1.4, sentence("RCROR,35.0,A,,V,B")[:-2] + "00"), (2.2, sentence("RCROR,25.0,A,,V,B"))]
    with serial.Serial(port, 38400, timeout=0) as line:
        for at, text in script:
            _wait(clock, at, stop)
            line.write((text + "\r\n").encode())
        while not stop.is_set():  # the order source stays fresh
            line.write((sentence("RCROR,25.0,A,,V,B") + "\r\n").encode())
            stop.wait(0.3)


def _telegraph(stop: threading.Event, clock) -> None:
    """The engine telegraph on CAN from 1 s: half ahead, repeated; one frame of another source."""
    with can.Bus(interface="virtual", channel="icebridge-replay-test") as bus:
        _wait(clock, 1.0, stop)
        bus.send(console_frame("EngineOrder", source=0x43, Engine=0, Lever=0, TelegraphPosition=1, Mode=1))
        while not stop.is_set():
            bus.send(console_frame("EngineOrder", Engine=0, Lever=0, TelegraphPosition=3, Mode=1))
            stop.wait(0.3)


def _outputs(record: RecordedSession | None, path) -> list[str]:
    """The instrument sentences sent, without their wall-clock time fields."""
    out = []
    for r in read_nmea_log(path)[0]:
        if r.direction != "tx":
            continue
        fields = r.sentence.split("*")[0].split(",")
        for i in TIME_FIELDS.get(fields[0][3:], ()):
            fields[i] = ""
        out.append(",".join(fields))
    return out


def _live_session(tmp_path):
    """Four seconds of a live run under the consoles' scripted orders, recorded: the config,
    model, the world at the end, the record's folder, the links' errors and the order counts."""
    lever = ModbusConsole("tcp")
    lever.set(1, 40)  # lever 40 % ahead until the telegraph speaks
    lever.start()
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = _config(tmp_path, node_end, lever.port)
        model = build_world(cfg, None)
        live = start_world(model, cfg)
        record = tmp_path / "session"
        stop = threading.Event()
        consoles = [threading.Thread(target=_helm, args=(console_end, stop, lambda: live.time), daemon=True),
                    threading.Thread(target=_telegraph, args=(stop, lambda: live.time), daemon=True)]
        with LinkHub(cfg.links, cfg.arbitration, record) as hub:
            for c in consoles:
                c.start()
            try:
                run_realtime(model, live, hub, RATE, None, should_stop=lambda: live.time >= 4.0 - 1e-9)
            finally:
                stop.set()
                for c in consoles:
                    c.join(2.0)
                lever.stop()
            errors = {link.name: link.health().errors for link in hub.links}
            return cfg, model, live, record, errors, dict(hub.order_counts)


def test_a_recorded_session_replays_to_the_same_track_cells_and_outputs(tmp_path):
    cfg, model, live, record, errors, counts = _live_session(tmp_path)
    assert errors["helm"]["malformed"] >= 1 and errors["helm"]["bad_checksum"] == 1  # the noise, dropped
    assert errors["telegraph"]["source_not_allowed"] == 1
    assert counts["lever/lever/0"] > 0 and counts["telegraph/telegraph/0"] > 0

    session = load_inputs([str(record)], None, {}, 1.0 / RATE)
    assert isinstance(session, RecordedSession) and session.exact
    period, ticks, _ = read_ticks(record / TICKS_FILE)
    assert period == 1.0 / RATE and len(ticks) == len(session.ticks) == 120
    again = start_world(model, cfg)
    with SessionSource(cfg.links, cfg.arbitration, session) as source, LinkHub(cfg.links, cfg.arbitration, tmp_path / "replayed") as out:
        stats = run_replay(model, again, source, Playback(None), out, None)
    assert stats.steps == 120 and again.time == live.time
    assert {k: source.orders[k] for k in counts} == counts  # every order decoded again
    assert source.errors()["helm"]["bad_checksum"] == 1 and source.errors()["telegraph"]["source_not_allowed"] == 1

    # the same track: the ship turned under the recorded orders, and the replay follows it exactly
    assert math.degrees(live.ship.rudder) > 5.0 and live.ship.eta[5] > 1e-4 and live.ship.rps_order > 0.0
    np.testing.assert_allclose(again.ship.eta, live.ship.eta, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(again.ship.nu, live.ship.nu, rtol=0.0, atol=1e-9)
    # the same broken cells
    a, b = live.ice.state, again.ice.state
    assert a.n == b.n
    for cause in (BreakCause.HULL, BreakCause.CONTACT):
        np.testing.assert_array_equal(np.nonzero(b.cause == cause)[0], np.nonzero(a.cause == cause)[0])
    assert np.count_nonzero(a.cause == BreakCause.HULL) > 0
    # the same NMEA outputs, sentence for sentence
    sent, resent = _outputs(None, record / "nmea.log"), _outputs(None, tmp_path / "replayed" / "nmea.log")
    assert len(sent) > 100
    assert resent == sent

    # without its tick log (an older record) the session replays approximately: each input at
    # the tick its time falls in
    (record / TICKS_FILE).unlink()
    rough = load_inputs([str(record / "nmea.log"), str(record / "can.log"), str(record / "modbus.csv")], None, {},
                        1.0 / RATE)
    assert not rough.exact and abs(len(rough.ticks) - 120) <= 3
    third = start_world(model, cfg)
    with SessionSource(cfg.links, cfg.arbitration, rough) as source:
        run_replay(model, third, source, Playback(None), None, None)
    assert math.hypot(*(third.ship.eta[:2] - live.ship.eta[:2])) < 1.0
