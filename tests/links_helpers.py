"""Shared pieces of the link tests: a ship state, console frames, pty pairs from socat,
configs, a paced console writer, and hub ticks."""
from __future__ import annotations

import math
import os
import shutil
import subprocess
import time
from contextlib import contextmanager
from pathlib import Path

import can
import cantools

from bridge_node.links.arbiter import Decision
from bridge_node.links.hub import LinkHub
from bridge_node.links.can.n2k_frames import identifier
from bridge_node.node.config import DEFAULT_CONFIG, NodeConfig
from sim_core.ship.outputs import ShipOutputs

CONSOLE = cantools.database.load_file(str(DEFAULT_CONFIG.parent / "console.dbc"))
STATE = ShipOutputs(time=10.0, north=100.0, east=50.0, latitude=math.radians(74.0012345),
                    longitude=math.radians(20.0054321), heading=math.radians(123.4),
                    course_over_ground=math.radians(125.0), speed_over_ground=4.321, speed_longitudinal=4.3,
                    speed_transverse=-0.2, rate_of_turn=math.radians(0.35), rudder_angle=math.radians(-12.3),
                    shaft_rps=1.234, ice_resistance=1.5e5, pitch=math.radians(0.4),
                    roll=math.radians(-2.5))


def console_frame(name: str, source: int = 0x42, **values) -> can.Message:
    """A console frame of the shipped console.dbc (HelmOrder or EngineOrder) with these signals."""
    spec = CONSOLE.get_message_by_name(name)
    pgn = {"HelmOrder": 0xFF50, "EngineOrder": 0xFF51}[name]
    return can.Message(arbitration_id=identifier(6, pgn, source), data=spec.encode(values), is_extended_id=True)


def rudder_order_pgn(angle_rad: float, source: int = 0x10) -> can.Message:
    """An NMEA 2000 helm's PGN 127245 carrying a rudder angle order, rad."""
    raw = int(round(angle_rad / 1e-4)) & 0xFFFF
    data = bytes([0, 0xF8 | (1 if angle_rad > 0 else 2), raw & 0xFF, raw >> 8, 0xFF, 0x7F, 0xFF, 0xFF])
    return can.Message(arbitration_id=identifier(2, 127245, source), data=data, is_extended_id=True)


def tick(hub: LinkHub, state: ShipOutputs, now: float) -> Decision:
    """One loop tick: poll (phase 1), then publish ``state`` with the poll's alarm changes (phase 2)."""
    decision = hub.poll(now)
    hub.publish(state, now, decision.alarms)
    return decision


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


@contextmanager
def bare_pty():
    """One kernel pseudo-terminal with no relay: (the path of its serial end, for the node;
    the file descriptor of its other end, for the console). Unlike socat's pair, nothing in
    between can stall: socat blocks writing to an end that is never read, and then stops
    passing the other way too."""
    console, node = os.openpty()
    try:
        yield os.ttyname(node), console
    finally:
        os.close(node)
        os.close(console)


def open_hub(hub: LinkHub) -> LinkHub:
    """Open the hub and wait until every link's device is open or has failed. The hub waits
    5 s at most; a loaded machine may take longer, and what a console writes before its
    port opens is lost (pyserial flushes a port's input as it opens it)."""
    hub.open()
    for link in hub.links:
        link.await_open(None)
    return hub


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


def wait_for(predicate, timeout: float = 15.0, poll=None):
    """Call poll() (if given) until predicate() holds; returns the time it took, s. The
    timeout only ends a test that would otherwise hang: it is not a time window the
    condition must meet (a loaded machine has taken over 3 s)."""
    t0 = time.monotonic()
    while not predicate():
        if time.monotonic() - t0 > timeout:
            raise AssertionError("condition not met in time")
        if poll:
            poll()
        time.sleep(0.005)
    return time.monotonic() - t0


def order_collector(hub: LinkHub, state: ShipOutputs):
    """(orders seen so far by kind, a function ticking the hub once and adding its orders)."""
    got = {}

    def tick_once() -> None:
        controls = tick(hub, state, time.monotonic()).controls
        got.update({k: v for k, v in vars(controls).items() if v is not None})
    return got, tick_once
