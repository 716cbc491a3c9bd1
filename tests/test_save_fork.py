"""Save points, rewind and fork: a save point taken in a commanded run is reached again by
re-simulating the run's record, and the run's own continuation from there is the saved
run's, step for step; a forked run keeps the point in its record, so that its replay
starts where it forked; a record that does not reach the saved state is a clean error."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, exercise_config, exercise_toml, run_cli, until_answered

from bridge_node.control.client import request
from bridge_node.control.commands import parse_command
from bridge_node.control.queue import CommandQueue
from bridge_node.control.save_point import FORK_FILE, SAVES_FOLDER, read_save
from bridge_node.links.hub import LinkHub
from bridge_node.common.errors import UserError
from bridge_node.common.network import free_port
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.exercise.tick import ExerciseTick
from bridge_node.replay.engine import StepOrders
from bridge_node.node.fork import resimulate
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.session import SessionSource

RATE = 30.0
SCRIPT = [
    (0.5, {"command": "wind", "speed_kn": 25.0, "from_deg": 60.0}),
    (1.0, {"command": "steering_failure", "pumps_failed": 1}),
    (1.5, {"command": "reposition", "north_m": 200.0, "east_m": 250.0, "heading_deg": 20.0, "speed_kn": 5.0}),
    (2.5, {"command": "save", "name": "mid"}),
    (3.0, {"command": "sensor_failure", "sensor": "gyro", "mode": "offset", "offset_deg": 5.0}),
    (3.5, {"command": "current", "speed_kn": 1.0, "to_deg": 270.0}),
]


def _instructor(queue: CommandQueue):
    script = list(SCRIPT)

    def put(outcome) -> None:
        while script and outcome.events.time >= script[0][0] - 1e-9:
            assert queue.put(parse_command(script.pop(0)[1]))
    return put


def _state(data) -> tuple:
    return data.time, data.seq, data.ship.eta.copy(), data.ship.nu.copy(), data.ice.state.status.copy()


def _same(a: tuple, b: tuple) -> None:
    assert a[0] == pytest.approx(b[0]) and a[1] == b[1]
    np.testing.assert_allclose(a[2], b[2], rtol=0.0, atol=1e-6)
    np.testing.assert_allclose(a[3], b[3], rtol=0.0, atol=1e-6)
    np.testing.assert_array_equal(a[4], b[4])


def test_a_save_point_is_reached_again_and_its_continuation_is_the_saved_runs(tmp_path):
    cfg = exercise_config(tmp_path / "tiles", 600.0, 600.0, start_north=-60.0)
    model = build_world(cfg, None)
    live = start_world(model, cfg)
    record = tmp_path / "session"
    queue = CommandQueue()
    at_save = []
    with LinkHub(cfg.links, cfg.arbitration, record) as hub:
        run_realtime(model, live, hub, RATE, None,
                     [_instructor(queue), lambda o: at_save.extend([_state(live)] * bool(o.saves))],
                     should_stop=lambda: live.time >= 5.0 - 1e-9 and live.moving_to is None or live.time > 60.0,
                     commands=queue)
    point = read_save(record / SAVES_FOLDER / "mid.json")
    assert point.seq == at_save[0][1] and point.record == str(record.resolve())

    fork = start_world(model, cfg)
    resimulate(model, fork, cfg, point)
    _same(_state(fork), at_save[0])  # the saved state, from the record alone

    session = load_inputs([str(record)], None, {}, 1.0 / RATE)
    with SessionSource(cfg.links, cfg.arbitration, session) as source:  # the saved run's own continuation, from the fork on
        orders = StepOrders(source)
        orders.k = next(k for k, t in enumerate(session.ticks) if t.seq == point.seq)
        tick = ExerciseTick(model, fork, orders, (), orders)
        while orders.k < source.steps:
            tick(source.dt, orders.clock(), send=False)
    _same(_state(fork), _state(live))
    assert fork.sensors == live.sensors and fork.environment == live.environment

    point_text = (record / SAVES_FOLDER / "mid.json").read_text()
    wrong = tmp_path / "wrong.json"
    wrong.write_text(point_text.replace('"north": ', '"north": 1.0 + '))
    with pytest.raises(UserError, match="not an IceBridge save point"):
        read_save(wrong)
    changed = json.loads(point_text)
    changed["state"]["north"] += 1.0
    wrong.write_text(json.dumps(changed))
    with pytest.raises(UserError, match="does not reach the state saved"):
        resimulate(model, start_world(model, cfg), cfg, read_save(wrong))


def _run(config, out, *extra: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "bridge_node", "run", "--config", str(config), "--render", "none",
                             "--json", "--out", str(out), *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=REPO)


def test_a_forked_run_replays_from_where_it_forked(tmp_path):
    """``icebridge run --fork SAVE`` re-simulates to the save point and goes on live; its
    record names the point, and ``icebridge replay`` of it ends where the forked run ended."""
    endpoint = f"tcp://127.0.0.1:{free_port()}"
    config = exercise_toml(tmp_path, control=f'endpoint = "{endpoint}"')
    first = _run(config, tmp_path / "out1", "--duration", "6")
    # asked until the node answers: once its exercise is loaded (its own tile cache, built
    # cold: seconds, more on a loaded machine)
    until_answered(lambda: request(endpoint, {"request": "status"}, None, 10.0)["status"]["seq"] >= 60, 120.0,
                   node=first)
    reply = request(endpoint, {"command": {"command": "save", "name": "early"}}, None, 5.0)
    again = request(endpoint, {"command": {"command": "save", "name": "early"}}, None, 5.0)
    fault = request(endpoint, {"command": {"command": "link_fault", "link": "nope", "fault": "drop"}}, None, 5.0)
    out, err = first.communicate(timeout=120)
    assert first.returncode == 0, err
    assert reply["ok"] and not again["ok"] and "exists already" in again["error"]
    assert not fault["ok"] and "no such link" in fault["error"]
    point = read_save(Path(reply["path"]))
    assert point.record == json.loads(out)["record"] and point.seq >= 60

    forked = _run(config, tmp_path / "out2", "--duration", "3", "--fork", reply["path"])
    out, err = forked.communicate(timeout=120)
    assert forked.returncode == 0, err
    summary = json.loads(out)
    assert summary["forked_from"] == {"record": point.record, "step": point.seq}
    record = Path(summary["record"])
    assert read_save(record / FORK_FILE) == point

    replay = run_cli("replay", str(record), "--config", str(config), "--max", "--render", "none", "--json",
                     "--out", str(tmp_path / "out3"))
    assert replay.returncode == 0, replay.stderr
    rows = (tmp_path / "out3" / "replay_track.csv").read_text().splitlines()
    last = dict(zip(rows[0].split(","), rows[-1].split(",")))
    north, east = float(last["north_m"]), float(last["east_m"])
    assert abs(north - summary["north_m"]) <= 0.06 and abs(east - summary["east_m"]) <= 0.06
