import os
import sys
import time
from pathlib import Path

import pytest
from hypothesis import settings as hypothesis_settings

from bridge_node.common.errors import UserError
from bridge_node.node.config import NodeConfig, load_config
from bridge_node.common.network import free_port
from sim_core.fracture.tile_template import FractureSettings, build_tile

# The suite draws the same property-test examples every run (a red CI names a bug, not a
# dice roll); ICEBRIDGE_HYPOTHESIS=explore draws new ones each run to look for more.
hypothesis_settings.register_profile("suite", derandomize=True)
hypothesis_settings.register_profile("explore", derandomize=False)
hypothesis_settings.load_profile(os.environ.get("ICEBRIDGE_HYPOTHESIS", "suite"))

REPO = Path(__file__).resolve().parent.parent


def fuzz_budget(suite: int) -> int:
    """Inputs a fuzz test draws: ``suite`` in the suite's run, or ``ICEBRIDGE_FUZZ_EXAMPLES``
    for a hunt (issue 30 asks for 20 000 a parser:
    ``ICEBRIDGE_FUZZ_EXAMPLES=20000 ICEBRIDGE_HYPOTHESIS=explore pytest tests/test_parser_fuzz.py
    tests/test_replay_fuzz.py tests/test_links_bad_input.py tests/test_links_dis.py
    tests/test_hardening.py``)."""
    return int(os.environ.get("ICEBRIDGE_FUZZ_EXAMPLES", suite))


@pytest.fixture(scope="session")
def prism_tile():
    return build_tile(1.0, seed=7, settings=FractureSettings(cells="prism"))


@pytest.fixture(scope="session")
def voronoi3d_tile():
    # a 40 m tile keeps the per-cell Qhull loop short; counts scale by area (~137..242 cells)
    return build_tile(1.0, seed=7, settings=FractureSettings(cells="voronoi3d", tile_side=40.0))


def until_answered(what, timeout: float = 60.0, poll: float = 0.2, node=None):
    """Call ``what()`` every ``poll`` s until it returns something true, and return that; a
    UserError (a node not answering yet) counts as nothing. AssertionError after ``timeout``
    s, or at once when ``node`` (its process) has exited."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            got = what()
        except UserError:
            got = None
        if got:
            return got
        assert node is None or node.poll() is None, node.communicate()[1]
        time.sleep(poll)
    raise AssertionError("timed out")


def run_cli(*args, cwd=None):
    """Run the installed CLI in a subprocess, as a user would."""
    import subprocess

    return subprocess.run(
        [sys.executable, "-m", "bridge_node", *args], capture_output=True, text=True,
        cwd=cwd or REPO, timeout=300,
    )


def exercise_config(cache_dir: Path, width: float, height: float, tile_side: float = 100.0,
                    start_north: float | None = None, **scene) -> NodeConfig:
    """The default config on a small field (m) with its own template cache; optionally the
    ship's start (m north of the field) and scene settings."""
    base = load_config()
    return base.model_copy(update={
        "fracture": base.fracture.model_copy(update={"tile_side": tile_side}),
        "ice_field": base.ice_field.model_copy(update={"width": width, "height": height}),
        "scene": base.scene.model_copy(update=scene),
        "paths": base.paths.model_copy(update={"cache_dir": str(cache_dir)}),
        "exercise": base.exercise.model_copy(update={"start_north": start_north}),
    })


def region_world(cache_dir: Path, width: float, height: float, regions: list[dict], start_north: float):
    """The world (model, data at the start) of ``exercise_config`` with 100 m tiles and these
    ``[[ice_field.regions]]`` (as TOML tables)."""
    from bridge_node.node.world_setup import build_world, start_world
    from sim_core.regimes.settings import RegionSettings
    cfg = exercise_config(cache_dir, width, height, 100.0, start_north=start_north)
    field = cfg.ice_field.model_copy(update={"regions": [RegionSettings.model_validate(r) for r in regions]})
    cfg = cfg.model_copy(update={"ice_field": field})
    model = build_world(cfg, None)
    return model, start_world(model, cfg)


def exercise_toml(folder: Path, channels: str = "", **sections: str) -> Path:
    """A config file for CLI runs: a 400 m x 400 m field of 0.3 m ice, the ship's bow in the
    ice, its own template cache and session folder, a state stream and a control endpoint on
    free loopback ports, and the given ``[[render.channels]]`` text and extra sections
    (name -> TOML body; a ``control`` one replaces the default's)."""
    sections = {"control": f'endpoint = "tcp://127.0.0.1:{free_port()}"'} | sections
    text = ('[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 400.0\nthickness = 0.3\n'
            '[exercise]\nstart_north = -60.0\n'
            f'[paths]\ncache_dir = "{folder / "tiles"}"\nsession_dir = "{folder / "sessions"}"\n'
            f'[stream]\npublish = "tcp://127.0.0.1:{free_port()}"\nsnapshot = "tcp://127.0.0.1:{free_port()}"\n'
            + channels + "".join(f"[{name}]\n{body}\n" for name, body in sections.items()))
    path = folder / "exercise.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def ctx():
    """A headless OpenGL context (EGL; Mesa's llvmpipe here) for the render tests."""
    from bridge_node.render.channels import create_context
    return create_context()


@pytest.fixture(scope="module")
def exercise(tmp_path_factory):
    """The render tests' world: a 400 m x 600 m field of 0.5 m ice, B = 50 m; the ship has
    steamed 70 s into it. (Modules with a world of their own define their own.)"""
    from bridge_node.node.world_setup import build_world, start_world
    from sim_core.world import step
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "tiles", 400.0, 600.0, 50.0, start_north=-60.0)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(700):
        step(model, data, 0.1)
    return model, data
