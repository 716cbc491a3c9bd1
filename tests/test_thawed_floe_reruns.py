"""A turn back into thawed floes replays to the bit (issue 26: woken floes thaw as their
bodies, ``sim_core.ice.compound_thaw``). A save point is reached again by re-simulating the
run, so two runs of the same orders must be the same run: the ship steams a minute into
7/10 small and medium floes, is moved 1.5 km away until the tiles it woke floes in have
frozen, and back beside where it was, where they thaw as bodies again. Each run is a fresh
interpreter, as a re-simulation is, so the engine's objects lie elsewhere in memory.

Its floes' bodies once thawed with their cells' shapes put on the static body before it
turned dynamic: three runs gave three different fields, differing from the fourth step
after the thaw in the last bits. Put on the moving body, they are the same."""
import subprocess
import sys

from conftest import REPO

_FIELD = (REPO / "config" / "exercises" / "pack_ice.toml").read_text().replace(
    'ice = [{ stage = "thin_first_year", floe_size = "small_floe", concentration = 4 },\n'
    '       { stage = "grey_white", floe_size = "ice_cake", concentration = 3 }]',
    'ice = [{ stage = "thin_first_year", floe_size = "medium_floe", concentration = 3 },\n'
    '       { stage = "thin_first_year", floe_size = "small_floe", concentration = 4 }]')

_TURN_BACK = """
import hashlib, sys
from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world, warm_up
from sim_core.fleet import Controls
from sim_core.instructor import Reposition
from sim_core.world import step

cfg = load_config(sys.argv[1])
model = build_world(cfg, sys.argv[1])
data = start_world(model, cfg, sys.argv[1])
warm_up(model, cfg)

def steps(seconds, command=None):
    for i in range(round(seconds * 60)):
        step(model, data, 1 / 60, Controls(telegraph="half_ahead"), (command,) if command and i == 0 else ())

steps(60.0)
north, east = float(data.ships[0].eta[0]), float(data.ships[0].eta[1])
st = data.ice.state
woken = int(st.bonded.sum())
steps(20.0, Reposition(north=north + 1500.0, east=east, heading=0.0, speed=0.0, at_once=True))
frozen = int(data.ice.frozen.count)
steps(1.0, Reposition(north=north - 60.0, east=east, heading=0.0, speed=2.5, at_once=True))
print(hashlib.sha1(st.xy.tobytes() + st.status.tobytes() + st.bonded.tobytes()).hexdigest(), woken, frozen,
      int(st.bonded.sum()))
"""


def test_a_turn_back_into_thawed_floes_reruns_to_the_bit(tmp_path):
    assert "medium_floe" in _FIELD
    config = tmp_path / "medium_floes.toml"
    config.write_text(_FIELD)
    runs = []
    for _ in range(2):
        done = subprocess.run([sys.executable, "-c", _TURN_BACK, str(config)], capture_output=True, text=True,
                              timeout=600, cwd=REPO)
        assert done.returncode == 0, done.stderr[-2000:]
        runs.append(done.stdout.split())
    (digest, woken, frozen, bonded), again = runs
    assert int(woken) > 1000 and int(frozen) > 1000 and int(bonded) > 1000  # floes woke, froze and came back
    assert again == runs[0]
