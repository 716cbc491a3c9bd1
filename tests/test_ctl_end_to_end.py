"""``icebridge run`` commanded by ``icebridge ctl`` and by a control client, as an instructor
does it: separate processes, the console on a serial line, the instruments on UDP. Freeze
stops the exercise clock and resume restarts it; a reposition moves the ship in the NMEA
position; a steering failure holds the rudder angle the RSA sentences report."""
import json
import math
import socket
import subprocess
import sys
import time
import urllib.request

import psutil
import pynmea2
import pytest
from pyais import decode
import serial
from conftest import REPO, exercise_toml, run_cli, until_answered
from links_helpers import pty_pair

from bridge_node.control.client import request
from bridge_node.common.network import free_port


class _Instruments:
    """The NMEA sentences the node sends to UDP, parsed as they come."""

    def __init__(self) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.1)
        self.port = self.sock.getsockname()[1]
        self.last: dict[str, pynmea2.NMEASentence] = {}
        self.ais: list[str] = []  # !AIVDM sentences, as they came

    def read(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                for line in self.sock.recv(4096).decode().split():
                    if line.startswith("!AIVDM"):
                        self.ais.append(line)
                    if line.startswith("$"):
                        msg = pynmea2.parse(line)
                        self.last[msg.sentence_type] = msg
            except (socket.timeout, pynmea2.ParseError):
                pass


def _order(helm: serial.Serial, instruments: _Instruments, deg: float, until=None, seconds: float = 60.0) -> None:
    """The helm's rudder order, sent 10 times a second until ``until()`` holds (at most
    ``seconds``) or, without it, for ``seconds``; the outputs read meanwhile."""
    body = f"RCROR,{deg:.1f},A,,V,B"
    checksum = 0
    for c in body:
        checksum ^= ord(c)
    end = time.monotonic() + seconds
    while time.monotonic() < end and not (until and until()):
        helm.write(f"${body}*{checksum:02X}\r\n".encode())
        instruments.read(0.1)


def _steering_failure(endpoint: str, helm: serial.Serial, instruments: _Instruments) -> None:
    """A steering failure holds the rudder where it is, as the RSA sentences show; repaired,
    it follows the order again."""
    def rudder() -> float:
        return float(instruments.last["RSA"].rsa_starboard) if "RSA" in instruments.last else math.nan
    _order(helm, instruments, 6.0, lambda: abs(rudder() - 6.0) < 0.2)
    assert rudder() == pytest.approx(6.0, abs=0.2)
    assert request(endpoint, {"command": {"command": "steering_failure", "pumps_failed": 2}}, None)["ok"]
    _order(helm, instruments, -6.0, seconds=3.0)
    assert rudder() == pytest.approx(6.0, abs=0.2)  # stuck
    assert request(endpoint, {"command": {"command": "steering_failure", "pumps_failed": 0}}, None)["ok"]
    _order(helm, instruments, -6.0, lambda: abs(rudder() + 6.0) < 0.2)
    assert rudder() == pytest.approx(-6.0, abs=0.2)  # repaired


def test_freeze_reposition_and_steering_failure_from_the_command_line(tmp_path):
    instruments = _Instruments()
    endpoint = f"tcp://127.0.0.1:{free_port()}"
    with pty_pair(tmp_path) as (node_end, console_end):
        config = exercise_toml(tmp_path, "", control=f'endpoint = "{endpoint}"')
        config.write_text(config.read_text() +
                          f'[[links]]\nname = "console"\ntype = "nmea0183"\nport = "{node_end}"\nbaudrate = 38400\n'
                          f'udp_output = true\nudp_port = {instruments.port}\n'
                          '[links.ais]\nmmsi = 257000001\nto_bow = 20\nto_stern = 130\nto_port = 12\nto_starboard = 12\n'
                          '[arbitration]\nrudder = ["console"]\nengine = []\n')
        node = subprocess.Popen([sys.executable, "-m", "bridge_node", "run", "--config", str(config), "--duration",
                                 "120", "--render", "none", "--json", "--out", str(tmp_path / "out")], cwd=REPO,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        helm = serial.Serial(console_end, 38400, timeout=0)
        try:
            status = lambda: request(endpoint, {"request": "status"}, None, 1.0)["status"]  # noqa: E731
            until_answered(status)

            # freeze: the clock stops and the outputs go on; resume: it runs again
            r = run_cli("ctl", "--config", str(config), "freeze")
            assert r.returncode == 0 and "freeze: queued" in r.stdout
            t0 = until_answered(lambda: status()["frozen"] and status()["time_s"])
            instruments.read(1.0)
            assert status()["time_s"] == t0 and "RMC" in instruments.last  # held, still reporting
            assert run_cli("ctl", "--config", str(config), "resume").returncode == 0
            until_answered(lambda: status()["time_s"] > t0 + 0.5)

            _steering_failure(endpoint, helm, instruments)

            # a reposition moves the ship in the NMEA position
            r = run_cli("ctl", "--config", str(config), "reposition", "--lat", "74.002", "--lon", "20.004",
                        "--heading", "90", "--speed", "0")
            assert r.returncode == 0, r.stderr
            until_answered(lambda: abs(status()["latitude_deg"] - 74.002) < 1e-4, timeout=30.0)
            instruments.read(2.0)
            rmc = instruments.last["RMC"]
            assert rmc.latitude == pytest.approx(74.002, abs=2e-4) and rmc.longitude == pytest.approx(20.004, abs=5e-4)

            # a vessel the instructor adds goes out as AIS
            vessel = {"command": "add_vessel", "mmsi": 230000001, "name": "ODEN", "length_m": 108.0, "beam_m": 31.0,
                      "latitude_deg": 74.003, "longitude_deg": 20.004, "course_deg": 0.0, "speed_kn": 0.0}
            assert request(endpoint, {"command": vessel}, None)["ok"]
            until_answered(lambda: instruments.read(0.5) or any(decode(m).asdict()["mmsi"] == 230000001
                                                           for m in instruments.ais if m.startswith("!AIVDM,1,1")))
            report = next(decode(m).asdict() for m in instruments.ais if m.startswith("!AIVDM,1,1"))
            assert report["lat"] == pytest.approx(74.003, abs=1e-4) and report["lon"] == pytest.approx(20.004, abs=1e-4)

            # a bad command: exit 2 and the node's reason; nothing applied
            r = run_cli("ctl", "--config", str(config), "visibility", "nan")
            assert r.returncode == 2 and "visibility_m = NaN" in r.stderr and "Traceback" not in r.stderr
            assert status()["visibility_m"] == 8000.0
        finally:
            helm.close()
            node.terminate()
            out, err = node.communicate(timeout=60)
    assert node.returncode == 0, err
    summary = json.loads(out)
    assert summary["control"]["requests"]["accepted"] == 6 and summary["control"]["requests"]["invalid"] == 1
    assert math.isfinite(summary["tick_ms_p99"])


def test_run_starts_the_instructor_station_and_names_its_address(tmp_path):
    port = free_port()
    config = exercise_toml(tmp_path, "", instructor=f"start = true\nport = {port}")
    node = subprocess.Popen([sys.executable, "-m", "bridge_node", "run", "--config", str(config), "--duration", "120",
                             "--render", "none", "--json", "--out", str(tmp_path / "out")], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        def page() -> bool:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=2) as r:
                    return r.status == 200 and b"<canvas" in r.read()
            except OSError:
                return False
        until_answered(page, timeout=120.0, poll=0.5)
        station = [p for p in psutil.Process(node.pid).children() if "instructor" in p.cmdline()]
        niceness = [p.nice() - psutil.Process(node.pid).nice() for p in station]
    finally:
        node.terminate()
        out, err = node.communicate(timeout=60)
    assert node.returncode == 0, err
    assert niceness == [10]  # the station yields the CPU to the physics loop
    summary = json.loads(out)
    assert summary["instructor"]["address"] == f"http://127.0.0.1:{port}/"
    assert summary["instructor"]["exit"] == 0, (tmp_path / "out" / "instructor.log").read_text()
