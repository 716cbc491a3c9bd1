"""Replay of real logs as they come (issue 30, items 1 and 2): sparse AIS tracks (one
report a minute, 3 minutes at anchor) replay as a ship moving between its fixes at the
logged speed, holding only gaps that are long for its speed or that the data contradicts;
CSV tracks with elapsed-seconds time columns replay without ``--columns``, and one with
positions but no time says which ``--columns`` would fix it.

Tracks are built and stepped directly (``load_inputs``, ``clean_for``, ``TrackPath``,
``TrackSource``), as ``icebridge replay`` does; one end-to-end run checks the ice."""
import csv
import json
import math

import numpy as np
import pytest
from conftest import free_port
from pydantic import ValidationError
from replay_logs import KNOT, T0, Fix, ais_lines, at_anchor, replayed_errors, shifted, voyage

from bridge_node.commands.cli import main
from bridge_node.common.errors import UserError
from bridge_node.replay.csv_track import parse_mapping
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.settings import ReplaySettings
from bridge_node.replay.track import Track, TrackPath, TrackSource, clean_for
from bridge_node.reports.replay import gap_summary

MMSI = 230000001
STEP = 0.5  # s, the default replay step
# AIS gives positions to 1/10 000 minute (0.19 m of latitude): two fixes a minute apart may be
# 0.37 m off, 0.012 kn, and a cubic's peak speed moves 1.5 times a chord's error: 0.02 kn. A cubic
# through a 15 deg arc (0.25 deg/s for a minute) runs 0.01 % off the circle's speed. So a replayed
# step may exceed the logged speed by 0.05 kn at most; the old replay jumped 185 m in one step.
SPEED_TOLERANCE = 0.05 * KNOT


def sparse_ais(tmp_path, fixes: list[Fix]) -> Track:
    """The fixes as a one-vessel AIS log (pyais), read and cleaned with the default settings."""
    path = tmp_path / "sparse.ais"
    path.write_text("\n".join(ais_lines({MMSI: ("SPARSE", fixes)})) + "\n")
    track = clean_for(load_inputs([str(path)], None, {}, 0.1), ReplaySettings())
    assert track is not None and len(track.t) == len(fixes)
    return track


def stepped(track: Track) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step a replay source along the track as the replay loop does: logged time at the end
    of each step (s), the poses' north and east (m), heading (rad) and speed (m/s) as
    rows, and each step's displacement over the step (m/s)."""
    origin = (float(track.lat[0]), float(track.lon[0]))
    source = TrackSource(TrackPath(track, origin, ReplaySettings().max_gap_s), track.start, track.end, STEP)
    t = np.array([source.logged_time(k) + source.dt for k in range(source.steps)])
    poses = [source.inputs(k)[0].kinematic for k in range(source.steps)]
    rows = np.array([(p.north, p.east, p.heading, math.hypot(p.surge, p.sway)) for p in poses])
    start = source.path.position(track.start)
    moved = np.hypot(*np.diff(np.vstack([start, rows[:, :2]]), axis=0).T) / STEP
    return t, rows, moved


def test_one_report_a_minute_replays_moving_between_fixes_at_the_logged_speed(tmp_path):
    fixes = voyage(duration=900.0, every=60.0, speed_kn=6.0, turn_after=300.0, rate_deg_s=0.25)
    track = sparse_ais(tmp_path, fixes)
    assert track.gaps == [] and len(track.bridged) == len(fixes) - 1  # every minute a gap, none held
    assert track.heading_source == "heading"
    t, rows, moved = stepped(track)
    logged_distance = 6.0 * KNOT * 900.0  # the logged speed over the logged time: the voyage's own length
    chords = sum(math.hypot(*(np.subtract(*track_ne(track, i)))) for i in range(len(fixes) - 1))
    distance = moved.sum() * STEP
    assert distance == pytest.approx(logged_distance, rel=0.02)
    assert distance >= chords  # a curve through the fixes, not the straight legs
    assert moved.max() <= 6.0 * KNOT + SPEED_TOLERANCE and rows[:, 3].max() <= 6.0 * KNOT + SPEED_TOLERANCE
    assert moved.min() >= 6.0 * KNOT - SPEED_TOLERANCE  # never sits still: moving between every two fixes
    at = np.searchsorted(t, [f.t for f in fixes[1:]])
    ne = np.array([geodetic(track, f) for f in fixes[1:]])
    assert np.hypot(*(rows[at, :2] - ne).T).max() < 0.5  # through every fix
    fine = {round(f.t): f for f in voyage(duration=900.0, every=1.0, turn_after=300.0, rate_deg_s=0.25)}
    truth = np.radians([fine[round(x)].heading for x in t[::10]])
    off = np.degrees(np.abs((rows[::10, 2] - truth + math.pi) % (2.0 * math.pi) - math.pi))
    assert off.max() < 1.0  # the heading between reports follows the turn (AIS heading: whole degrees)


