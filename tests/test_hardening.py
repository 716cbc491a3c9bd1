"""Never a traceback, never an open door: each reproducer of the hardening issue gives a
clear error (file, key or option, value, what is allowed) with exit status 2, or the
documented safe behaviour; mutated configs are clean errors or valid configs; the node
opens no socket off the loopback; torn record lines are skipped and counted."""
import math
import os
import shutil
import socket
import subprocess
import sys
import time
import tomllib

import can
import psutil
import pytest
import tomli_w
from conftest import REPO, exercise_toml, fuzz_budget, run_cli
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from links_helpers import console_frame
from toml_mutants import mutated

from bridge_node.links.messages import Traffic
from bridge_node.links.can.link import CanLink
from bridge_node.links.modbus.link import RegisterAccess
from bridge_node.links.can.n2k_frames import identifier
from bridge_node.links.nmea0183.sentences import ROR, SentenceError, parse_order
from bridge_node.links.nmea0183.link import NmeaLink
from bridge_node.links.record_reader import read_can_log, read_modbus_csv, read_nmea_log
from bridge_node.links.session_record import SessionRecord
from bridge_node.links.can.settings import CanLinkSettings
from bridge_node.links.nmea0183.settings import NmeaLinkSettings
from bridge_node.node.config import DEFAULT_CONFIG, ConfigError, load_config, load_ship
from bridge_node.common.network import free_port
from sim_core import kernel_sources_digest

CONSOLE = DEFAULT_CONFIG.parent / "bridge_console.toml"
BASE = '[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'


def clean_error(r: subprocess.CompletedProcess, *fragments: str) -> None:
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert "Traceback" not in r.stderr
    for f in fragments:
        assert f in r.stderr, (f, r.stderr)


def test_the_readmes_console_config_copied_elsewhere_still_finds_its_dbc(tmp_path):
    cfg = tmp_path / "x.toml"
    shutil.copy(CONSOLE, cfg)
    r = run_cli("links", "monitor", "--config", str(cfg), "--duration", "1", "--no-record", "--json")
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert load_config(cfg).links[0].dbc == str(DEFAULT_CONFIG.parent / "console.dbc")


@pytest.mark.parametrize("dbc, message", [
    ("/dev/zero", "is not a regular file"),
    ("missing.dbc", "no such file"),
    ("not_a.dbc", "is not a DBC file"),
])
def test_bad_dbc_files_are_config_errors_never_a_hang(tmp_path, dbc, message):
    (tmp_path / "not_a.dbc").write_text("this is not a DBC file\n" * 50)
    cfg = tmp_path / "c.toml"
    cfg.write_text(BASE + f'[[links]]\nname = "a"\ntype = "can"\nallowed_sources = "any"\ndbc = "{dbc}"\n')
    clean_error(run_cli("links", "monitor", "--config", str(cfg), "--duration", "1"), str(cfg), "links.0.dbc",
                dbc, message)


