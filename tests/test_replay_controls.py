"""Replay controls: pause, faster, slower and seek forward (the world runs ahead without
outputs, then the render processes get a snapshot), from the keys of a real terminal."""
import json
import os
import subprocess
import sys
import threading
import time

from conftest import REPO, exercise_config, free_port
from replay_logs import nmea_lines, voyage

from bridge_node.links.hub import LinkHub
from bridge_node.links.record_reader import read_nmea_log
from bridge_node.node.render_processes import open_stream
from bridge_node.node.world_setup import build_world
from bridge_node.replay.engine import MAX_SPEED, Playback, run_replay
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.track import TrackPath, TrackSource, clean
from bridge_node.stream.settings import StreamSettings
from sim_core.world import new_world_data


def test_speed_keys_step_by_two_between_the_limits():
    p = Playback(500.0)
    p.key("+", 0, 0.5)
    assert p.speed == 1000.0
    p.key("+", 0, 0.5)
    assert p.speed is None  # beyond 1000 x: as fast as possible
    p.key("-", 0, 0.5)
    assert p.speed == MAX_SPEED
    for _ in range(12):
        p.key("<", 0, 0.5)
    assert p.speed == 1.0
    p.key("f", 10, 0.5)
    p.key("right", 10, 0.5)
    assert p.seek_to == 10 + 2 * 120  # two minutes ahead of step 10
    p.key(" ", 0, 0.5)
    assert p.paused
    p.key("q", 0, 0.5)
    assert p.stop


def test_a_seek_runs_ahead_without_outputs_and_a_pause_holds(tmp_path):
    base = exercise_config(tmp_path / "tiles", 400.0, 600.0, 50.0)
    cfg = type(base).model_validate(base.model_dump() | {
        "links": [{"type": "nmea0183", "name": "instruments", "udp_port": free_port(), "rates": {"HDT": 10.0}}]})
    (tmp_path / "v.nmea").write_text("\n".join(nmea_lines(voyage())))
    track = clean(load_inputs([str(tmp_path / "v.nmea")], None, {}, 0.1), 30.0, 20.0)
    model = build_world(cfg, None)
    path = TrackPath(track, model.origin, 30.0)
    source = TrackSource(path, track.start, track.end, 0.5)
    pose = path.pose(track.start, 0.5)
    data = new_world_data(model, pose.north, pose.east, pose.heading, pose.surge)
    seen = []

    def keys(k, stats, playback):
        seen.append((k, playback.paused))
        if len(seen) == 1:
            return ["f"]  # seek one minute (120 steps) ahead at once
        if k >= 180 and not any(paused for _, paused in seen):
            return [" "]
        return [" "] if seen[-1][1] and sum(paused for _, paused in seen) >= 3 else []

    stream = StreamSettings(publish=f"tcp://127.0.0.1:{free_port()}", snapshot=f"tcp://127.0.0.1:{free_port()}")
    with open_stream(stream) as publisher, LinkHub(cfg.links, cfg.arbitration, tmp_path / "sent") as hub:
        stats = run_replay(model, data, source, Playback(100.0), hub, publisher, keys)
    assert stats.steps == source.steps == 240  # every step simulated, the seek's included
    assert stats.distance > 300.0 and stats.broken_by_hull > 0  # the ice along the skipped minute broke
    published = source.steps - 120
    hdt = [r for r in read_nmea_log(tmp_path / "sent" / "nmea.log")[0] if "HDT" in r.sentence]
    assert len(hdt) == published  # one heading per step shown, none while seeking
    assert publisher.sent == published + 1  # and the render processes got a snapshot at the target
    assert sum(paused for _, paused in seen) >= 3  # it held, and went on


def _drain(fd: int) -> None:
    """Read a terminal until it closes (the writer never blocks on a full terminal)."""
    try:
        while os.read(fd, 4096):
            pass
    except OSError:  # the other end is gone
        pass
    os.close(fd)


def test_keys_from_a_real_terminal_seek_to_the_end(tmp_path):
    cfg = tmp_path / "exercise.toml"
    cfg.write_text(f'[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 600.0\nthickness = 0.3\n'
                   f'[fracture]\ntile_side = 50.0\n[paths]\ncache_dir = "{tmp_path / "tiles"}"\n'
                   f'[stream]\npublish = "tcp://127.0.0.1:{free_port()}"\nsnapshot = "tcp://127.0.0.1:{free_port()}"\n')
    (tmp_path / "v.nmea").write_text("\n".join(nmea_lines(voyage(duration=600.0, every=5.0))))
    controller, terminal = os.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "bridge_node", "replay", str(tmp_path / "v.nmea"), "--config",
                             str(cfg), "--speed", "1", "--render", "none", "--json", "--out", str(tmp_path / "out")],
                            stdin=terminal, stderr=terminal, stdout=subprocess.PIPE, cwd=REPO, text=True)
    os.close(terminal)
    shown = b""
    deadline = time.monotonic() + 120.0
    while b"q quit" not in shown and time.monotonic() < deadline:  # the keys help: keys are read now
        shown += os.read(controller, 4096)
    os.write(controller, b"F")  # ten minutes ahead: past the end of this 10 min log
    drain = threading.Thread(target=_drain, args=(controller,), daemon=True)  # the progress bar goes on
    drain.start()
    out, _ = proc.communicate(timeout=120.0)
    drain.join(5.0)
    summary = json.loads(out)
    assert proc.returncode == 0
    assert summary["steps"] == 1200 and summary["duration_s"] == 600.0  # ran ahead to the end
    assert summary["pace"] == 1.0
