"""Issue 30, item 6: every output replaces only an absent path or a regular file, never a
symbolic link, a device node or a FIFO, refused before anything is written; a failed write
is a clean error that leaves the old file; and the options that hung or printed NaN are
range-checked."""
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from bridge_node.commands.render_node import _write_summary
from bridge_node.common.errors import UserError
from bridge_node.common.paths import writable_file
from bridge_node.render.video import save_png


def icebridge(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """The CLI as a user runs it; a hang is a TimeoutExpired, so a failed test."""
    return subprocess.run([sys.executable, "-m", "bridge_node", *args], capture_output=True, text=True, cwd=REPO,
                          timeout=timeout)


def clean_error(r: subprocess.CompletedProcess, *fragments: str) -> None:
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert "Traceback" not in r.stderr
    for f in fragments:
        assert f in r.stderr, (f, r.stderr)


@pytest.fixture
def places(tmp_path):
    """A FIFO, a symbolic link to a regular file, and a symbolic link loop."""
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "target.json").write_text("keep me")
    (tmp_path / "link").symlink_to(tmp_path / "target.json")
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    return tmp_path


def test_the_summary_never_replaces_a_fifo_or_a_symlink(places):
    for name, kind in (("fifo", "a FIFO"), ("link", "a symbolic link"), ("loop", "a symbolic link")):
        with pytest.raises(UserError, match=f"--summary = .*{name}'.*is {kind}"):
            _write_summary({"frames": 1}, str(places / name))
    assert stat.S_ISFIFO(os.lstat(places / "fifo").st_mode)
    assert os.readlink(places / "link") == str(places / "target.json")
    assert (places / "target.json").read_text() == "keep me"
    assert sorted(p.name for p in places.iterdir()) == ["fifo", "link", "loop", "target.json"]  # no temporary left


def test_a_device_is_refused_before_anything_is_written():
    # new in the fix: without it this test stops here, before any write that could replace a device
    from bridge_node.common.output_files import OutputFile

    for device in ("/dev/null", "/dev/full"):
        with pytest.raises(UserError, match=f"--video = '{device}': is a character device"):
            OutputFile(device, "--video")
        with pytest.raises(UserError, match=f"--summary = '{device}': is a character device"):
            _write_summary({"frames": 1}, device)
        with pytest.raises(UserError, match=f"--panorama = '{device}': is a character device"):
            save_png(np.zeros((4, 4, 3), np.uint8), Path(device), "--panorama")
        assert stat.S_ISCHR(os.lstat(device).st_mode)
    assert not [p for p in os.listdir("/dev") if p.startswith((".null.", ".full."))]


def test_a_regular_file_is_replaced_whole_and_images_need_no_extension(tmp_path):
    summary = tmp_path / "s.json"
    summary.write_text("old")
    _write_summary({"frames": 3}, str(summary))
    assert summary.read_text() == '{"frames": 3}'
    panorama = save_png(np.full((4, 6, 3), 200, np.uint8), tmp_path / "panorama", "--panorama")
    assert panorama.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["panorama", "s.json"]


def test_a_path_that_becomes_a_fifo_before_the_rename_is_refused(tmp_path):
    from bridge_node.common.output_files import OutputFile  # new in the fix

    path = tmp_path / "out.json"
    output = OutputFile(path, "--summary")
    output.tmp.write_text("{}")
    os.mkfifo(path)  # swapped in after the check
    with pytest.raises(UserError, match="is a FIFO"):
        output.commit()
    assert stat.S_ISFIFO(os.lstat(path).st_mode) and not output.tmp.exists()


def test_a_failed_write_is_a_clean_error_and_keeps_the_old_file(tmp_path):
    path = tmp_path / "tile.glb"
    path.write_bytes(b"old")
    code = ("import resource, signal, sys\n"
            "from bridge_node.common.errors import UserError\n"
            "from bridge_node.common.output_files import write_output\n"
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (1000, 1000))  # a disk that fills after 1000 bytes\n"
            "try:\n"
            f"    write_output({str(path)!r}, b'x' * 100_000, '--export')\n"
            "except UserError as exc:\n"
            "    sys.exit(str(exc))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=60)
    assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
    assert "--export = " in r.stderr and "cannot write this file (File too large)" in r.stderr
    assert path.read_bytes() == b"old" and sorted(p.name for p in tmp_path.iterdir()) == ["tile.glb"]


def test_writable_file_refuses_what_it_would_replace(places):
    for name in ("fifo", "link", "loop"):
        with pytest.raises(UserError, match="outputs replace only regular files"):
            writable_file(places / name, "--export")
    assert writable_file(places / "target.json", "--export") == places / "target.json"


def test_prefracture_export_to_a_fifo_a_loop_or_a_full_disk_is_a_clean_error(places):
    for target, kind in ((places / "fifo", "is a FIFO"), (places / "loop", "is a symbolic link"),
                         ("/dev/full", "is a character device")):
        clean_error(icebridge("prefracture", "--thickness", "0.5", "--export", str(target)), "--export", kind)
    assert stat.S_ISCHR(os.lstat("/dev/full").st_mode)


@pytest.mark.parametrize("args, message", [
    (["prefracture", "--thickness", "0.5", "--seed", "-1"], "--seed -1: a seed is an integer from 0"),
    (["render-node", "--wait", "nan"], "--wait nan is outside the allowed range"),
    (["render-node", "--wait", "inf"], "--wait inf is outside the allowed range"),
    (["render-node", "--wait", "1e308"], "--wait 1e+308 is outside the allowed range"),
    (["trial", "turning", "--speed", "1e-320"], "--speed 1e-320 is outside the allowed range [1.0, 30.0]"),
])
def test_options_that_hung_or_gave_nan_are_range_checked(tmp_path, args, message):
    clean_error(icebridge(*args, "--out", str(tmp_path), timeout=90), message)


def test_console_results_never_replace_a_fifo(places):
    from bridge_node.commands.console import _write_results

    with pytest.raises(UserError, match="--results = .*fifo'.*is a FIFO"):
        _write_results([], places / "fifo")
    assert stat.S_ISFIFO(os.lstat(places / "fifo").st_mode)
    _write_results([], places / "target.json")
    assert (places / "target.json").read_text() == "[]"
