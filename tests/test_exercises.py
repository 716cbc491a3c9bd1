"""The ready exercises of ``config/exercises/`` (issue 26, item 6): each one loads, and runs
with ``icebridge run --config`` as its header says, its console's expectations met; the
pack exercise's field drifts in its wind."""
import json
import math
import subprocess
import sys

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


_KERNELS_LOADED_BY_STEPS = """
import sys
from numba.core.registry import CPUDispatcher
from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world, warm_up
from sim_core.world import step
from sim_core.fleet import Controls

def signatures():
    return {f"{name}.{k}": len(v.signatures) for name, module in list(sys.modules.items())
            if name.startswith(("sim_core", "bridge_node")) for k, v in vars(module).items()
            if isinstance(v, CPUDispatcher)}

cfg = load_config(sys.argv[1])
model = build_world(cfg, sys.argv[1])
data = start_world(model, cfg, sys.argv[1])
warm_up(model, cfg)
before = signatures()
for _ in range(120):
    step(model, data, 1 / 60, Controls(telegraph="half_ahead"))
after = signatures()
print(len(after), {k: n for k, n in after.items() if n != before.get(k)})
"""


def test_after_the_warm_up_no_step_of_the_pack_exercise_loads_a_kernel():
    """The node warms every compiled kernel up before its first tick, so that no tick waits
    for numba to compile or load one (a second and a half, with an empty cache). In a fresh
    interpreter, two seconds of the pack exercise (the ship starts among wide floes, which
    break and part) add no signature to any kernel of the node. A wide floe's parts were
    warmed up with the wrong cell type (int64, the rows hold int32): its first part loaded
    a kernel in the first tick."""
    done = subprocess.run([sys.executable, "-c", _KERNELS_LOADED_BY_STEPS,
                           str(REPO / "config" / "exercises" / "pack_ice.toml")],
                          capture_output=True, text=True, timeout=600, cwd=REPO)
    assert done.returncode == 0, done.stderr[-2000:]
    kernels, loaded = done.stdout.split(" ", 1)
    assert int(kernels) > 40 and loaded.strip() == "{}", done.stdout
