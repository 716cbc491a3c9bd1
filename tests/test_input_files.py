"""Issue 30, items 4 and 5: every file the node reads is a regular file under a size limit,
read with that bound, so a device, a FIFO or a huge file is one clear error (exit 2, no
traceback, no hang); TOML that Python's reader cannot take (nested too deep, an integer of
more than 4300 digits) and a NUL in a path are clean errors naming the file and the key."""
import os
import re
import subprocess
import sys

import pytest
from conftest import REPO

from bridge_node.hil.scenario import load_scenario
from bridge_node.links.record_reader import read_nmea_log
from bridge_node.node.config import DEFAULT_CONFIG, ConfigError, load_config, load_ship
from bridge_node.common.errors import UserError
from bridge_node.render.warp import WarpError, read_pfm

BASE = '[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
SCENARIO = REPO / "config" / "scenarios" / "helm_response.toml"  # needs no backup end


def icebridge(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """The CLI as a user runs it; a hang is a TimeoutExpired, so a failed test."""
    return subprocess.run([sys.executable, "-m", "bridge_node", *args], capture_output=True, text=True, cwd=REPO,
                          timeout=timeout)


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "fifo.toml"
    os.mkfifo(path)
    return path


# (arguments, with {} where the input file goes; what the message calls the file)
PLACES = [
    (["run", "--config", "{}", "--duration", "1", "--no-record", "--out", "{out}"], "config file"),
    (["prefracture", "--config", "{}", "--out", "{out}"], "config file"),
    (["replay", "--config", "{}", str(REPO / "config" / "default.toml"), "--out", "{out}"], "config file"),
    (["trial", "turning", "--config", "{}", "--out", "{out}"], "config file"),
    (["experiment", "breaking", "--config", "{}", "--out", "{out}"], "config file"),
    (["replay", "{}", "--out", "{out}"], "log"),
    (["console", "--script", "{}"], "scenario file"),
    (["hil", "run", "{}", "--out", "{out}"], "scenario file"),
    (["hil", "run", str(SCENARIO), "--node-config", "{}", "--out", "{out}"], "config file"),
    (["hil", "run", str(SCENARIO), "--attach", "{}", "--out", "{out}"], "console config"),
]


@pytest.mark.parametrize("args, what", PLACES, ids=[" ".join(a[:2]) + f" ({w})" for a, w in PLACES])
def test_a_fifo_in_any_input_place_is_a_clear_error_never_a_hang(tmp_path, fifo, args, what):
    r = icebridge(*[a.format(fifo, out=tmp_path / "out") for a in args])
    assert r.returncode == 2, r.stderr[-2000:]
    assert "Traceback" not in r.stderr
    assert f"{fifo}: the {what} is not a regular file (it is a FIFO)" in r.stderr, r.stderr


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
@pytest.mark.parametrize("args", [["prefracture", "--config", "{}", "--out", "{out}"], ["replay", "{}", "--out", "{out}"],
                                  ["console", "--script", "{}"]], ids=["config", "log", "script"])
def test_endless_devices_are_refused_without_reading_them(tmp_path, device, args):
    r = icebridge(*[a.format(device, out=tmp_path) for a in args], timeout=30)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr[-2000:]
    assert f"{device}: the " in r.stderr and "is not a regular file (it is a character device)" in r.stderr


def test_a_config_over_the_size_limit_is_refused(tmp_path):
    from bridge_node.common.input_files import TOML_LIMIT  # new in the fix: imported here, the rest runs without it
    big = tmp_path / "big.toml"
    big.write_text(BASE + "# padding\n" * (TOML_LIMIT // 10 + 1))
    with pytest.raises(ConfigError, match=rf"{re.escape(str(big))}: the config file is larger than 4 MiB"):
        load_config(big)


def test_reads_are_bounded_even_when_the_size_is_not_known_up_front(tmp_path):
    from bridge_node.common.input_files import read_input
    path = tmp_path / "f"
    path.write_bytes(b"x" * 100)
    assert read_input(path, "log", 100) == b"x" * 100
    with pytest.raises(UserError, match="the log is larger than 99 bytes"):
        read_input(path, "log", 99)
    with pytest.raises(UserError, match="log not found"):
        read_input(tmp_path / "missing", "log", 99)


def test_warp_ship_and_session_record_files_must_be_regular_files(tmp_path):
    os.mkfifo(tmp_path / "warp.pfm")
    config = tmp_path / "node.toml"
    config.write_text(BASE + '[[render.channels]]\nname = "c"\nwarp = "warp.pfm"\n')
    with pytest.raises(ConfigError, match=r"render.channels.0.warp = 'warp.pfm': .*warp.pfm is not a regular file"):
        load_config(config)
    with pytest.raises(WarpError, match=r"channel c: the warp grid file .*warp.pfm is not a regular file \(it is a "
                                        r"FIFO\)"):
        read_pfm(tmp_path / "warp.pfm", "channel c")  # as a channel reads it when it opens
    (tmp_path / "ships").mkdir()
    os.mkfifo(tmp_path / "ships" / "fifo_ship.toml")
    with pytest.raises(ConfigError, match=r"fifo_ship.toml: the config file is not a regular file \(it is a FIFO\)"):
        load_ship("fifo_ship", config)
    os.mkfifo(tmp_path / "nmea.log")
    with pytest.raises(UserError, match=r"nmea.log: the session record file is not a regular file"):
        read_nmea_log(tmp_path / "nmea.log")


def deep_config(tmp_path, depth: int):
    path = tmp_path / "deep.toml"
    path.write_text(BASE + "[render]\nchannels = " + "[" * depth + "]" * depth + "\n")
    return path


def test_toml_nested_too_deep_names_the_file_line_and_key(tmp_path):
    path = deep_config(tmp_path, 5000)
    with pytest.raises(ConfigError, match=rf"{re.escape(str(path))}:6: render.channels: not valid TOML: values "
                                          "nested too deep"):
        load_config(path)
    scenario = tmp_path / "s.toml"
    scenario.write_text(SCENARIO.read_text() + "\n[deep]\nvalue = " + "{a = " * 3000 + "1" + "}" * 3000 + "\n")
    with pytest.raises(ConfigError, match=r"s.toml:\d+: deep.value: not valid TOML: values nested too deep"):
        load_scenario(scenario)
    r = icebridge("prefracture", "--config", str(path), "--out", str(tmp_path))
    assert r.returncode == 2 and "Traceback" not in r.stderr and "render.channels" in r.stderr, r.stderr[-2000:]


def test_huge_integers_are_config_errors_naming_the_key(tmp_path):
    path = tmp_path / "big_int.toml"
    path.write_text(BASE.replace("thickness = 0.5", "thickness = " + "9" * 5000))
    with pytest.raises(ConfigError, match=rf"{re.escape(str(path))}:4: ice_field.thickness: not valid TOML: an "
                                          "integer of more than 4300 digits"):
        load_config(path)
    path.write_text(BASE.replace("thickness = 0.5", "thickness = 0x" + "f" * 20000))  # parsed; too long to print
    with pytest.raises(ConfigError, match=r"ice_field.thickness = <an integer of 80000 bits>: .*valid number"):
        load_config(path)


def test_a_nul_in_a_path_is_a_config_error_naming_the_key(tmp_path):
    path = tmp_path / "nul.toml"
    path.write_text(BASE + '[paths]\nsession_dir = "\\u0000"\n')
    with pytest.raises(ConfigError, match=rf"{re.escape(str(path))}: invalid configuration:\n  paths.session_dir: a "
                                          "path cannot contain a NUL character"):
        load_config(path)
    r = icebridge("links", "monitor", "--config", str(path), "--duration", "1")
    assert r.returncode == 2 and "Traceback" not in r.stderr and "paths.session_dir" in r.stderr, r.stderr[-2000:]


def test_the_default_config_and_its_dbc_still_load():
    cfg = load_config(DEFAULT_CONFIG.parent / "bridge_console.toml")
    assert cfg.links[0].dbc.endswith("console.dbc")
