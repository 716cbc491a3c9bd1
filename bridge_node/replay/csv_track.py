"""CSV tracks: one fix per row, columns found by their common names or a ``--columns``
mapping, and GPX tracks.

Columns (case, spaces and a unit in brackets do not matter): time (``time``, ``timestamp``,
``datetime``, ``utc``, ``BaseDateTime``, ...; unix seconds, ISO 8601, or seconds from the
start), failing that elapsed seconds (``t``, ``t_s``, ``time_s``, ``elapsed``, ``elapsed_s``,
``seconds``, ``sec``, ``t (s)``), an optional separate ``date`` (not with elapsed seconds), ``lat``/``latitude`` and ``lon``/``lng``/``longitude``
(decimal degrees), ``heading``/``hdg``, ``cog``/``course``, ``sog``/``speed`` (knots unless
the column name says m/s or km/h) and ``mmsi`` (several vessels in one file: pick one with
``--mmsi``). ``--columns time=ts,lat=y,lon=x,speed=v,speed_unit=m/s`` names others.
"""
from __future__ import annotations

import csv
import datetime as dt
import math
import re

import gpxpy
import gpxpy.gpx

from bridge_node.common.errors import UserError
from bridge_node.replay.track import TrackLog
from sim_core.frames.units import KNOT

COLUMNS = {
    "time": ("time", "timestamp", "datetime", "date_time", "utc", "time_utc", "utc_time", "basedatetime",
             "gps_time", "received_at"),
    "date": ("date", "utc_date", "date_utc"),
    "lat": ("lat", "latitude", "lat_deg", "latitude_deg"),
    "lon": ("lon", "lng", "long", "longitude", "lon_deg", "longitude_deg"),
    "heading": ("heading", "hdg", "true_heading", "heading_true", "hdt", "heading_deg"),
    "course": ("cog", "course", "course_over_ground", "cog_deg", "course_deg"),
    "speed": ("sog", "speed", "speed_over_ground", "sog_kn", "sog_kts", "speed_kn", "speed_kts", "speed_knots",
              "sog_ms", "speed_ms", "speed_mps", "speed_kmh"),
    "mmsi": ("mmsi",),
}
MAX_TIME = 1e13  # |a time cell| above this (unix ms in year 2286) is not a time
ELAPSED = ("t", "t_s", "time_s", "elapsed", "elapsed_s", "elapsed_time", "seconds", "sec", "secs")  # s from the start
TIME_PROBE_ROWS = 50  # rows read to suggest a column of times
SPEED_UNITS = {"kn": KNOT, "m/s": 1.0, "km/h": 1.0 / 3.6}
MAPPING_KEYS = (*COLUMNS, "speed_unit")
NOT_AVAILABLE_ANGLE = 360.0  # AIS writes 511 for an unknown heading: >= 360 deg is none
MAX_HEADER = 10_000  # characters: a longer first line is no CSV header
MAX_SPEED_KN = 1000.0  # a speed cell above this (or below 0) makes the row bad


def _normal(name: str) -> str:
    """A header name compared as: lower case, unit in brackets dropped, spaces and dashes as _."""
    name = re.sub(r"[\(\[].*?[\)\]]", "", name.strip().lower()).strip()
    return re.sub(r"[\s\-]+", "_", name)


def _speed_unit(header: str) -> str:
    h = header.lower().replace(" ", "")
    if any(u in h for u in ("m/s", "mps", "_ms", "(ms)")):
        return "m/s"
    return "km/h" if any(u in h for u in ("km/h", "kmh", "kph")) else "kn"


def parse_mapping(text: str | None) -> dict[str, str]:
    """``--columns`` as {key: column}; UserError naming a bad entry."""
    if not text:
        return {}
    out = {}
    for item in text.split(","):
        key, sep, column = (s.strip() for s in item.partition("="))
        if not sep or not column or key not in MAPPING_KEYS:
            raise UserError(f"--columns {text!r}: bad entry {item!r}; give KEY=COLUMN with KEY one of "
                            f"{', '.join(MAPPING_KEYS)}")
        if key == "speed_unit" and column not in SPEED_UNITS:
            raise UserError(f"--columns {text!r}: speed_unit must be one of {', '.join(SPEED_UNITS)}")
        out[key] = column
    return out


def find_columns(header: list[str], mapping: dict[str, str]) -> dict[str, int]:
    """Index of each known column in the header: mapped names first, then common names."""
    normal = [_normal(h) for h in header]
    found = {}
    for key, names in COLUMNS.items():
        if key in mapping:
            wanted = _normal(mapping[key])
            if wanted in normal:
                found[key] = normal.index(wanted)
            continue
        for i, n in enumerate(normal):
            if n in names:
                found[key] = i
                break
    elapsed = next((normal.index(n) for n in ELAPSED if n in normal), None)
    if "time" not in found and "time" not in mapping and elapsed is not None:
        found.pop("date", None)  # a date and seconds from the start are no time
        found["time"] = elapsed
    return found


