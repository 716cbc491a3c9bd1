"""Replay input that escaped or hung (issue 30, item 3): every case is a counted and
skipped line where the reader counts bad data, or one ``UserError`` naming the file and
what is wrong; never a traceback, never a value out of range taken in, never a long wait."""
import math
from pathlib import Path

import pytest
from replay_logs import (
    T0,
    ais_lines,
    ais_static,
    csv_text,
    gpx_text,
    nmea_lines,
    sentence,
    tick_log,
    truncated_ais,
    voyage,
)

from bridge_node.links.record_reader import MAX_RECORD_TICKS, check_tick_count, read_modbus_csv, read_nmea_log
from bridge_node.common.errors import UserError
from bridge_node.exercise.tick_record import TICKS_FILE, read_ticks
from bridge_node.replay.inputs import MAX_SPAN_S, check_span, load_inputs
from bridge_node.replay.settings import ReplaySettings
from bridge_node.replay.track import TrackLog, TrackPath, clean_for

MMSI = 230000001


def load(tmp_path: Path, name: str, text: str) -> TrackLog:
    """``load_inputs`` of one file holding ``text``."""
    (tmp_path / name).write_text(text)
    return load_inputs([str(tmp_path / name)], None, {}, 0.05)


def nmea_with(kind: str, body: str, every: int = 1) -> str:
    """A plain capture of a 20 s voyage with every ``every``-th sentence of ``kind``
    (e.g. ``HDT``) replaced by the sentence of ``body``."""
    lines, k = nmea_lines(voyage(duration=20.0)), 0
    for i, line in enumerate(lines):
        if line[3:6] == kind:
            if k % every == 0:
                lines[i] = sentence(body)
            k += 1
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("body", ["HEHDT,99999,T", "HEHDT,-9999,T", "HEHDT,360.1,T", "HEHDT,nan,T",
                                  "HETHS,99999,A", "HEHDG,99999,,,1.0,E", "HEHDG,10.0,,,-9999,E"])
def test_an_out_of_range_heading_is_a_counted_bad_field_and_the_track_stays_in_range(tmp_path, body):
    log = load(tmp_path, "voyage.nmea", nmea_with("HDT", body, every=2))
    assert log.bad["bad_field"] == 6  # 11 headings, every other one bad
    assert len(log.heading) == 5 and all(0.0 <= h < 2.0 * math.pi for _, h in log.heading)
    track = clean_for(log, ReplaySettings())
    path = TrackPath(track, (track.lat[0], track.lon[0]), 30.0)
    poses = [path.pose(t, 0.5) for t in track.t[1:]]
    assert all(0.0 <= p.heading < 2.0 * math.pi and abs(p.yaw_rate) < 0.1 for p in poses)


@pytest.mark.parametrize("body", ["GPZDA,120000.00,01,01,99999999999,00,00", "GPZDA,120000.00,99,99,2023,00,00",
                                  "GPRMC,999999999999999999999,A,7400.000,N,02000.000,E,6.0,0.0,141123,,,A",
                                  "GPRMC,221320.00,A,7400.000,N,02000.000,E,6.0,0.0,999999,,,A"])
def test_a_huge_time_or_date_field_is_a_counted_bad_field(tmp_path, body):
    text = sentence(body) + "\n" + nmea_with("XXX", "")
    log = load(tmp_path, "voyage.nmea", text)
    assert log.bad["bad_field"] == 1 and log.read["RMC"] == 11
    assert all(math.isfinite(t) for t, _, _ in log.fixes)


