"""A run commanded by an instructor, replayed from its session record: the commands are
recorded with the steps they were applied at, and the replay applies them there, so it
ends in the live run's final state."""
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.exercise.command_log import COMMANDS_FILE, read_commands
from bridge_node.control.commands import parse_command
from bridge_node.control.queue import CommandQueue
from bridge_node.links.hub import LinkHub
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.replay.engine import Playback, run_replay
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.session import RecordedSession, SessionSource
from sim_core.instructor import Freeze, Reposition

RATE = 30.0
SCRIPT = [  # (simulated time s at which the instructor sends it, command)
    (0.5, {"command": "wind", "speed_kn": 30.0, "from_deg": 90.0}),
    (1.0, {"command": "steering_failure", "pumps_failed": 1}),
    (1.5, {"command": "freeze"}),
    (1.5, {"command": "current", "speed_kn": 1.5, "to_deg": 200.0}),
    (1.5, {"command": "resume"}),  # (three in one tick: freeze, current, resume)
    (2.0, {"command": "reposition", "north_m": 300.0, "east_m": 250.0, "heading_deg": 30.0, "speed_kn": 5.0}),
    (3.0, {"command": "visibility", "visibility_m": 400.0}),
    (3.0, {"command": "add_vessel", "mmsi": 230000001, "name": "ODEN", "length_m": 108.0, "beam_m": 31.0,
           "north_m": 400.0, "east_m": 300.0, "course_deg": 200.0, "speed_kn": 9.0}),
    (4.0, {"command": "steer_vessel", "mmsi": 230000001, "course_deg": 90.0, "speed_kn": 3.0}),
    (4.5, {"command": "set_ice", "ice": "open water", "polygon_m": [[0.0, 500.0], [600.0, 500.0], [600.0, 600.0],
                                                                  [0.0, 600.0]]}),
]


class _Instructor:
    """Puts each scripted command in the queue once the world's clock reaches its time
    (a listener: the tick after that applies it)."""

    def __init__(self, queue: CommandQueue) -> None:
        self.queue, self.script = queue, list(SCRIPT)

    def __call__(self, outcome) -> None:
        while self.script and outcome.events.time >= self.script[0][0] - 1e-9:
            assert self.queue.put(parse_command(self.script.pop(0)[1]))


def test_a_replay_of_a_commanded_run_ends_in_its_final_state(tmp_path):
    cfg = exercise_config(tmp_path / "tiles", 600.0, 600.0, start_north=-60.0)
    model = build_world(cfg, None)
    live = start_world(model, cfg)
    record = tmp_path / "session"
    queue = CommandQueue()
    frozen_ticks = []
    with LinkHub(cfg.links, cfg.arbitration, record) as hub:
        run_realtime(model, live, hub, RATE, None,
                     [_Instructor(queue), lambda o: frozen_ticks.append(o.events.environment.frozen)],
                     should_stop=lambda: live.time >= 6.0 - 1e-9 and live.moving_to is None or live.time > 60.0,
                     commands=queue)  # (a move waits for its tiles, prepared a millisecond a step)
    logged, bad = read_commands(record / COMMANDS_FILE)
    applied = [c for step in sorted(logged) for c in logged[step]]
    assert not bad["malformed"] and len(applied) == len(SCRIPT)
    assert Freeze(True) in applied and any(isinstance(c, Reposition) and c.at_once for c in applied)
    assert sum(frozen_ticks) == 0  # frozen and resumed within one tick: no step was held
    assert live.ship.steering_pumps == 1 and live.environment.visibility == 400.0
    assert 300.0 < live.ship.eta[0] < 330.0  # moved, and on from there

    session = load_inputs([str(record)], None, {}, 1.0 / RATE)
    assert isinstance(session, RecordedSession) and session.exact
    again = start_world(model, cfg)
    with SessionSource(cfg.links, cfg.arbitration, session) as source:
        stats = run_replay(model, again, source, Playback(None), None, None)
    assert stats.steps == len(session.ticks) and again.time == pytest.approx(live.time)
    np.testing.assert_allclose(again.ship.eta, live.ship.eta, rtol=0.0, atol=1e-6)
    np.testing.assert_allclose(again.ship.nu, live.ship.nu, rtol=0.0, atol=1e-6)
    assert again.environment == live.environment and again.epoch == live.epoch
    assert again.vessels == live.vessels and live.vessels[230000001].course == pytest.approx(math.pi / 2)
    a, b = live.ice.state, again.ice.state
    np.testing.assert_array_equal(a.status, b.status)
    laid = np.flatnonzero(live.scene.tile_class != model.scene.tile_class)
    assert len(laid) >= 3 and np.array_equal(again.scene.tile_class, live.scene.tile_class)  # the same ice laid
    assert math.hypot(*(again.ship.eta[:2] - live.ship.eta[:2])) < 1e-6