def _mapping_text(mapping: dict[str, str], **more: str) -> str:
    return ",".join(f"{k}={v}" for k, v in (mapping | more).items())


def _no_time(path: str, header: list[str], cols: dict[str, int], rows: list[list[str]],
             mapping: dict[str, str]) -> UserError:
    """The error for a CSV track with positions but no time column: what was found, and
    the ``--columns`` that names the first other column whose cells read as increasing times."""
    found = f"latitude in {header[cols['lat']]!r} and longitude in {header[cols['lon']]!r}"
    if "time" in mapping:
        return UserError(f"{path}: no time column: found {found}, but no column {mapping['time']!r} "
                         f"(--columns {_mapping_text(mapping)}); the columns are {', '.join(header)}")
    used = set(cols.values())
    for i, name in enumerate(header):
        try:
            t = [_time(row[i])[0] for row in rows[:TIME_PROBE_ROWS]]
        except (ValueError, IndexError):
            continue
        if i not in used and len(t) > 1 and all(b > a for a, b in zip(t, t[1:])):
            return UserError(f"{path}: no time column: found {found}, but no column with a time's name "
                             f"(time, timestamp, utc, t_s, elapsed, ...); if {name!r} holds the times, give "
                             f"--columns {_mapping_text(mapping, time=name)}")
    return UserError(f"{path}: no time column: found {found}, but none of the columns "
                     f"({', '.join(header)}) holds times; a track needs them: add one and give "
                     f"--columns {_mapping_text(mapping, time='COLUMN')}")


def looks_like_csv_track(first_lines: list[str], mapping: dict[str, str]) -> bool:
    """Whether the first non-comment line is a header naming latitude and longitude columns."""
    header = next((line for line in first_lines if line.strip() and not line.startswith("#")), "")
    if len(header) > MAX_HEADER:
        return False
    try:
        dialect = csv.Sniffer().sniff(header, delimiters=",;\t|")
        cols = find_columns(next(csv.reader([header], dialect)), mapping)
    except (csv.Error, StopIteration):
        return False
    return "lat" in cols and "lon" in cols


def _time(text: str) -> tuple[float, bool]:
    """(seconds, absolute) of a time cell: unix seconds or milliseconds, ISO 8601 (UTC
    unless it says otherwise), a time of day, or seconds from the start. ValueError."""
    text = text.strip()
    try:
        x = float(text)
    except ValueError:
        pass
    else:
        if not math.isfinite(x) or abs(x) > MAX_TIME:
            raise ValueError(text)
        return (x * 1e-3, True) if x > 1e11 else (x, x > 1e8)
    try:
        moment = dt.datetime.fromisoformat(text.replace("/", "-"))
    except ValueError:
        tod = dt.time.fromisoformat(text)
        return tod.hour * 3600.0 + tod.minute * 60.0 + tod.second + tod.microsecond * 1e-6, False
    return unix_time(moment), True


def unix_time(moment: dt.datetime) -> float:
    """Unix time (s) of a datetime, UTC unless it says otherwise; ValueError for one that
    has no unix time (a zone offset of 24 h or more, a year that overflows in UTC)."""
    try:
        return (moment if moment.tzinfo else moment.replace(tzinfo=dt.timezone.utc)).timestamp()
    except OverflowError as exc:
        raise ValueError(f"{moment!r}: {exc}") from None


def _angle(cell: str) -> float | None:
    """Degrees in a cell as rad; None when empty or not available (>= 360)."""
    if not cell.strip():
        return None
    deg = float(cell)
    return math.radians(deg) if math.isfinite(deg) and 0.0 <= deg < NOT_AVAILABLE_ANGLE else None


def _rows(reader, bad: list[int]):
    """The rows of a csv reader; a row csv cannot split (a field over its 131 072
    character limit, a stray quote in strict dialects) is counted in ``bad[0]`` and
    skipped."""
    while True:
        try:
            yield next(reader)
        except StopIteration:
            return
        except csv.Error:
            bad[0] += 1