@pytest.mark.parametrize("chars", [0, 8, 12, 16, 20])
def test_an_ais_message_missing_fields_is_counted(tmp_path, chars):
    fixes = voyage(duration=20.0)
    lines = ais_lines({MMSI: ("ICE TEST", fixes)})
    lines[3] = truncated_ais(lines[3], chars)
    static = ais_static(MMSI + 1, "SHORT", T0, 2)
    lines += [static[0], truncated_ais(static[1], 0)]  # a type 5 without its dimensions
    log = load(tmp_path, "ais.log", "\n".join(lines) + "\n")
    bad = log.bad["ais_no_position"] + log.bad["ais_undecodable"]
    assert bad + log.read["position report"] == len(fixes) and bad <= 1
    assert all(0.0 <= h < 2.0 * math.pi for _, h in log.heading)
    assert all(0.0 <= s < 110.0 for _, s in log.speed)


def test_a_csv_field_over_the_csv_limit_is_a_bad_row(tmp_path):
    rows = csv_text(voyage(duration=20.0)).splitlines()
    rows.insert(3, f"{'x' * 140_000},74.0,20.0,0.0,6.0")
    rows.insert(5, f'"{"y" * 140_000}",74.0,20.0,0.0,6.0')
    log = load(tmp_path, "track.csv", "\n".join(rows) + "\n")
    assert log.bad["bad_row"] == 2 and log.read["csv row"] == 11


def test_a_csv_row_with_a_speed_out_of_range_is_a_bad_row(tmp_path):
    rows = csv_text(voyage(duration=20.0)).splitlines()
    rows[2] = rows[2].rsplit(",", 1)[0] + ",-5.0"
    rows[3] = rows[3].rsplit(",", 1)[0] + ",1e300"
    log = load(tmp_path, "track.csv", "\n".join(rows) + "\n")
    assert log.bad["bad_row"] == 2 and all(0.0 <= s <= 600.0 for _, s in log.speed)


@pytest.mark.parametrize("lat, lon", [("inf", "20.0"), ("-1e400", "20.0"), ("nan", "20.0"), ("95.0", "20.0"),
                                      ("74.0", "inf"), ("74.0", "1e308"), ("74.0", "-181.0")])
def test_a_gpx_point_off_the_earth_is_a_bad_point(tmp_path, lat, lon):
    text = gpx_text(voyage(duration=20.0)).replace('lat="74.00000000" lon="20.00000000"',
                                                   f'lat="{lat}" lon="{lon}"', 1)
    assert f'lat="{lat}"' in text
    log = load(tmp_path, "track.gpx", text)
    assert log.bad["bad_point"] == 1 and log.read["gpx point"] == 10
    track = clean_for(log, ReplaySettings())
    assert all(math.isfinite(x) for x in (*track.lat, *track.lon))


@pytest.mark.parametrize("offset", ["+24:00", "-24:00", "+99:59"])
def test_a_gpx_time_zone_offset_of_a_day_or_more_is_a_bad_point(tmp_path, offset):
    text = gpx_text(voyage(duration=20.0)).replace("Z</time>", f"{offset}</time>", 1)
    log = load(tmp_path, "track.gpx", text)
    assert log.bad["bad_point"] == 1 and log.read["gpx point"] == 10


def ticks_folder(tmp_path: Path, period: str, ticks: list[str]) -> Path:
    """A session folder holding only a tick log."""
    (tmp_path / TICKS_FILE).write_text(tick_log(period, ticks))
    return tmp_path


@pytest.mark.parametrize("period", ["nan", "inf", "-inf", "0", "0.0", "-0.02", "1e-300", "1e300", "x"])
def test_a_tick_log_period_that_is_no_step_is_refused_naming_the_file(tmp_path, period):
    folder = ticks_folder(tmp_path, period, ["0 100.0 1700000000.0 0 0 0"])
    with pytest.raises(ValueError, match="period_s"):
        read_ticks(folder / TICKS_FILE)
    with pytest.raises(UserError, match=rf"{TICKS_FILE}: its period_s"):
        load_inputs([str(folder)], None, {}, 0.05)


