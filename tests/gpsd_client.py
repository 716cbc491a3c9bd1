"""A real gpsd (Debian's package; ``scripts/setup.sh`` installs it) reading the node's NMEA
UDP output on the loopback, and the JSON reports it gives its clients."""
from __future__ import annotations

import json
import shutil
import socket
import subprocess
import time
from collections.abc import Callable
from contextlib import contextmanager
from pathlib import Path

from conftest import free_port


def gpsd_version() -> tuple[int, ...]:
    """The installed gpsd's version, as (3, 22)."""
    text = subprocess.run(["gpsd", "-V"], capture_output=True, text=True).stdout.split()[1]
    return tuple(int(x) for x in text.split(".")[:2])


@contextmanager
def gpsd(folder: Path):
    """A gpsd listening for NMEA on a free UDP port: yields (that port, a function that
    collects its JSON reports while calling ``step`` for ``seconds``)."""
    if shutil.which("gpsd") is None:
        raise RuntimeError("gpsd is missing: run scripts/setup.sh, which installs it")
    udp_port, gpsd_port = free_port(), free_port()
    proc = subprocess.Popen(["gpsd", "-N", "-n", "-b", "-S", str(gpsd_port), "-F", str(folder / "gpsd.sock"),
                             f"udp://127.0.0.1:{udp_port}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 10.0
        while True:
            try:
                client = socket.create_connection(("127.0.0.1", gpsd_port))
                break
            except ConnectionRefusedError:
                assert time.monotonic() < deadline, "gpsd did not start"
                time.sleep(0.05)
        client.sendall(b'?WATCH={"enable":true,"json":true,"scaled":true};\n')
        client.settimeout(0.05)

        def collect(step: Callable[[], None], seconds: float, until: Callable[[list], bool]) -> list[dict]:
            """Reports until ``until(reports)`` holds or ``seconds`` pass."""
            text, reports, t0 = b"", [], time.monotonic()
            while time.monotonic() - t0 < seconds and not until(reports):
                step()
                try:
                    text += client.recv(65536)
                except socket.timeout:
                    pass
                *lines, rest = text.split(b"\n")
                text = rest
                reports += [json.loads(line) for line in lines if line.startswith(b"{")]
            return reports
        yield udp_port, collect
        client.close()
    finally:
        proc.terminate()
        proc.wait(5.0)
