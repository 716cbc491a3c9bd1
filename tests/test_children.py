"""A node killed outright (SIGKILL, as a crash) takes its children with it: the software
console, its socat pair, the render process and the state publisher end within seconds, and
the node's folders in /tmp are removed when the next node makes its own (issue 30, item 9)."""
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil
from conftest import REPO, exercise_toml

from bridge_node.common.children import private_folder

DEMO = REPO / "config" / "scenarios" / "demo_voyage.toml"
CHANNEL = '[[render.channels]]\nname = "bow"\nwidth = 64\nheight = 36\npitch_deg = -10.0\n'


def _children(pid: int) -> list[psutil.Process]:
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def _command_line(process: psutil.Process) -> str:
    """The process's command line, or "" once it has ended or is a zombie between polls."""
    try:
        return " ".join(process.cmdline())
    except psutil.Error:
        return ""


def test_a_killed_node_takes_its_children_and_leaves_no_folder_behind(tmp_path):
    cfg = exercise_toml(tmp_path, CHANNEL, console=f'script = "{DEMO}"\nlink = "can"')
    node = subprocess.Popen([sys.executable, "-m", "bridge_node", "run", "--config", str(cfg), "--duration", "300",
                             "--render", "local", "--out", str(tmp_path / "out")], cwd=REPO,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 180.0
        kinds = set()
        while kinds != {"socat", "console", "render-node", "publisher"} and time.monotonic() < deadline:
            time.sleep(0.5)
            kinds = set()
            for child in _children(node.pid):
                with_args = _command_line(child)
                kinds |= {k for k, word in (("socat", "socat"), ("console", " console "),
                                            ("render-node", " render-node "), ("publisher", "spawn_main"))
                          if word in f" {with_args} "}
        assert kinds == {"socat", "console", "render-node", "publisher"}, kinds
        children = _children(node.pid)
        folders = list(Path(tempfile.gettempdir()).glob(f"icebridge-*-{node.pid}-*"))
        assert {f.name.split("-")[1] for f in folders} == {"hil", "stream"}
    finally:
        node.send_signal(signal.SIGKILL)
        node.wait(10)
    _gone, alive = psutil.wait_procs(children, timeout=30)
    assert alive == [], [_command_line(p) for p in alive]
    fresh = private_folder("hil")  # the next node's folder: the dead one's go first
    shutil.rmtree(fresh)
    assert not any(f.exists() for f in folders if f.name.startswith("icebridge-hil-"))
    stream = [f for f in folders if f.name.startswith("icebridge-stream-")]
    shutil.rmtree(private_folder("stream"))
    assert not any(f.exists() for f in stream)
