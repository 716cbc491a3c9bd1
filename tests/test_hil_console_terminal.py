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


def started(node: serial.Serial, terminal: int, proc: subprocess.Popen) -> tuple[bytes, bytes]:
    """Play the node until the console's first rudder order comes (or it exits, or a
    minute passes): its start imports the node's packages, seconds on a loaded machine
    (a fixed 4 s window failed once, under a full test run beside a busy loop)."""
    heard = screen = b""
    end = time.monotonic() + 60.0
    while b"$RCROR," not in heard and proc.poll() is None and time.monotonic() < end:
        got = exchange(node, terminal, 0.5)
        heard, screen = heard + got[0], screen + got[1]
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
            phases = {}
            for key in b"ddwxxuug":
                os.write(terminal, bytes([key]))
                got = exchange(node, terminal, 0.5)
                phases[len(phases)] = got[0]
                heard, screen = heard + got[0], screen + got[1]
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
    # comes, then it is back), g sends a burst of garbage
    assert b"$RCROR,120.0,A,,V,B" in phases[3] and b"$RCROR,120.0" not in phases[4][-200:]
    assert phases[5].count(b"ROR") <= 1 and phases[6].count(b"$RCROR,10.0,A,,V,B") >= 3  # 10 Hz for 0.5 s
    assert sum(b >= 0x80 for b in phases[7]) > 10 and b"UNPLUGGED" in screen