def test_tick_lines_out_of_range_are_malformed_and_never_parsed_whole(tmp_path):
    bad = ["9" * 4000 + " 100.0 1700000000.0 0 0 0", "-1 100.0 1700000000.0 0 0 0",
           "1 nan 1700000000.0 0 0 0", "1 100.0 inf 0 0 0", "1 100.0 1700000000.0 99999999999999999999 0 0",
           "1 100.0 1700000000.0 -5 0 0", "1 100.0 1700000000.0 0 0"]
    folder = ticks_folder(tmp_path, "0.05", ["0 100.0 1700000000.0 0 0 0", *bad * 200])
    period, ticks, counts = read_ticks(folder / TICKS_FILE)  # (a 4000-digit step number is refused by length)
    assert period == 0.05 and len(ticks) == 1 and counts["malformed"] == len(bad) * 200


def test_a_modbus_record_without_its_columns_is_refused_naming_the_file(tmp_path):
    (tmp_path / "modbus.csv").write_text("time,link,op,table,address,raw,value\n1700000000.0,m,read,hr,1,2,3\n")
    with pytest.raises(UserError, match=r"modbus\.csv: not a Modbus record: its header lacks unix_time"):
        load_inputs([str(tmp_path)], None, {}, 0.05)  # a folder: its record files by name


def test_modbus_rows_out_of_range_are_malformed(tmp_path):
    header = "unix_time,link,op,table,address,raw,value\n"
    rows = ["nan,m,read,hr,1,2,3", "inf,m,read,hr,1,2,3", "1700000000.0,m,read,hr,x,2,3",
            "1700000000.0,m,read,hr,1,99999999999,3", f'1700000000.0,m,read,hr,1,2,"{"z" * 140_000}"',
            "1700000000.0,m,read,hr,1,2,3"]
    (tmp_path / "modbus.csv").write_text(header + "\n".join(rows) + "\n")
    out, counts = read_modbus_csv(tmp_path / "modbus.csv")
    assert len(out) == 1 and counts["malformed"] == 5


@pytest.mark.parametrize("when", ["inf", "-inf", "nan", "1e300", "-1"])
def test_a_record_line_whose_time_is_out_of_range_is_malformed_not_an_overflow(tmp_path, when):
    (tmp_path / "nmea.log").write_text(f"1700000000.0 gps rx $GPHDT,1.0,T*00\n{when} gps rx $GPHDT,1.0,T*00\n")
    records, counts = read_nmea_log(tmp_path / "nmea.log")
    assert len(records) == 1 and counts["malformed"] == 1
    (tmp_path / "modbus.csv").write_text("unix_time,link,op,table,address,raw,value\n")
    session = load_inputs([str(tmp_path)], None, {}, 0.05)  # no tick log: ticks made from the times
    assert len(session.ticks) == 1 and session.bad == {"nmea.log malformed": 1}


def test_a_record_without_a_tick_log_spanning_too_many_ticks_is_refused():
    assert check_tick_count(Path("rec"), [1.7e9, 1.7e9 + 10.0], 0.05) == 201
    with pytest.raises(UserError, match=r"rec: the record's lines span 300000000 s"):
        check_tick_count(Path("rec"), [1.7e9, 2.0e9], 0.05)
    assert MAX_RECORD_TICKS * 0.05 < 30 * 86400.0


def test_a_track_longer_than_thirty_days_is_refused_naming_its_span_and_from_to():
    assert check_span(["a.csv"], T0, T0 + 3600.0, 0.5) == 7200
    with pytest.raises(UserError, match=r"a\.csv: the track spans 31 days \(from 2023-11-14 22:13:20 to "
                                        r"2023-12-15 22:13:20 UTC\).*--from and --to"):
        check_span(["a.csv"], T0, T0 + 31 * 86400.0, 0.5)
    with pytest.raises(UserError, match="--from and --to"):
        check_span(["a.csv"], 0.0, 1e300, 0.5, absolute=False)
    assert check_span(["a.csv"], T0, T0 + MAX_SPAN_S, 0.5) == 5_184_000