def test_unusable_output_paths_are_refused_before_the_work(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(BASE + '[[links]]\nname = "a"\ntype = "nmea0183"\n[paths]\nsession_dir = "/etc/hostname"\n')
    clean_error(run_cli("links", "monitor", "--config", str(cfg), "--duration", "1"), "paths.session_dir",
                "/etc/hostname", "cannot write files there")
    clean_error(run_cli("links", "monitor", "--config", str(cfg), "--duration", "1", "--record", "/dev/null/x"),
                "--record", "/dev/null/x")
    r = run_cli("run", "--duration", "1", "--no-record", "--out", "/etc/hostname")
    clean_error(r, "--out", "/etc/hostname")
    assert "ticks" not in r.stdout  # refused before the run, not after it
    clean_error(run_cli("prefracture", "--thickness", "0.5", "--export", "/proc/x.glb"), "--export", "/proc/x.glb")
    clean_error(run_cli("prefracture", "--cache-dir", "/etc/hostname"), "--cache-dir")


@pytest.mark.parametrize("text, fragments", [
    ('[[links]]\nname = "io"\ntype = "modbus"\n[[links.registers]]\norder = "rudder"\naddress = 0\n'
     '[[links.writes]]\nvalue = "rudder_angle"\naddress = 1\nscale = 0\n', ["writes.0.scale", "1e-06 <= |scale|"]),
    ('[[links]]\nname = "io"\ntype = "modbus"\n[[links.registers]]\norder = "rudder"\naddress = 0\nscale = nan\n',
     ["registers.0.scale", "must be finite"]),
    ('[[links]]\nname = "io"\ntype = "modbus"\n[[links.registers]]\norder = "rudder"\naddress = 0\nscale = 1e30\n',
     ["registers.0.scale"]),
    ('[[links]]\nname = "n"\ntype = "nmea0183"\nport = "socket://192.0.2.1:4001"\n',
     ["port = '192.0.2.1' is not a loopback address", "allow_network"]),
    ('[[links]]\nname = "n"\ntype = "nmea0183"\nport = "rfc2217://192.0.2.1:4001"\n', ["allow_network"]),
    ('[[links]]\nname = "c"\ntype = "can"\nallowed_sources = "any"\ninterface = "socketcand"\n',
     ["'socketcand' reaches a network", "allow_network"]),
    ('[[links]]\nname = "c"\ntype = "can"\nallowed_sources = "any"\ninterface = "udp_multicast"\n', ["allow_network"]),
    ('[[links]]\nname = "c"\ntype = "can"\ninterface = "slcan"\nchannel = "socket://10.0.0.5:3333"\n'
     'allowed_sources = [66]\n', ["channel = '10.0.0.5'"]),
    ('[[links]]\nname = "c"\ntype = "can"\nallowed_sources = []\n', ["allowed_sources"]),
    ('[[links]]\nname = "c"\ntype = "can"\n', ["allowed_sources", "required"]),
    ('[[links]]\nname = "n"\ntype = "nmea0183"\nport = ""\n', ["links.0.port = ''"]),
    ('[[links]]\nname = "n"\ntype = "nmea0183"\n[links.rates]\nHDT = false\n', ["rates.HDT = False"]),
])
def test_bad_link_values_are_config_errors(tmp_path, text, fragments):
    cfg = tmp_path / "c.toml"
    cfg.write_text(BASE + text)
    clean_error(run_cli("links", "monitor", "--config", str(cfg), "--duration", "1"), str(cfg), *fragments)


@pytest.mark.parametrize("text, fragment", [
    ('[ship]\nname = "' + "x" * 300 + '"\n[ice_field]\nthickness = 0.5\n', "ship.name"),
    ('[ship]\nname = "../../etc/passwd"\n[ice_field]\nthickness = 0.5\n', "ship.name"),
    ('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = true\n', "ice_field.thickness = True"),
    ('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = "1.0"\n', "ice_field.thickness = '1.0'"),
])
def test_loose_values_are_config_errors(tmp_path, text, fragment):
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    clean_error(run_cli("prefracture", "--config", str(cfg), "--out", str(tmp_path)), str(cfg), fragment)


def test_nmea_numbers_are_nmea_decimals_only():
    for text in ("1_0", "1e-400", "1e2", "nan", "inf", "0x10", " 5"):
        with pytest.raises(SentenceError) as err:
            parse_order(str(ROR("RC", "ROR", (text, "A", "", "V", "B"))), 0.0, "x")
        assert err.value.kind == "bad_field", text
    for text, deg in (("10", 10.0), ("-5.5", -5.5), (".5", 0.5), ("+2.", 2.0)):
        order, = parse_order(str(ROR("RC", "ROR", (text, "A", "", "V", "B"))), 0.0, "x")
        assert order.value == pytest.approx(math.radians(deg))


def test_can_orders_from_our_own_address_or_in_fd_frames_are_dropped():
    link = CanLink(CanLinkSettings(type="can", name="c", channel="icebridge-hardening", allowed_sources="any"))
    own = console_frame("HelmOrder", source=link.settings.source_address, RudderOrder=5.0, Status=1, Counter=0)
    assert link._decode(own, 0.0) == [] and link.health().errors["own_address"] == 1
    good = console_frame("HelmOrder", RudderOrder=5.0, Status=1, Counter=0)
    fd = can.Message(arbitration_id=good.arbitration_id, data=bytes(good.data) + bytes(4), is_extended_id=True,
                     is_fd=True)
    assert link._decode(fd, 0.0) == [] and link.health().errors["fd_frame"] == 1
    assert len(link._decode(good, 0.0)) == 1


def test_the_udp_mirror_socket_is_bound_to_the_loopback():
    with NmeaLink(NmeaLinkSettings(type="nmea0183", name="n", udp_port=10110)) as link:
        assert link._udp.getsockname()[0] == "127.0.0.1"


def test_free_ports_are_never_handed_out_twice():
    """Nothing holds a port between free_port() and its user's bind: within a process it
    never returns the same one twice, and each is free for a listener when returned."""
    ports = [free_port() for _ in range(300)]
    assert len(set(ports)) == len(ports)
    with socket.socket() as s:
        s.bind(("127.0.0.1", ports[-1]))


MUTANTS = fuzz_budget(2000)  # more for an exploring run


@settings(max_examples=MUTANTS, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture],
          )
