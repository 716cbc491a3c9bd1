"""``icebridge replay`` of track logs: NMEA 0183 (plain, OpenCPN VDR CSV, the node's own
log), AIS (two vessels, one picked by MMSI), CSV and GPX logs of one synthetic voyage drive
the ship along the logged positions and break the ice; bad data is reported, never fatal;
user mistakes are one-line errors."""
import csv
import time
import json
import math

import numpy as np
import pytest
from conftest import free_port
from replay_logs import (
    T0,
    Fix,
    ais_lines,
    ais_static,
    csv_text,
    gpx_text,
    nmea_lines,
    replayed_errors,
    sentence,
    voyage,
)

from bridge_node.commands.cli import main

MMSI, OTHER = 230000001, 230000002


@pytest.fixture(scope="module")
def exercise(tmp_path_factory):
    """A config: a 400 m x 600 m field of 0.3 m ice in 50 m tiles, templates cached for the
    module, instruments on a free UDP port, the state stream on free ports."""
    folder = tmp_path_factory.mktemp("replay")
    path = folder / "exercise.toml"
    path.write_text(f'[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 600.0\nthickness = 0.3\n'
                    f'[fracture]\ntile_side = 50.0\n[paths]\ncache_dir = "{folder / "tiles"}"\n'
                    f'session_dir = "{folder / "sessions"}"\n[stream]\npublish = "tcp://127.0.0.1:{free_port()}"\n'
                    f'snapshot = "tcp://127.0.0.1:{free_port()}"\n'
                    f'[[links]]\nname = "instruments"\ntype = "nmea0183"\nudp_port = {free_port()}\n')
    return path


def replay(capsys, config, out, *args) -> tuple[int, dict | None, str]:
    """Run ``icebridge replay`` in this process: exit status, its JSON summary, stderr."""
    code = main(["replay", *map(str, args), "--config", str(config), "--render", "none", "--json",
                 "--out", str(out)])
    captured = capsys.readouterr()
    return code, json.loads(captured.out) if code == 0 and captured.out.strip() else None, captured.err


LOGS = {
    "nmea": ("voyage.nmea", lambda f: "\n".join(nmea_lines(f)), ()),
    "vdr": ("vdr.csv", lambda f: "\n".join(nmea_lines(f, "vdr")), ()),
    "node": ("nmea.log", lambda f: "\n".join(nmea_lines(f, "unix")), ()),
    "ais": ("ais.log", lambda f: "\n".join(ais_lines({MMSI: ("ICE TEST", f), OTHER: ("OTHER", voyage(
        start=(300.0, -200.0), heading0=90.0, rate_deg_s=0.0))})), ("--mmsi", MMSI)),
    "csv": ("track.csv", csv_text, ()),
    "gpx": ("track.gpx", gpx_text, ()),
}


@pytest.mark.parametrize("kind", LOGS)
def test_logs_of_one_voyage_drive_the_ship_along_it_and_break_ice(capsys, tmp_path, exercise, kind):
    name, write, extra = LOGS[kind]
    fixes = voyage()
    (tmp_path / name).write_text(write(fixes) + "\n")
    code, summary, err = replay(capsys, exercise, tmp_path / "out", tmp_path / name, "--max", *extra)
    assert code == 0, err
    errors = replayed_errors((tmp_path / "out" / "replay_track.csv").read_text(), fixes)
    assert len(errors) == len(fixes) - 1 and errors.max() < 1.0  # every logged point but the start
    assert summary["cells_broken"]["by_hull"] > 500  # a channel through the ice along the track
    assert summary["time_s"]["level_ice"] > 60.0
    assert summary["distance_m"] == pytest.approx(6.0 * 1852.0 / 3600.0 * 120.0, rel=0.01)
    assert summary["input"]["heading_from"] == {"gpx": "track", "csv": "heading"}.get(kind, "heading")
    assert summary["input"]["bad_data"] == {}
    if kind == "ais":
        assert summary["input"]["vessel"] == f"{MMSI} ICE TEST"
    assert (tmp_path / "out" / "replay.png").stat().st_size > 10_000


