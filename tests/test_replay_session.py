"""A recorded run re-simulated from its session record: a console on a real pty pair steers
the ship through the ice in real time; the record, replayed through the node's own link
code, gives the same track, the same broken cells and the same NMEA outputs."""
import math
import threading

import numpy as np
import serial
from conftest import exercise_config
from links_helpers import pty_pair
from replay_logs import sentence

from bridge_node.links.hub import LinkHub
from bridge_node.links.record_reader import read_nmea_log
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.tick_record import TICKS_FILE, read_ticks
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.replay.engine import Outputs, Playback, run_replay
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.session import RecordedSession, SessionSource
from sim_core.ice.floes import BreakCause

RATE = 30.0
TIME_FIELDS = {"RMC": (1, 9), "GGA": (1,), "ZDA": (1, 2, 3, 4), "ALR": (1,)}  # wall-clock fields, by sentence


def _config(tmp_path, port: str):
    base = exercise_config(tmp_path / "tiles", 300.0, 300.0, 50.0, start_north=-60.0)
    return type(base).model_validate(base.model_dump() | {
        "ice_field": base.ice_field.model_dump() | {"thickness": 0.3},
        "links": [{"type": "nmea0183", "name": "console", "port": port, "udp_output": False}],
        "arbitration": {"rudder": ["console"], "engine": ["console"], "fail_safe": "hold"}})


def _console(port: str, stop: threading.Event, clock) -> None:
    """A helmsman: starboard 20, half ahead, starboard 25, with noise on the line."""
    script = [(0.2, sentence("RCROR,20.0,A,,V,B")), (0.5, "garbage on the line"),
              (0.9, sentence("RCETL,120000.00,O,03,30,B,0")), (1.4, sentence("RCROR,35.0,A,,V,B")[:-2] + "00"),
              (2.2, sentence("RCROR,25.0,A,,V,B"))]
    with serial.Serial(port, 38400, timeout=0) as line:
        for at, text in script:
            while clock() < at and not stop.is_set():
                stop.wait(0.005)
            line.write((text + "\r\n").encode())
        while not stop.is_set():  # the order source stays fresh
            line.write((sentence("RCROR,25.0,A,,V,B") + "\r\n").encode())
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


def test_a_recorded_session_replays_to_the_same_track_cells_and_outputs(tmp_path):
    with pty_pair(tmp_path) as (node_end, console_end):
        cfg = _config(tmp_path, node_end)
        model = build_world(cfg, None)
        live = start_world(model, cfg)
        record = tmp_path / "session"
        stop = threading.Event()
        console = threading.Thread(target=_console, args=(console_end, stop, lambda: live.time), daemon=True)
        with LinkHub(cfg.links, cfg.arbitration, record) as hub:
            console.start()
            try:
                run_realtime(model, live, hub, RATE, None, should_stop=lambda: live.time >= 4.0 - 1e-9)
            finally:
                stop.set()
                console.join(2.0)
            errors = hub.links[0].health().errors
    assert errors["malformed"] >= 1 and errors["bad_checksum"] == 1  # the noise was read, and dropped

    session = load_inputs([str(record)], None, {}, 1.0 / RATE)
    assert isinstance(session, RecordedSession) and session.exact
    period, ticks, _ = read_ticks(record / TICKS_FILE)
    assert period == 1.0 / RATE and len(ticks) == len(session.ticks) == 120
    again = start_world(model, cfg)
    with SessionSource(cfg, session) as source, LinkHub(cfg.links, cfg.arbitration, tmp_path / "replayed") as out:
        stats = run_replay(model, again, source, Playback(None), Outputs(out, None))
    assert stats.steps == 120 and again.time == live.time
    assert source.orders["console/rudder/0"] >= 3 and source.orders["console/telegraph/0"] == 1
    assert source.errors()["console"]["bad_checksum"] == 1

    # the same track: the ship turned under the recorded orders, and the replay follows it exactly
    assert math.degrees(live.ship.rudder) > 5.0 and live.ship.eta[5] > 1e-4
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
