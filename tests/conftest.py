import sys
from pathlib import Path

import pytest

from sim_core.fracture.tile_template import FractureSettings, build_tile

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def prism_tile():
    return build_tile(1.0, seed=7, settings=FractureSettings(cells="prism"))


@pytest.fixture(scope="session")
def voronoi3d_tile():
    # a 40 m tile keeps the per-cell Qhull loop short; counts scale by area (~137..242 cells)
    return build_tile(1.0, seed=7, settings=FractureSettings(cells="voronoi3d", tile_side=40.0))


def run_cli(*args, cwd=None):
    """Run the installed CLI in a subprocess, as a user would."""
    import subprocess

    return subprocess.run(
        [sys.executable, "-m", "bridge_node", *args], capture_output=True, text=True,
        cwd=cwd or REPO, timeout=300,
    )
