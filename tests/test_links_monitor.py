"""``icebridge links monitor`` as a user runs it, and the session record surviving a kill."""
import json
import os
import select
import signal
import subprocess
import sys
import time

import serial
from conftest import REPO, run_cli
from links_helpers import bare_pty, pty_pair

from bridge_node.links.nmea0183.sentences import PRC, ROR, checksum


def write_config(tmp_path, port: str, udp_port: int | None = None) -> str:
    cfg = tmp_path / "node.toml"
    cfg.write_text(
        '[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
        f'[[links]]\nname = "console"\ntype = "nmea0183"\nport = "{port}"\nbaudrate = 38400\n'
        f'udp_port = {udp_port or 10110}\n'
        '[arbitration]\nrudder = ["console"]\nengine = ["console"]\nfail_safe_after_s = 1.0\n'
    )
    return str(cfg)


def start_monitor(cfg: str, record, *extra) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "bridge_node", "links", "monitor", "--config", cfg,
                             "--record", str(record), *extra], cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def wait_ready(proc, read, timeout: float = 30.0) -> None:
    """Wait until the node's console port is open: until the console hears a sentence from
    it (``read()``: the bytes waiting at the console, at once). Only an open port writes,
    and pyserial flushes a port's input as it opens it, before any write, so what the
    console writes from then on reaches the node. (The session record's files exist
    before the port opens, and it records what the node sends even then.)"""
    t0, heard = time.monotonic(), b""
    while b"$" not in heard:
        assert proc.poll() is None, proc.stderr.read()
        assert time.monotonic() - t0 < timeout
        time.sleep(0.05)
        heard += read()


def pty_read(fd: int) -> bytes:
    """What waits at a pty's end (b"" if nothing)."""
    return os.read(fd, 4096) if select.select([fd], [], [], 0)[0] else b""


def monitor_summary(tmp_path, duration: str, lines: list[bytes], times: int, extra: str = "") -> dict:
    """Run the monitor on a console pty (``extra`` added to its config), send ``lines``
    ``times`` times, 0.1 s apart, and return its JSON summary. The pty has no relay: the
    test never reads what the node writes to the console, and socat's pair stops passing
    the console's orders once that end is full (``bare_pty``)."""
    with bare_pty() as (node_end, console):
        cfg = tmp_path / "monitor.toml"
        cfg.write_text(open(write_config(tmp_path, node_end)).read() + extra)
        record = tmp_path / "rec"
        proc = start_monitor(str(cfg), record, "--duration", duration, "--json")
        wait_ready(proc, lambda: pty_read(console))
        for _ in range(times):
            for line in lines:
                os.write(console, line)
            time.sleep(0.1)
        out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    return json.loads(out)


def test_monitor_json_summary(tmp_path):
    # 3 s of orders, then silence: stale after 1 s, fail-safe 1 s later; 8 s in all, so that
    # a loaded machine's slow start and late orders leave the fail-safe time to act
    s = monitor_summary(tmp_path, "8", [(str(ROR("RC", "ROR", ("20.0", "A", "", "V", "B"))) + "\r\n").encode(),
                                        (str(PRC("RC", "PRC", ("50.0", "A", "", "V", "", "V", "B", "0"))) + "\r\n")
                                        .encode(), b"$RCROR,20.0,A,,V,B*00\r\n"], 30)
    assert s["orders"]["console/rudder/0"]["count"] == 30
    assert abs(s["orders"]["console/rudder/0"]["last"] - 0.349066) < 1e-5
    assert s["orders"]["console/lever/0"]["last"] == 50.0
    assert s["errors"] == {"bad_checksum": 30}
    assert s["outputs"]["console"] > 20
    # the open-water ship obeyed the console (from midships towards 20 deg), and has been
    # turning back to midships since the fail-safe
    assert 0.5 < s["ship"]["rudder_deg"] < 20.0
    assert any(a["number"] == 111 and a["active"] for a in s["alarms"])  # console went silent: fail-safe


