"""The ready exercises of ``config/exercises/`` (issue 26, item 6): each one loads, and runs
with ``icebridge run --config`` as its header says, its console's expectations met; the
pack exercise's field drifts in its wind."""
import json
import math

import pytest
from conftest import REPO, run_cli

from bridge_node.node.config import load_config

EXERCISES = sorted((REPO / "config" / "exercises").glob("*.toml"))


def test_there_are_exercises():
    assert EXERCISES


@pytest.mark.parametrize("path", EXERCISES, ids=[p.stem for p in EXERCISES])
def test_an_exercise_runs(path, tmp_path):
    cfg = load_config(path)
    assert cfg.ice_field.regions or cfg.ice_field.chart
    done = run_cli("run", "--config", str(path), "--duration", "20", "--render", "none", "--no-record", "--json",
                   "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr[-2000:]
    summary = json.loads(done.stdout)
    assert summary["ticks"] > 0 and summary["console"]["passed"], summary["console"]
    east, north = summary["ice_drift_m"]
    if cfg.ice_dynamics.field_drift and cfg.exercise.wind_speed_kn > 0.0:  # the pack: its wind drives it downwind
        downwind = math.radians(cfg.exercise.wind_from_deg + 180.0)
        assert east * math.sin(downwind) + north * math.cos(downwind) > 0.5
    else:
        assert east == north == 0.0
