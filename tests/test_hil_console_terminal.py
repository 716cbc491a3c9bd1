"""``icebridge console`` steered from the keyboard in a real terminal (a pty), against a
peer on a pty pair that plays the node: it sends RSA and reads the console's orders."""
import os
import pty
import select
import subprocess
import sys
import time

import pynmea2
import serial
from conftest import REPO

from bridge_node.hil.bench import PtyPair

RSA = (str(pynmea2.RSA("II", "RSA", ("-3.5", "A", "", "V"))) + "\r\n").encode()


def exchange(node: serial.Serial, terminal: int, seconds: float) -> tuple[bytes, bytes]:
    """Play the node for ``seconds``: send RSA at 20 Hz; what came on the line and the screen."""
    heard = screen = b""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        node.write(RSA)
        heard += node.read(4096)
        while select.select([terminal], [], [], 0)[0]:
            try:
                screen += os.read(terminal, 65536)
            except OSError:  # the console has exited
                return heard, screen
        time.sleep(0.05)
    return heard, screen


def exchange_until(node: serial.Serial, terminal: int, done, timeout: float = 30.0) -> tuple[bytes, bytes]:
    """Play the node until ``done(heard, screen)`` holds for what came since the call (or
    ``timeout`` s pass): the console acts on a key within its next loop, but a loaded
    machine may hold it back, so a phase is measured from when its effect shows, not from
    the key."""
    heard = screen = b""
    end = time.monotonic() + timeout
    while not done(heard, screen) and time.monotonic() < end:
        got = exchange(node, terminal, 0.1)
        heard, screen = heard + got[0], screen + got[1]
    return heard, screen


def started(node: serial.Serial, terminal: int, proc: subprocess.Popen) -> tuple[bytes, bytes]:
    """Play the node until the console's first rudder order comes (or it exits, or a
    minute passes): its start imports the node's packages, seconds on a loaded machine
    (a fixed 4 s window failed once, under a full test run beside a busy loop)."""
    heard, screen = exchange_until(node, terminal, lambda h, _: b"$RCROR," in h or proc.poll() is not None, 60.0)
    got = exchange(node, terminal, 1.0)  # a second of orders after the first
    return heard + got[0], screen + got[1]


def test_keys_steer_and_the_echo_shows(tmp_path):
    with PtyPair(tmp_path, "nmea") as pair:
        cfg = tmp_path / "console.toml"
        cfg.write_text(f'[[links]]\nrole = "primary"\ntype = "nmea0183"\nport = "{pair.console_end}"\n')
        node = serial.Serial(str(pair.node_end), 38400, timeout=0)
        terminal, slave = pty.openpty()
        proc = subprocess.Popen([sys.executable, "-m", "bridge_node", "console", "--config", str(cfg)], cwd=REPO,
                                stdin=slave, stdout=slave, stderr=slave, env=os.environ | {"COLUMNS": "200"})
        os.close(slave)
        try:
            heard, screen = started(node, terminal, proc)  # steering midships, stop
            assert b"$RCROR,0.0,A,,V,B" in heard, screen.decode(errors="replace")
            ten = b"$RCROR,10.0,A,,V,B"
            # each key, and what shows that the console has acted on it
            keys = [(b"d", lambda h, _: b"$RCROR,5.0,A,,V,B" in h), (b"d", lambda h, _: ten in h),
                    (b"w", lambda h, _: b"$RCETL,,O,01,,B,0" in h),
                    (b"x", lambda h, _: b"$RCROR,120.0" in h),  # corrupting: out of range
                    (b"x", lambda h, _: ten in h),  # and no longer
                    (b"u", lambda _, s: b"UNPLUGGED" in s), (b"u", lambda h, _: h.count(ten) >= 3),  # back
                    (b"g", lambda h, _: sum(b >= 0x80 for b in h) > 10)]  # a burst of garbage
            phases = {}
            for key, acted in keys:
                os.write(terminal, key)
                got = exchange_until(node, terminal, acted)
                after = exchange(node, terminal, 0.5)  # half a second from then on
                phases[len(phases)] = (got[0], after[0])
                heard, screen = heard + got[0] + after[0], screen + got[1] + after[1]
            os.write(terminal, b"q")
            proc.wait(10)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(5)
            node.close()
            os.close(terminal)
    assert proc.returncode == 0, screen.decode(errors="replace")
    assert b"$RCROR,10.0,A,,V,B" in heard  # two presses of d: 10 deg starboard
    assert b"$RCETL,,O,01,,B,0" in heard  # w from stop: dead slow ahead
    assert b"rudder -3.5 deg" in screen  # the echoed rudder angle
    # faults from the keys: x corrupts the orders (out of range), u unplugs the console (nothing
    # comes, then it is back), g sends a burst of garbage; each showed its effect
    assert all(acted(phases[k][0], screen) for k, (_, acted) in enumerate(keys))
    assert b"$RCROR,120.0,A,,V,B" in phases[3][0] and b"$RCROR,120.0" not in phases[4][1]
    assert phases[5][1].count(b"ROR") <= 1  # unplugged: none (one may have been on its way)