def test_searchlight_orders_act_under_the_monitor(tmp_path):
    """The monitor steps the exercise's one tick, so a searchlight order from the console
    reaches the ship's light (it used to be shown and dropped)."""
    body = "PICBSL,0,A,45.0,-5.0"
    # 8 s for 1 s of orders: a loaded machine's slow start must not cut the last ones off
    s = monitor_summary(tmp_path, "8", [f"${body}*{checksum(body):02X}\r\n".encode()], 10,
                        '[[render.searchlights]]\nposition = [20.0, 0.0, 30.0]\ndepression_deg = 10.0\n'
                        'train_range_deg = [-90.0, 90.0]\non = false\n')
    assert s["orders"]["console/searchlight/0"]["count"] == 10
    assert s["searchlights"] == [{"on": True, "bearing_deg": 45.0, "elevation_deg": -5.0}]
    assert s["orders_rejected"] == {}


def test_session_record_readable_after_kill(tmp_path):
    with pty_pair(tmp_path) as (node_end, console_end):
        record = tmp_path / "rec"
        proc = start_monitor(write_config(tmp_path, node_end), record)
        port = serial.Serial(console_end, 38400, timeout=0)
        wait_ready(proc, port.read_all)
        t_end = time.time() + 3.0
        sent = 0
        while time.time() < t_end:
            port.write((str(ROR("RC", "ROR", (f"{sent % 30}.0", "A", "", "V", "B"))) + "\r\n").encode())
            sent += 1
            time.sleep(0.05)
        killed_at = time.time()
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
        port.close()
    lines = (record / "nmea.log").read_text().splitlines()
    rx = [line for line in lines if " rx " in line]
    assert all(len(line.split(" ", 3)) == 4 for line in lines)  # every line whole
    # what the node read before the kill is on disk (the flush period itself is tested on a
    # fake clock in test_links_base.py), and every recorded order is one the console sent
    assert rx and float(rx[-1].split()[0]) <= killed_at
    sent_lines = {str(ROR("RC", "ROR", (f"{k % 30}.0", "A", "", "V", "B"))) for k in range(sent)}
    assert {line.split(" ", 3)[3] for line in rx} <= sent_lines


def test_monitor_without_links_is_a_clear_error(tmp_path):
    cfg = tmp_path / "no_links.toml"
    cfg.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n')
    r = run_cli("links", "monitor", "--config", str(cfg), "--duration", "1")
    assert r.returncode == 2 and "no [[links]] configured" in r.stderr and "Traceback" not in r.stderr


def test_link_config_errors_name_the_key(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
                   '[[links]]\nname = "a"\ntype = "carrier_pigeon"\n')
    r = run_cli("links", "monitor", "--config", str(cfg), "--duration", "1")
    assert r.returncode == 2 and str(cfg) in r.stderr and "links.0" in r.stderr and "carrier_pigeon" in r.stderr
    cfg.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
                   '[[links]]\nname = "a"\ntype = "can"\nbitrate = 5\n[arbitration]\nrudder = ["b"]\n')
    r = run_cli("links", "monitor", "--config", str(cfg), "--duration", "1")
    assert r.returncode == 2 and "links.0.bitrate = 5" in r.stderr
    cfg.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
                   '[[links]]\nname = "a"\ntype = "can"\nallowed_sources = "any"\n[arbitration]\nrudder = ["b"]\n')
    r = run_cli("links", "monitor", "--config", str(cfg), "--duration", "1")
    assert r.returncode == 2 and "arbitration.rudder: unknown link(s) ['b']" in r.stderr
    assert "Traceback" not in r.stderr


def test_shipped_console_example_config_is_valid():
    from bridge_node.node.config import DEFAULT_CONFIG, load_config

    cfg = load_config(DEFAULT_CONFIG.parent / "bridge_console.toml")
    assert [link.type for link in cfg.links] == ["can", "nmea0183", "modbus", "dis"]
    assert cfg.links[1].ais is not None and cfg.links[1].sends_udp()
    assert cfg.arbitration.rudder == ["console_can", "console_nmea", "wing_io"]