def geodetic(track: Track, f: Fix) -> tuple[float, float]:
    """A logged fix's north and east (m) from the track's first fix."""
    from sim_core.frames.geodesy import geodetic_to_local

    return geodetic_to_local(math.radians(f.lat), math.radians(f.lon), track.lat[0], track.lon[0])


def track_ne(track: Track, i: int) -> tuple[tuple[float, float], tuple[float, float]]:
    """Fixes i and i + 1 of the track, north and east (m) from its first fix."""
    from sim_core.frames.geodesy import geodetic_to_local

    return tuple(geodetic_to_local(track.lat[j], track.lon[j], track.lat[0], track.lon[0]) for j in (i, i + 1))


def test_three_minutes_at_anchor_are_no_gap_to_hold(tmp_path):
    """Reports every 3 min at anchor: a 180 s gap at speed 0 is short for that speed."""
    track = sparse_ais(tmp_path, at_anchor(T0, 3600.0))
    assert track.gaps == [] and len(track.bridged) == 20
    _, rows, moved = stepped(track)
    assert moved.max() < 0.05 * KNOT  # swinging on the cable, not jumping
    assert np.ptp(rows[:, 0]) < 30.0 and np.ptp(rows[:, 1]) < 30.0


def test_a_gap_the_data_contradicts_and_a_long_one_are_held_and_listed(tmp_path):
    """The positions jump 400 m north between two reports a minute apart at 6 kn (185 m):
    impossible at the logged speed, though under the 40 kn of a skipped jump. Later the log
    is silent for 15 min: 2.8 km at 6 kn, long for that speed."""
    fixes = voyage(duration=1800.0, every=60.0, speed_kn=6.0, turn_after=2000.0)
    fixes = shifted(fixes, T0 + 300.0, 400.0)
    fixes = [f for f in fixes if not T0 + 900.0 < f.t < T0 + 1800.0]  # 15 min without a report
    track = sparse_ais(tmp_path, fixes)
    assert [(g.start - T0, g.end - T0) for g in track.gaps] == [(300.0, 360.0), (900.0, 1800.0)]
    assert track.gaps[0].reason.startswith("contradicted") and track.gaps[1].reason.startswith("long")
    assert len(track.bridged) == len(fixes) - 3 and track.jumps == []
    listed = gap_summary(track)
    assert listed["gaps_held"][0] == {"from": "2023-11-14 22:18:20", "to": "2023-11-14 22:19:20", "s": 60.0,
                                      "why": track.gaps[0].reason, "run_m": pytest.approx(585.0, abs=2.0)}
    assert listed["gaps_held"][1]["run_m"] == pytest.approx(6.0 * KNOT * 900.0, rel=0.01)
    assert "2778 m" in listed["gaps_held"][1]["why"]
    assert listed["gaps_interpolated"] == {"count": len(fixes) - 3, "s": 60.0 * (len(fixes) - 3)}
    t, rows, moved = stepped(track)
    for gap in track.gaps:
        inside = (t > gap.start + STEP) & (t < gap.end)
        assert inside.any() and moved[inside].max() == 0.0 and rows[inside, 3].max() == 0.0  # held
    outside = np.ones(len(t), bool)
    for gap in track.gaps:
        outside &= ~((t > gap.start) & (t <= gap.end + STEP))
    assert moved[outside].max() <= 6.0 * KNOT + SPEED_TOLERANCE and moved[outside].min() > 5.9 * KNOT


def test_the_gap_limits_are_settings_with_ranges(tmp_path):
    r = ReplaySettings()
    assert (r.max_gap_run_m, r.gap_speed_tolerance) == (1000.0, 0.25)
    for bad in ({"max_gap_run_m": -1.0}, {"max_gap_run_m": 1e6}, {"gap_speed_tolerance": 6.0}):
        with pytest.raises(ValidationError):
            ReplaySettings(**bad)
    fixes = voyage(duration=300.0, every=60.0, speed_kn=6.0)
    path = tmp_path / "sparse.ais"
    path.write_text("\n".join(ais_lines({MMSI: ("SPARSE", fixes)})))
    log = load_inputs([str(path)], None, {}, 0.1)
    held = clean_for(log, ReplaySettings(max_gap_run_m=150.0))  # 185 m a minute: every gap long
    assert len(held.gaps) == 5 and all(g.reason.startswith("long") for g in held.gaps)
    assert clean_for(log, ReplaySettings(max_gap_s=90.0)).bridged == []  # a minute apart: no gap at all


ELAPSED_HEADERS = ["t_s", "t", "time_s", "elapsed", "Elapsed (s)", "seconds", "sec", "t [s]"]


