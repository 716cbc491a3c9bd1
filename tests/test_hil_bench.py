"""The HIL bench as users run it: the node as its own process, the software console in
another, over slcan on a pty pair, NMEA 0183 on a pty pair and Modbus TCP on 127.0.0.1."""
import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from conftest import REPO

from bridge_node.hil.bench import Bench
from bridge_node.node.config import load_config, resolve_path

pytest_plugins = ["bridge_node.testing"]  # the fixtures users get: hil_bench, hil_scenario
SCENARIOS = REPO / "config" / "scenarios"


@pytest.fixture(scope="module")
def node_toml(tmp_path_factory):
    """A small exercise (400 m field of 0.3 m ice) with a template library shared by the tests."""
    folder = tmp_path_factory.mktemp("node")
    path = folder / "node.toml"
    path.write_text(f'[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 400.0\nthickness = 0.3\n'
                    f'[paths]\ncache_dir = "{folder / "tiles"}"\n')
    return path


def hil_run(*args, out) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "bridge_node", "hil", "run", *map(str, args), "--out", str(out)],
                          cwd=REPO, capture_output=True, text=True, timeout=240)


@pytest.mark.parametrize("link", ["can", "nmea", "modbus"])
def test_the_shipped_helm_response_passes_over_every_link_kind(node_toml, tmp_path, link):
    """helm_response.toml as shipped: rudder at 20 starboard on RSA and on the console's own
    link, at the SOLAS rate, the ship turning; over slcan, NMEA 0183 and Modbus TCP."""
    junit = tmp_path / "hil.xml"
    r = hil_run(SCENARIOS / "helm_response.toml", "--links", link, "--node-config", node_toml, "--junit", junit,
                out=tmp_path / "out")
    assert r.returncode == 0, r.stdout + r.stderr
    suites = ET.parse(junit).getroot()
    assert suites.get("failures") == "0" and int(suites.get("tests")) >= 4


def test_link_loss_bad_input_and_bus_off_over_slcan(node_toml, tmp_path):
    junit = tmp_path / "hil.xml"
    r = hil_run(SCENARIOS / "link_loss.toml", SCENARIOS / "bad_input.toml", SCENARIOS / "can_bus_off.toml",
                "--links", "can", "--node-config", node_toml, "--junit", junit, out=tmp_path / "out")
    assert r.returncode == 0, r.stdout + r.stderr
    suites = ET.parse(junit).getroot()
    assert suites.get("failures") == "0" and int(suites.get("tests")) == 12
    assert "ALR 111 raised after" in r.stdout  # the fail-safe, measured
    run = next((tmp_path / "out").iterdir())
    node = json.loads((run / "node.json").read_text().splitlines()[-1])
    errors = node["links"][0]["errors"]
    # the node's documented reactions: bad input counted by kind, the garbage burst whole,
    # the lost bus counted and reopened
    assert errors["out_of_range"] > 0 and errors["wrong_dlc"] > 0 and errors["unknown_frame"] == 200
    assert errors["bus_lost"] == 1 and node["links"][0]["reconnects"] >= 1 and node["links"][0]["connected"]
    # nothing lost from the session record: every frame the node took in is there, an order
    # or counted as bad; and those are the console's frames but the ones written into the pty
    # while the node's end was closed by the bus-off (about 3 s at 20 frames/s)
    record = next((run / "sessions").iterdir()) / "can.log"
    received = sum(1 for line in record.read_text().splitlines() if line.endswith(" R"))
    assert received == node["links"][0]["inputs"] + sum(errors[k] for k in ("out_of_range", "wrong_dlc",
                                                                            "unknown_frame"))
    written = sum(int(line.split(" frames ")[1].split()[0]) for line in r.stdout.splitlines()
                  if "console sent: primary" in line)
    assert written - 100 <= received <= written


def test_arbitration_hand_over_nmea_to_modbus_then_attach(node_toml, hil_bench, hil_scenario, tmp_path):
    """The hand-over through the pytest fixtures; then ``hil run --attach``: another console
    takes over the running node through the ends of the console config the bench wrote."""
    from bridge_node.testing import assert_scenario  # after pytest_plugins registered (and rewrote) it
    bench = hil_bench(links=["nmea0183", "modbus"], node_config=node_toml)
    assert_scenario(bench.play(hil_scenario(SCENARIOS / "arbitration_handover.toml")))
    bench.bench.console.__exit__(None, None, None)  # the bench's console lets go of its ends
    r = hil_run(helm_scenario(tmp_path, 3.0), "--attach", bench.bench.folder / "console.toml", out=tmp_path / "out")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "PASS  helm" in r.stdout and "node: no summary (attached" in r.stdout
    summary = bench.stop()
    primary, backup = summary["links"][0], summary["links"][1]
    assert primary["errors"] == {} and primary["inputs"] > 50  # NMEA orders taken, none bad
    assert backup["inputs"] > 50  # Modbus polled


