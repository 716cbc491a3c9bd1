"""Channel windows through glfw on a real X server (Xvfb, a virtual display on this
headless machine): the window shows what the channel rendered. The rendering runs in its
own process (``window_probe.py``): Mesa cannot hold the GLX context of the windows and the
EGL context of the other render tests in one process."""
import json
import os
import shutil
import subprocess
import sys
import time

import pytest
from conftest import REPO, exercise_toml

HERE = os.path.dirname(__file__)


@pytest.fixture(scope="module")
def display():
    """An X display with one 1280x1024 monitor."""
    if shutil.which("Xvfb") is None:
        raise RuntimeError("Xvfb is missing: run scripts/setup.sh, which installs it")
    number = 90 + os.getpid() % 500
    proc = subprocess.Popen(["Xvfb", f":{number}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 10.0
    while not os.path.exists(f"/tmp/.X11-unix/X{number}"):
        assert proc.poll() is None and time.monotonic() < deadline, "Xvfb did not start"
        time.sleep(0.05)
    yield f":{number}"
    proc.terminate()
    proc.wait(5.0)


def test_window_shows_the_channel_and_missing_monitors_are_errors(display, tmp_path):
    r = subprocess.run([sys.executable, os.path.join(HERE, "window_probe.py"), str(tmp_path / "tiles")],
                       capture_output=True, text=True, cwd=REPO, env=os.environ | {"DISPLAY": display}, timeout=300)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["windows"] == 1  # only the window channel gets a window
    assert out["shape"] == out["rendered_shape"] == [90, 160, 3]
    assert out["max_diff"] <= 2  # the window shows the channel's pixels
    assert out["rendered_std"] > 10  # and they are a real picture: sky, ice, the bow
    assert "monitor 3 does not exist (1 monitor(s)" in out["missing_monitor_error"]


def test_window_output_without_a_display_is_a_clear_error(tmp_path):
    cfg = tmp_path / "window.toml"
    cfg.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
                   '[[render.channels]]\nname = "bow"\noutput = "window"\n')
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    r = subprocess.run([sys.executable, "-m", "bridge_node", "render-snapshot", "--config", str(cfg), "--time", "0",
                        "--out", str(tmp_path)], capture_output=True, text=True, cwd=REPO, env=env, timeout=300)
    assert r.returncode == 2 and "no display" in r.stderr and "Traceback" not in r.stderr


def test_run_with_a_display_shows_the_window_channels(display, tmp_path):
    """The main job on a display: its render process opens the window channel and draws it
    from the state stream (no video or panorama: those are for headless runs)."""
    cfg = exercise_toml(tmp_path, '[[render.channels]]\nname = "bow"\nwidth = 160\nheight = 90\noutput = "window"\n')
    r = subprocess.run([sys.executable, "-m", "bridge_node", "run", "--config", str(cfg), "--duration", "4", "--json",
                        "--no-record", "--out", str(tmp_path)], capture_output=True, text=True, cwd=REPO,
                       env=os.environ | {"DISPLAY": display}, timeout=300)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    proc, = out["render_processes"]
    assert proc["exit"] == 0 and proc["restarts"] == 0 and proc["frames"] > 0 and proc["channels"] == ["bow"]
    assert out["video"] == [] and out["panorama"] == []