@pytest.mark.parametrize("name", ELAPSED_HEADERS)
def test_a_csv_with_elapsed_seconds_replays_without_columns(tmp_path, name):
    fixes = voyage(duration=120.0, every=10.0)
    rows = [f"{name},lat,lon,sog"] + [f"{f.t - T0:g},{f.lat:.8f},{f.lon:.8f},{f.speed:.1f}" for f in fixes]
    (tmp_path / "track.csv").write_text("\n".join(rows) + "\n")
    log = load_inputs([str(tmp_path / "track.csv")], None, {}, 0.1)
    assert not log.absolute and log.read == {"csv row": len(fixes)} and log.bad == {}
    track = clean_for(log, ReplaySettings())
    assert track.start == 0.0 and track.end == 120.0 and track.gaps == []
    t, rows_, moved = stepped(track)
    assert moved.sum() * STEP == pytest.approx(6.0 * KNOT * 120.0, rel=0.01)
    at = np.searchsorted(t, [f.t - T0 for f in fixes[1:]])
    ne = np.array([geodetic(track, f) for f in fixes[1:]])
    assert np.hypot(*(rows_[at, :2] - ne).T).max() < 0.5


@pytest.mark.parametrize("header, row, mapping, fix", [
    ("stamp,lat,lon,sog", "{t:g},{lat},{lon},6.0", "", "--columns time=stamp"),
    ("name,y,x", "ship,{lat},{lon}", "lat=y,lon=x", "--columns lat=y,lon=x,time=COLUMN"),
    ("stamp,lat,lon", "{t:g},{lat},{lon}", "time=when", "no column 'when' (--columns time=when)"),
])
def test_positions_without_a_time_column_say_so_and_show_the_columns_that_fix_it(tmp_path, header, row,
                                                                                  mapping, fix):
    fixes = voyage(duration=60.0, every=10.0)
    lines = [header] + [row.format(t=f.t - T0, lat=f"{f.lat:.8f}", lon=f"{f.lon:.8f}") for f in fixes]
    path = tmp_path / "no_time.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(UserError) as caught:
        load_inputs([str(path)], None, parse_mapping(mapping), 0.1)
    message = str(caught.value)
    assert message.startswith(f"{path}: no time column: found latitude in ") and fix in message
    assert "no position" not in message and "\n" not in message
    if fix.startswith("--columns time="):  # and the columns it shows do fix it
        log = load_inputs([str(path)], None, parse_mapping(fix.split()[1]), 0.1)
        assert len(log.fixes) == len(fixes) and log.bad == {}


@pytest.fixture
def ice_exercise(tmp_path):
    """A 400 m x 600 m field of 0.3 m ice in 50 m tiles, the ship starting inside the ice."""
    path = tmp_path / "exercise.toml"
    path.write_text(f'[exercise]\nstart_north = 20.0\n[ship]\nname = "polar_cargo"\n'
                    f'[ice_field]\nwidth = 400.0\nheight = 600.0\nthickness = 0.3\n'
                    f'[fracture]\ntile_side = 50.0\n[paths]\ncache_dir = "{tmp_path / "tiles"}"\n'
                    f'session_dir = "{tmp_path / "sessions"}"\n[stream]\npublish = "tcp://127.0.0.1:{free_port()}"\n'
                    f'snapshot = "tcp://127.0.0.1:{free_port()}"\n')
    return path


def test_a_sparse_ais_log_replays_breaking_ice_all_along_its_track(capsys, tmp_path, ice_exercise):
    """``icebridge replay`` of one report a minute: the ship runs at the logged speed the
    whole way, in level ice (the bow always in unbroken ice), breaking a channel."""
    fixes = voyage(duration=240.0, every=60.0, speed_kn=4.0, turn_after=120.0, rate_deg_s=0.2)
    (tmp_path / "sparse.ais").write_text("\n".join(ais_lines({MMSI: ("SPARSE", fixes)})) + "\n")
    code = main(["replay", str(tmp_path / "sparse.ais"), "--max", "--render", "none", "--json",
                 "--config", str(ice_exercise), "--out", str(tmp_path / "out")])
    out = capsys.readouterr()
    assert code == 0, out.err
    summary = json.loads(out.out)
    assert summary["input"]["gaps_held"] == [] and summary["duration_s"] == 240.0
    assert summary["distance_m"] == pytest.approx(4.0 * KNOT * 240.0, rel=0.02)
    # the bow in unbroken ice all along (the old replay, waiting at each fix: 16 s of 240)
    assert summary["time_s"].get("level_ice", 0.0) >= 0.99 * 240.0
    rows = list(csv.DictReader((tmp_path / "out" / "replay_track.csv").open()))
    sog = np.array([float(r["sog_kn"]) for r in rows])
    assert sog.min() > 3.9 and sog.max() <= 4.05
    assert {r["ice"] for r in rows if float(r["time"]) > T0 + 2.0} == {"level_ice"}  # after the first steps
    assert summary["cells_broken"]["by_hull"] > 1000  # a channel of 490 m
    errors = replayed_errors((tmp_path / "out" / "replay_track.csv").read_text(), fixes)
    assert errors.max() < 1.0