def _row_fix(cell: dict[str, str], unit: float) -> tuple:
    """(t, absolute, lat rad, lon rad, mmsi, speed m/s, course, heading) of one row's
    cells; ValueError, IndexError or KeyError for a row that is not a fix."""
    when, absolute = _time(f"{cell['date']} {cell['time']}" if "date" in cell and "time" in cell
                           else cell.get("time", ""))
    lat, lon = float(cell["lat"]), float(cell["lon"])
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
        raise ValueError("position out of range")
    mmsi = int(cell["mmsi"]) if "mmsi" in cell else None
    speed = float(cell["speed"]) if cell.get("speed", "").strip() else None
    if speed is not None and not 0.0 <= speed * unit <= MAX_SPEED_KN * KNOT:
        raise ValueError("speed out of range")
    return (when, absolute, math.radians(lat), math.radians(lon), mmsi, None if speed is None else speed * unit,
            _angle(cell.get("course", "")), _angle(cell.get("heading", "")))


def read_csv_track(path: str, lines: list[str], mapping: dict[str, str]) -> dict[int | None, TrackLog]:
    """The fixes of a CSV track as track logs by MMSI (None: the file has no MMSI column);
    rows that cannot be read (bad cells, a position off the Earth, a speed out of range,
    a field csv cannot split) are counted as ``bad_row`` on each. UserError naming the
    file when it has no header csv can read, no latitude and longitude or no time column."""
    body = [line for line in lines if line.strip() and not line.startswith("#")]
    try:
        if not body or len(body[0]) > MAX_HEADER:
            raise csv.Error("no header line")
        dialect = csv.Sniffer().sniff(body[0], delimiters=",;\t|")
        rows = csv.reader(body, dialect)
        header = next(rows)
    except (csv.Error, StopIteration) as exc:
        raise UserError(f"{path}: no CSV header naming the columns ({exc})") from None
    bad = [0]
    cols = find_columns(header, mapping)
    if "lat" not in cols or "lon" not in cols:
        raise UserError(f"{path}: no latitude and longitude columns in its header ({', '.join(header)[:200]}); "
                        f"name them with --columns lat=COLUMN,lon=COLUMN")
    if "time" not in cols:
        raise _no_time(path, header, cols, list(_rows(rows, bad)), mapping)
    unit = SPEED_UNITS[mapping.get("speed_unit") or (_speed_unit(header[cols["speed"]]) if "speed" in cols else "kn")]
    logs: dict[int | None, TrackLog] = {}
    for row in _rows(rows, bad):
        try:
            when, absolute, lat, lon, mmsi, speed, course, heading = _row_fix({k: row[i] for k, i in cols.items()},
                                                                              unit)
        except (ValueError, IndexError, KeyError):
            bad[0] += 1
            continue
        log = logs.setdefault(mmsi, TrackLog([path], vessel=None if mmsi is None else str(mmsi)))
        log.absolute = log.absolute and absolute
        log.fixes.append((when, lat, lon))
        log.add_motion(when, course, speed)
        if heading is not None:
            log.heading.append((when, heading))
        log.read["csv row"] += 1
    for log in logs.values():
        if bad[0]:
            log.bad["bad_row"] += bad[0]
    return logs


def _gpx_point(p) -> tuple[float, float, float, float | None, float | None]:
    """(t, lat rad, lon rad, course rad or None, speed m/s or None) of a GPX track point;
    ValueError for one off the Earth or whose time has no unix time (a zone offset of 24 h
    or more). A course or speed out of range is taken as none."""
    lat, lon = p.latitude, p.longitude
    if not (isinstance(lat, float) and isinstance(lon, float) and -90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
        raise ValueError(f"position {lat!r}, {lon!r} off the Earth")
    t = unix_time(p.time)
    if not abs(t) <= MAX_TIME:
        raise ValueError(f"time {p.time!r} out of range")
    course = p.course if isinstance(p.course, float) and 0.0 <= p.course < NOT_AVAILABLE_ANGLE else None
    speed = p.speed if isinstance(p.speed, float) and 0.0 <= p.speed <= MAX_SPEED_KN * KNOT else None
    return t, math.radians(lat), math.radians(lon), None if course is None else math.radians(course), speed


def read_gpx(path: str, text: str) -> TrackLog:
    """The track points of a GPX file (every track and segment; speed and course where the
    file has them); UserError if it is not GPX. Points without a time are counted as
    ``no_time``, points off the Earth or with a time that has no unix time (a zone offset
    of 24 h or more) as ``bad_point``."""
    try:
        gpx = gpxpy.parse(text)
    except (gpxpy.gpx.GPXException, ValueError) as exc:
        raise UserError(f"{path}: not a GPX file gpxpy can read: {exc}") from None
    log = TrackLog([path])
    for track in gpx.tracks:
        for segment in track.segments:
            for p in segment.points:
                if p.time is None:
                    log.bad["no_time"] += 1
                    continue
                try:
                    t, lat, lon, course, speed = _gpx_point(p)
                except ValueError:
                    log.bad["bad_point"] += 1
                    continue
                log.fixes.append((t, lat, lon))
                log.add_motion(t, course, speed)
                log.read["gpx point"] += 1
    return log