@given(st.sampled_from([DEFAULT_CONFIG, CONSOLE]), st.data())
def test_mutated_configs_are_clean_errors_or_valid_configs(tmp_path, seed, data):
    doc = mutated(tomllib.loads(seed.read_text()), data)
    cfg_file = tmp_path / "mutant.toml"
    try:
        cfg_file.write_text(tomli_w.dumps(doc))
    except (TypeError, ValueError):
        return  # not expressible as TOML (a NaN key, say): nothing a user could write
    try:
        cfg = load_config(cfg_file)
        load_ship(cfg.ship.name, cfg_file)
    except ConfigError as exc:
        assert str(cfg_file) in str(exc)


def test_the_node_opens_no_socket_off_the_loopback(tmp_path):
    cfg = exercise_toml(tmp_path, '[[render.channels]]\nname = "bow"\nwidth = 64\nheight = 36\n',
                        **{"[links]": 'name = "instruments"\ntype = "nmea0183"\nudp_port = 10110'})
    node = subprocess.Popen([sys.executable, "-m", "bridge_node", "run", "--config", str(cfg), "--duration", "30",
                             "--no-record", "--out", str(tmp_path)], cwd=REPO, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    seen = set()
    try:
        deadline = time.monotonic() + 40.0  # loading, then the run: look all along
        while node.poll() is None and time.monotonic() < deadline:
            procs = [psutil.Process(node.pid), *psutil.Process(node.pid).children(recursive=True)]
            for p in procs:
                try:
                    conns = p.net_connections(kind="inet")
                except psutil.NoSuchProcess:
                    continue
                seen |= {(c.laddr.ip, c.laddr.port) for c in conns} | {(c.raddr.ip, c.raddr.port)
                                                                       for c in conns if c.raddr}
            time.sleep(0.5)
    finally:
        node.terminate()
        node.wait(60)
    assert len(seen) >= 3, seen  # the stream's two endpoints and the UDP mirror at least
    assert all(ip.startswith("127.") or ip == "::1" for ip, _ in seen), seen


def write_record(folder) -> None:
    rec = SessionRecord(folder)
    for k in range(5):
        rec.on_traffic(Traffic(1.7e9 + k, "c", "can", "rx",
                               can.Message(timestamp=1.7e9 + k, arbitration_id=identifier(6, 0xFF50, 0x42),
                                           data=bytes([k, 1, 2, 3, 4, 5, 6, 7]), is_extended_id=True)))
        rec.on_traffic(Traffic(1.7e9 + k, "n", "nmea0183", "rx", str(ROR("RC", "ROR", (f"{k}.0", "A", "", "V", "B")))))
        rec.on_traffic(Traffic(1.7e9 + k, "io", "modbus", "read", RegisterAccess("holding", k, 100 + k, 10.0 + k)))
    rec.stop()


def same(a: list, b: list) -> bool:
    """Records equal, comparing CAN frames by content (can.Message compares by identity)."""
    def key(m):
        return (m.timestamp, m.arbitration_id, bytes(m.data), m.is_rx) if isinstance(m, can.Message) else m
    return [key(x) for x in a] == [key(x) for x in b]


@pytest.mark.parametrize("name, reader", [("can.log", read_can_log), ("nmea.log", read_nmea_log),
                                          ("modbus.csv", read_modbus_csv)])
def test_torn_record_lines_are_skipped_and_counted(tmp_path, name, reader):
    write_record(tmp_path / "rec")
    whole = (tmp_path / "rec" / name).read_bytes()
    full, counts = reader(tmp_path / "rec" / name)
    assert len(full) == 5 and not counts["torn"] and not counts["malformed"]
    ends = [i + 1 for i, b in enumerate(whole) if b == ord("\n")]
    for cut in range(ends[-3], len(whole) + 1):  # cut anywhere in the last two lines
        torn = tmp_path / f"cut_{name}"
        torn.write_bytes(whole[:cut])
        got, counts = reader(torn)
        complete = whole[:cut].count(b"\n") - (1 if name == "modbus.csv" else 0)  # the CSV header
        assert len(got) == complete and counts["torn"] == (0 if whole[:cut].endswith(b"\n") else 1)
        assert not counts["malformed"] and same(got, full[:complete])
    # a record reopened after the cut drops the torn tail before appending: nothing glues on
    (tmp_path / "rec" / name).write_bytes(whole[:len(whole) - 7])
    write_record(tmp_path / "rec")
    got, counts = reader(tmp_path / "rec" / name)
    assert len(got) == 9 and not counts["torn"] and not counts["malformed"]


def test_numba_caches_outside_the_source_tree(tmp_path):
    code = ("import numpy as np, sim_core.scene.quadtree as q; q.tiles_near(np.zeros((1, 2)), 80.0, 4, 4, 100.0); "
            "import os; print(os.environ['NUMBA_CACHE_DIR'])")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=300,
                       env={k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
                       | {"XDG_CACHE_HOME": str(tmp_path)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == str(tmp_path / "icebridge" / "numba" / kernel_sources_digest())
    assert list((tmp_path / "icebridge" / "numba").rglob("*.nbi"))
    assert not list((REPO / "sim_core").rglob("*.nbi"))


def test_a_changed_kernel_source_gets_a_cache_folder_of_its_own(tmp_path):
    """numba keys a cached kernel by its own file alone, so a kernel that compiles in
    another module's kept that module's old code; the cache folder follows the sources of
    every kernel instead. A file without kernels does not move it."""
    core = tmp_path / "sim_core"
    shutil.copytree(REPO / "sim_core", core, ignore=shutil.ignore_patterns("__pycache__"))
    before = kernel_sources_digest(core)
    (core / "world.py").write_text((core / "world.py").read_text() + "\n# a comment\n")
    assert kernel_sources_digest(core) == before  # no kernel there
    vertical = core / "ice" / "vertical.py"
    vertical.write_text(vertical.read_text().replace("SETTLED = 1e-5", "SETTLED = 2e-5"))
    assert kernel_sources_digest(core) != before


def test_a_ship_name_on_the_command_line_is_checked_too():
    clean_error(run_cli("trial", "turning", "--ship", "x" * 300), "ship name", "at most 64")
