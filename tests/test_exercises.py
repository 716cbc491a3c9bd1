"""The ready exercises of ``config/exercises/`` (issue 26, item 6): each one loads, and runs
with ``icebridge run --config`` as its header says, its console's expectations met."""
import json

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
