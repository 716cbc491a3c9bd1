"""Shared pieces of the link tests: pty pairs from socat, configs, a paced console writer."""
from __future__ import annotations

import shutil
import subprocess
import time
from contextlib import contextmanager
from pathlib import Path

from bridge_node.config import NodeConfig


@contextmanager
def pty_pair(folder: Path):
    """Two linked pseudo-terminals (socat), yielded as their paths, as a null-modem cable."""
    if shutil.which("socat") is None:
        raise RuntimeError("socat is missing: run scripts/setup.sh, which installs it")
    a, b = folder / "ptyA", folder / "ptyB"
    proc = subprocess.Popen(["socat", f"pty,raw,echo=0,link={a}", f"pty,raw,echo=0,link={b}"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 5.0
        while not (a.exists() and b.exists()):
            if time.monotonic() > deadline:
                raise RuntimeError("socat did not create the pty pair")
            time.sleep(0.01)
        yield str(a), str(b)
    finally:
        proc.terminate()
        proc.wait(5.0)


def node_config(links: list[dict], **arbitration) -> NodeConfig:
    return NodeConfig.model_validate({"ship": {"name": "polar_cargo"}, "ice_field": {"thickness": 0.5},
                                      "links": links, "arbitration": arbitration})


def paced_write(port, lines: list[str], baud: int) -> None:
    """Write sentences as a real UART at this baud rate would deliver them (10 bits/char)."""
    for line in lines:
        data = (line + "\r\n").encode()
        port.write(data)
        port.flush()
        time.sleep(len(data) * 10 / baud)


def wait_for(predicate, timeout: float = 3.0, poll=None):
    """Call poll() (if given) until predicate() holds; returns the time it took, s."""
    t0 = time.monotonic()
    while not predicate():
        if time.monotonic() - t0 > timeout:
            raise AssertionError("condition not met in time")
        if poll:
            poll()
        time.sleep(0.005)
    return time.monotonic() - t0



def order_collector(hub, state):
    """(orders seen so far by kind, a function ticking the hub once and adding its orders)."""
    got = {}

    def tick() -> None:
        controls = hub.tick(state, time.monotonic()).controls
        got.update({k: v for k, v in vars(controls).items() if v is not None})
    return got, tick