def test_an_ais_log_of_two_vessels_lists_them_when_none_is_picked(capsys, tmp_path, exercise):
    fixes, other = voyage(), voyage(duration=60.0, start=(300.0, -200.0))
    (tmp_path / "ais.log").write_text("\n".join(ais_lines({MMSI: ("ICE TEST", fixes), OTHER: ("OTHER", other)})))
    code, summary, _ = replay(capsys, exercise, tmp_path / "out", tmp_path / "ais.log")
    assert code == 0
    vessels = {v["mmsi"]: v for v in summary["vessels"]}
    assert set(vessels) == {MMSI, OTHER}
    assert vessels[MMSI]["name"] == "ICE TEST" and vessels[OTHER]["name"] == "OTHER"  # from 2-part type 5
    assert vessels[MMSI]["position_reports"] == len(fixes) and vessels[OTHER]["position_reports"] == len(other)
    assert vessels[MMSI]["messages"] == {"1": len(fixes), "5": 1}
    assert vessels[MMSI]["first"] == T0 - 1.0 and vessels[MMSI]["last"] == fixes[-1].t
    assert vessels[OTHER]["last"] == other[-1].t
    assert vessels[MMSI]["length_m"] == 150.0


def test_bad_data_is_counted_listed_and_never_fatal(capsys, tmp_path, exercise):
    fixes = voyage(duration=160.0)
    gap = [f for f in fixes if not T0 + 60.0 < f.t < T0 + 100.0]  # 40 s without a fix
    jump = gap.index(next(f for f in gap if f.t == T0 + 120.0))
    f = gap[jump]
    gap[jump] = Fix(f.t, f.lat + 0.02, f.lon, f.heading, f.course, f.speed)  # 2.2 km away: 4300 kn
    lines = nmea_lines(gap)
    lines[10:10] = ["garbage that is no sentence", "$GPRMC,123", sentence("GPRMC,1,2")[:-2] + "00",
                    sentence("GPGGA,230000.00,7400.000,N,02000.000,E,0,00,,,M,,M,,")]  # no fix
    lines += ais_static(MMSI, "ICE TEST", T0, 1)[:1]  # a two-part message cut after its first part
    (tmp_path / "bad.nmea").write_text("\n".join(lines) + "\n")
    code, summary, err = replay(capsys, exercise, tmp_path / "out", tmp_path / "bad.nmea", "--max")
    assert code == 0, err
    report = summary["input"]
    assert report["bad_data"] == {"no_sentence": 1, "no_checksum": 1, "bad_checksum": 1, "no_fix": 1,
                                  "incomplete_multipart": 1}
    assert report["gaps_held"] == []  # 40 s at 6 kn, 123 m: interpolated (issue 30)
    [skipped] = report["jumps_skipped"]
    assert skipped["at"] == "2023-11-14 22:15:20" and skipped["distance_m"] > 2000.0 and skipped["speed_kn"] > 1000
    rows = list(csv.DictReader((tmp_path / "out" / "replay_track.csv").open()))
    inside = [float(r["sog_kn"]) for r in rows if T0 + 60.0 <= float(r["time"]) < T0 + 100.0]
    assert len(inside) == 80 and min(inside) > 5.9 and max(inside) < 6.05  # moving through the gap
    good = [x for x in gap if x is not gap[jump]]
    errors = replayed_errors((tmp_path / "out" / "replay_track.csv").read_text(), good)
    assert errors.max() < 1.0  # every good fix still met


def test_a_ten_km_track_replays_at_max_and_its_leaving_the_field_is_reported(capsys, tmp_path, exercise):
    fixes = voyage(duration=972.0, every=10.0, speed_kn=20.0, rate_deg_s=0.0)  # 10 km due north
    (tmp_path / "long.csv").write_text(csv_text(fixes))
    code, summary, err = replay(capsys, exercise, tmp_path / "out", tmp_path / "long.csv", "--max",
                                "--field-origin", "74.0009,19.99")  # the first fix 100 m south of the field
    assert code == 0, err
    assert summary["distance_m"] == pytest.approx(10_000.0, rel=0.01)
    assert summary["input"]["field_origin"] == {"latitude_deg": 74.0009, "longitude_deg": 19.99,
                                                "placed": "--field-origin"}
    assert summary["input"]["heading_from"] == "heading"
    # the field's 600 m are crossed somewhere along the 10 km: ice before, open water after
    assert summary["time_s"]["open_water"] > 600.0 and summary["cells_broken"]["by_hull"] > 0
    assert summary["off_field"] and summary["off_field"][-1]["to"] == summary["logged_end"]
    first = next(csv.DictReader((tmp_path / "out" / "replay_track.csv").open()))
    assert float(first["north_m"]) == pytest.approx(-100.5 + 5.1, abs=0.5)  # 0.5 s after the start at 20 kn
    assert float(first["east_m"]) == pytest.approx(307.8, abs=0.5)  # 0.01 deg east of the pinned corner