def helm_scenario(folder, deg: float, rate: bool = False):
    """A short scenario file: helm ``deg`` at 0.5 s, the rudder there within 6 s on the panel
    (or, with ``rate``, the steering gear's rate from 1 deg to ``deg - 1`` at >= 2.32 deg/s)."""
    expect = ('quantity = "rudder_rate"\nfrom_deg = 1.0\nto_deg = {}\nmin = 2.32\n'.format(deg - 1.0) if rate
              else f'quantity = "rudder_angle"\nmin = {deg - 0.5}\nmax = {deg + 0.5}\n')
    path = folder / "helm.toml"
    path.write_text(f'name = "helm {deg:g}"\n[[actions]]\nat_s = 0.0\nhelm_deg = 0.0\n[[actions]]\nat_s = 0.5\n'
                    f'helm_deg = {deg}\n[[expect]]\nname = "steering gear rate"\nafter_s = 0.5\nwithin_s = 6.0\n'
                    f'link = "panel"\n' + expect)
    return path


def test_slowed_steering_gear_fails_with_the_measured_rate(node_toml, tmp_path):
    ships = tmp_path / "ships"
    ships.mkdir()
    ship = (REPO / "config" / "ships" / "polar_cargo.toml").read_text()
    (ships / "slow_gear.toml").write_text(ship.replace("rate_deg_s = 2.5", "rate_deg_s = 1.2"))
    slow = tmp_path / "slow.toml"
    slow.write_text(node_toml.read_text().replace("polar_cargo", "slow_gear"))
    junit = tmp_path / "hil.xml"
    r = hil_run(helm_scenario(tmp_path, 10.0, rate=True), "--links", "nmea", "--node-config", slow, "--junit", junit,
                out=tmp_path / "out")
    assert r.returncode == 1, r.stdout + r.stderr
    line = next(x for x in r.stdout.splitlines() if "steering gear rate" in x)
    assert line.lstrip().startswith("FAIL")
    rate = float(line.split(": ")[-1].split(" deg/s")[0])
    assert rate == pytest.approx(1.2, abs=0.1)  # the slowed gear's rate, measured from RSA
    failure = next(c for c in ET.parse(junit).getroot().iter("testcase") if "steering" in c.get("name"))
    assert f"{rate:.2f} deg/s" in failure.find("failure").get("message")


def test_modbus_bad_replies_over_tcp(node_toml, tmp_path):
    """The Modbus console's out-of-range registers and malformed MBAP replies: the node counts
    them (out_of_range, request_failed), reopens the connection, and the rudder holds."""
    r = hil_run(SCENARIOS / "modbus_bad_replies.toml", "--links", "modbus", "--node-config", node_toml,
                out=tmp_path / "out")
    assert r.returncode == 0, r.stdout + r.stderr
    run = next((tmp_path / "out").iterdir())
    node = json.loads((run / "node.json").read_text().splitlines()[-1])
    primary = node["links"][0]
    assert primary["errors"]["out_of_range"] > 0 and primary["errors"]["request_failed"] > 0
    assert set(primary["errors"]) <= {"out_of_range", "request_failed", "connect_failed"}
    assert primary["connected"] and primary["reconnects"] >= 1
    # nothing lost from the session record: every register the node read is there, an order
    # or counted as out of range
    record = next((run / "sessions").iterdir()) / "modbus.csv"
    reads = [row for row in record.read_text().splitlines()[1:] if row.split(",")[2] == "read"]
    assert len(reads) == primary["inputs"] + primary["errors"]["out_of_range"]


def test_scenarios_of_other_link_kinds_get_their_own_bench_in_one_command(node_toml, tmp_path):
    """Issue 30, item 10: a scenario names the link kinds it needs, and one ``hil run`` gives
    each its bench (here a CAN bus-off and a Modbus server's bad replies)."""
    junit = tmp_path / "hil.xml"
    r = hil_run(SCENARIOS / "can_bus_off.toml", SCENARIOS / "modbus_bad_replies.toml", "--node-config", node_toml,
                "--junit", junit, out=tmp_path / "out")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "starting the node (can console" in r.stdout and "starting the node (modbus console" in r.stdout
    suites = ET.parse(junit).getroot()
    assert suites.attrib["failures"] == "0"
    assert [s.attrib["name"] for s in suites] == ["CAN bus-off and recovery", "Modbus bad replies"]


def test_the_session_record_folder_is_not_doubled_for_a_relative_run_folder(tmp_path, monkeypatch):
    """``hil run`` names its run folder relative to the working directory; the node reads a
    relative ``paths.session_dir`` from its config's folder, which is that run folder, so the
    record went to out/hil/<stamp>/out/hil/<stamp>/sessions."""
    monkeypatch.chdir(tmp_path)
    bench = Bench(Path("out/hil/stamp"), ["nmea0183"])
    bench.folder.mkdir(parents=True)
    try:
        bench._write_configs()
    finally:
        bench._stack.close()
    node_toml = bench.folder / "node.toml"
    cfg = load_config(node_toml)
    assert resolve_path(node_toml, cfg.paths.session_dir) == tmp_path / "out" / "hil" / "stamp" / "sessions"
