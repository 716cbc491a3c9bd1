"""Channel windows through glfw on a real X server (Xvfb, a virtual display on this
headless machine): the window shows what the channel rendered."""
import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

from bridge_node.render.channel_output import ChannelSet, context_for
from bridge_node.render.channel_windows import WindowError
from bridge_node.render.render_settings import ChannelSettings, RenderSettings
from bridge_node.render.scene_renderer import SceneRenderer
from conftest import REPO
from test_render import exercise  # noqa: F401  the shared exercise fixture


@pytest.fixture(scope="module")
def display():
    """An X display with one 1280x1024 monitor, for this process and its children."""
    if shutil.which("Xvfb") is None:
        raise RuntimeError("Xvfb is missing: run scripts/setup.sh, which installs it")
    number = 90 + os.getpid() % 500
    proc = subprocess.Popen(["Xvfb", f":{number}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 10.0
    while not os.path.exists(f"/tmp/.X11-unix/X{number}"):
        assert proc.poll() is None and time.monotonic() < deadline, "Xvfb did not start"
        time.sleep(0.05)
    old = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = f":{number}"
    yield f":{number}"
    import glfw

    glfw.terminate()
    if old is None:
        del os.environ["DISPLAY"]
    else:
        os.environ["DISPLAY"] = old
    proc.terminate()
    proc.wait(5.0)


def test_window_shows_the_channel(display, exercise):  # noqa: F811
    model, data = exercise
    channels = [ChannelSettings(name="bow", width=160, height=90, output="window", pitch_deg=-10.0,
                                blend_right_deg=5.0),
                ChannelSettings(name="stern", width=160, height=90, yaw_deg=180.0)]
    ctx, hidden = context_for(channels)
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=channels)), channels, hidden)
    cs.render(data)
    assert len(cs.windows) == 1  # only the window channel gets one
    shown, rendered = cs.windows[0].shown(), cs.targets[0].image()
    assert shown.shape == rendered.shape == (90, 160, 3)
    assert np.abs(shown.astype(int) - rendered.astype(int)).max() <= 2
    assert rendered.std() > 10  # a real picture: sky, ice, the bow


def test_window_on_a_missing_monitor_is_a_clear_error(display, exercise):  # noqa: F811
    model, _ = exercise
    channels = [ChannelSettings(name="wing", width=64, height=36, output="window", monitor=3)]
    ctx, hidden = context_for(channels)
    with pytest.raises(WindowError, match="monitor 3 does not exist"):
        ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=channels)), channels, hidden)


def test_window_output_without_a_display_is_a_clear_error(tmp_path):
    cfg = tmp_path / "window.toml"
    cfg.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
                   '[[render.channels]]\nname = "bow"\noutput = "window"\n')
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    r = subprocess.run([sys.executable, "-m", "bridge_node", "render-snapshot", "--config", str(cfg), "--time", "0",
                        "--out", str(tmp_path)], capture_output=True, text=True, cwd=REPO, env=env, timeout=300)
    assert r.returncode == 2 and "no display" in r.stderr and "Traceback" not in r.stderr