def test_from_and_to_cut_the_track(capsys, tmp_path, exercise):
    (tmp_path / "v.nmea").write_text("\n".join(nmea_lines(voyage())))
    code, summary, _ = replay(capsys, exercise, tmp_path / "out", tmp_path / "v.nmea", "--speed", "1000",
                              "--from", "30", "--to", "22:14:50")
    assert code == 0
    assert summary["logged_start"] == "2023-11-14 22:13:50" and summary["logged_end"] == "2023-11-14 22:14:50"
    assert summary["duration_s"] == 60.0 and summary["pace"] == 1000.0


@pytest.mark.parametrize("content, what", [
    ("", "empty file"),
    ("no log here\njust text\n", "not a log this command reads"),
    ("time,x,y\n1,2,3\n", "not a log this command reads"),
    (sentence("GPRMC,120000.00,V,,,,,,,141123,,,N") + "\n", "no position in it"),
])
def test_a_file_without_a_usable_track_is_a_one_line_error(capsys, tmp_path, exercise, content, what):
    (tmp_path / "log.txt").write_text(content)
    code, _, err = replay(capsys, exercise, tmp_path / "out", tmp_path / "log.txt", "--max")
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"{tmp_path / 'log.txt'}: " in err and what in err and "looked for" in err
    assert "no_fix" not in content or err.endswith("; bad data: 1 no_fix\n")


@pytest.mark.parametrize("args, message", [
    (["--speed", "0.5"], "--speed 0.5: outside the allowed range [1, 1000]"),
    (["--speed", "5000"], "--speed 5000.0: outside the allowed range [1, 1000]"),
    (["--speed", "10", "--max"], "argument --max: not allowed with argument --speed"),
    (["--from", "later"], "--from 'later': not a time"),
    (["--from", "500"], "--from '500': outside the log"),
    (["--from", "15", "--to", "5"], "--from '15' is not before --to '5'"),
    (["--field-origin", "74"], "--field-origin '74': give LAT,LON"),
    (["--field-origin", "95,20"], "--field-origin '95,20': latitude must be within [-89, 89]"),
    (["--mmsi", "12"], "--mmsi 12: an MMSI has nine digits"),
    (["--mmsi", "999999999"], "--mmsi 999999999: no position reports of that vessel"),
    (["--columns", "when=t"], "--columns 'when=t': bad entry 'when=t'"),
])
def test_bad_options_are_one_line_errors(capsys, tmp_path, exercise, args, message):
    (tmp_path / "v.nmea").write_text("\n".join(nmea_lines(voyage(duration=20.0))))
    try:
        code, _, err = replay(capsys, exercise, tmp_path / "out", tmp_path / "v.nmea", *args)
    except SystemExit as exc:  # argparse's own usage errors
        code, err = exc.code, capsys.readouterr().err.splitlines()[-1] + "\n"
    assert code == 2 and err.count("\n") == 1 and message in err and "Traceback" not in err, err


def test_csv_columns_by_mapping(capsys, tmp_path, exercise):
    fixes = voyage(duration=40.0)
    rows = ["stamp;y;x;v"] + [f"{f.t - T0:.1f};{f.lat:.8f};{f.lon:.8f};{f.speed * 1852 / 3600:.3f}" for f in fixes]
    (tmp_path / "odd.csv").write_text("\n".join(rows))
    code, summary, err = replay(capsys, exercise, tmp_path / "out", tmp_path / "odd.csv", "--max",
                                "--columns", "time=stamp,lat=y,lon=x,speed=v,speed_unit=m/s")
    assert code == 0, err
    assert summary["logged_start"] == "0.0 s" and summary["duration_s"] == 40.0  # times from the start
    assert summary["input"]["heading_from"] == "track"
    errors = replayed_errors((tmp_path / "out" / "replay_track.csv").read_text(),
                             [Fix(f.t - T0, f.lat, f.lon, 0, 0, 0) for f in fixes])
    assert errors.max() < 1.0
    speed = np.array([float(r["sog_kn"]) for r in csv.DictReader((tmp_path / "out" / "replay_track.csv").open())])
    assert np.all(np.abs(speed - 6.0) < 0.05) and math.isfinite(speed.sum())


def test_replayed_sentences_carry_the_logged_time(capsys, tmp_path, exercise):
    """A chart plotter watching a replay sees the voyage's own UTC in RMC, not today's."""
    import re
    import socket

    port = int(re.search(r"udp_port = (\d+)", exercise.read_text()).group(1))
    fixes = voyage()
    (tmp_path / "voyage.nmea").write_text("\n".join(nmea_lines(fixes)) + "\n")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listener:
        listener.bind(("127.0.0.1", port))
        listener.settimeout(0.5)
        code, _, err = replay(capsys, exercise, tmp_path / "out", tmp_path / "voyage.nmea", "--max")
        assert code == 0, err
        received = []
        try:
            while True:
                received += listener.recv(65536).decode("ascii").split("\r\n")
        except TimeoutError:
            pass
    rmc = [s.split(",") for s in received if s[3:6] == "RMC"]
    assert rmc
    logged = {time.strftime("%d%m%y", time.gmtime(f.t)) for f in fixes}
    assert {r[9] for r in rmc} <= logged  # the log's date (2023-11-14), not the wall clock's
    first = time.strftime("%H%M%S", time.gmtime(fixes[0].t))
    last = time.strftime("%H%M%S", time.gmtime(fixes[-1].t + 1))
    assert all(first <= r[1][:6] <= last for r in rmc)


def test_the_other_vessels_of_a_replayed_ais_log_go_out_as_aivdm_on_its_clock(capsys, tmp_path, exercise):
    """Replaying one vessel of an AIS log, the other goes out as !AIVDM where the log had
    it at each report's logged UTC second, at the class A interval, named by its type 5."""
    import re
    import socket
    import threading

    from pyais import decode

    port = int(re.search(r"udp_port = (\d+)", exercise.read_text()).group(1))
    config = tmp_path / "ais.toml"
    quiet = "".join(f"{k} = 0\n" for k in ("RMC", "GGA", "VTG", "ZDA", "HDT", "ROT", "RSA", "RPM", "VBW", "XDR"))
    config.write_text(exercise.read_text() + f'[links.rates]\n{quiet}[links.ais]\nmmsi = 257123450\nto_bow = 20\n'
                      'to_stern = 130\nto_port = 10\nto_starboard = 12\n')
    other = voyage(start=(300.0, -200.0), heading0=90.0, rate_deg_s=0.0)  # due east at 6 kn
    (tmp_path / "ais.log").write_text("\n".join(ais_lines({MMSI: ("ICE TEST", voyage()), OTHER: ("OTHER", other)})))
    received, done = [], threading.Event()

    def listen(listener: socket.socket) -> None:  # read while the replay runs: --max outpaces a socket buffer
        while True:  # until the replay has ended and nothing more is waiting
            try:
                received.extend(listener.recv(65536).decode("ascii").split("\r\n"))
            except TimeoutError:
                if done.is_set():
                    return

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listener:
        listener.bind(("127.0.0.1", port))
        listener.settimeout(0.2)
        reader = threading.Thread(target=listen, args=(listener,))
        reader.start()
        try:
            code, _, err = replay(capsys, config, tmp_path / "out", tmp_path / "ais.log", "--mmsi", MMSI, "--max")
        finally:
            done.set()
            reader.join()
    assert code == 0, err
    vdm = [s for s in received if s.startswith("!AIVDM")]
    reports = [decode(s).asdict() for s in vdm if s.split(",")[1] == "1"]
    assert {r["mmsi"] for r in reports} == {OTHER} and 11 <= len(reports) <= 13  # every 10 s of 120 s
    lon = np.array([f.lon for f in other])
    for r in reports:
        assert r["lat"] == pytest.approx(other[0].lat, abs=1e-4 / 60)
        assert r["speed"] == pytest.approx(6.0, abs=0.1) and r["course"] == pytest.approx(90.0, abs=0.1)
        at = np.interp(r["lon"], lon, [f.t for f in other])  # when the log had it there
        assert -0.6 <= (at - r["second"] + 30.0) % 60.0 - 30.0 <= 1.1  # at that UTC second (0.5 s steps)
    assert decode(*[s for s in vdm if s.split(",")[1] == "2"][:2]).asdict()["shipname"] == "OTHER"
