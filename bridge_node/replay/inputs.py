"""What ``icebridge replay`` is given, recognised by content, not by file name.

- A folder holding a session record, or record files (``can.log``, ``modbus.csv``,
  ``ticks.log``; the node's ``nmea.log`` with a ``ticks.log`` beside it or given with the
  other record files): re-simulated.
- NMEA 0183 and AIS logs (any line form ``sentences`` reads; the node's ``nmea.log`` alone,
  without a tick log beside it, is a track log like any other).
- CSV tracks (a header naming latitude and longitude columns) and GPX files.

Several files of one voyage are merged. A file that holds no usable track is a clear
error naming it and what was looked for; AIS logs (and CSV files with an MMSI column) of
several vessels give the list of vessels when none was picked.
"""
from __future__ import annotations

import datetime as dt
import math
import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from bridge_node.common.errors import UserError
from bridge_node.common.input_files import LOG_LIMIT, read_input_text
from bridge_node.exercise.tick_record import HEADER as TICKS_HEADER
from bridge_node.exercise.tick_record import TICKS_FILE
from bridge_node.replay.csv_track import looks_like_csv_track, read_csv_track, read_gpx
from bridge_node.replay.sentences import SentenceLog
from bridge_node.replay.session import RecordedSession, read_session, record_files
from bridge_node.replay.track import TrackLog

_CANDUMP = re.compile(r"^\(\d+\.\d+\)\s+\S+\s+[0-9A-Fa-f]+#")
_NODE_NMEA = re.compile(r"^\d+\.\d+ \S+ (rx|tx) [$!]")
_MODBUS_HEADER = "unix_time,link,op,table,address,raw,value"
_SENTENCE = re.compile(r"[$!][A-Z][A-Z0-9]{4},")
SNIFF_LINES = 200
MAX_SPAN_S = 30 * 86400.0  # s: the longest stretch of a track log one replay steps through
LOOKED_FOR = ("NMEA 0183 RMC/GGA/GLL fixes, AIS position reports (types 1, 2, 3, 18, 19), CSV rows with "
              "time, latitude and longitude, GPX track points with a time, or a session record")


@dataclass
class VesselChoice:
    """Several vessels and none picked: their listing (MMSI, name, counts, time span)."""

    vessels: list[dict]


def _kind(path: Path, lines: list[str], mapping: dict[str, str]) -> str:
    """``session``, ``node_nmea`` (the node's own NMEA log, no tick log beside it),
    ``sentences``, ``csv`` or ``gpx`` by the file's first lines; UserError."""
    head = [line for line in lines[:SNIFF_LINES] if line.strip() and not line.startswith("#")]
    if not head:
        raise UserError(f"{path}: empty file: no usable track (looked for {LOOKED_FOR})")
    first = head[0].strip()
    if first.startswith(("<?xml", "<gpx")):
        return "gpx"
    if _CANDUMP.match(first) or first == _MODBUS_HEADER or TICKS_HEADER.match(lines[0]):
        return "session"
    if _NODE_NMEA.match(first):
        return "session" if (path.parent / TICKS_FILE).is_file() else "node_nmea"
    if any(_SENTENCE.search(line) for line in head):
        return "sentences"
    if looks_like_csv_track(head, mapping):
        return "csv"
    raise UserError(f"{path}: no usable track: not a log this command reads (looked for {LOOKED_FOR})")


def read_text(path: Path) -> str:
    """A log file's text (undecodable bytes replaced); UserError naming it if it is not a
    regular file, is larger than LOG_LIMIT or cannot be read."""
    return read_input_text(path, "log", LOG_LIMIT, errors="replace")


def _session_folder(path: Path) -> tuple[Path, set[str]]:
    """A session folder and the record files in it; UserError if it is not one."""
    names = {name for name in record_files().values() if (path / name).is_file()}
    if not names and not (path / TICKS_FILE).is_file():
        raise UserError(f"{path}: a folder, but not a session record (looked for {TICKS_FILE}, "
                        f"{', '.join(record_files().values())})")
    return path, names


def load_inputs(paths: list[str], mmsi: int | None, mapping: dict[str, str],
                session_period: float) -> TrackLog | RecordedSession | VesselChoice:
    """Recognise and read the given files: a track log (several files merged), a session
    record, or the vessels to choose from. UserError for anything unusable."""
    names = ", ".join(paths)
    sessions, sentences, track_logs, by_mmsi = _read_files(paths, mapping)
    if sessions:
        if sentences.own.files or track_logs or by_mmsi:
            raise UserError(f"{names}: a session record cannot be replayed together with track logs")
        return _session(sessions, names, session_period)
    return _track(sentences, track_logs, by_mmsi, mmsi, names)


def _read_files(paths: list[str], mapping: dict[str, str]) -> tuple[list, SentenceLog, list, dict]:
    """Every file read by its kind: the session record files (folder, names), the NMEA and
    AIS sentences, the CSV and GPX track logs, and the CSV logs by MMSI."""
    sessions: list[tuple[Path, set[str]]] = []
    node_nmea: list[tuple[str, Path, list[str]]] = []  # session files, or track logs when alone
    sentences, track_logs, by_mmsi = SentenceLog(), [], {}
    for name in paths:
        path = Path(name).expanduser()
        if path.is_dir():
            sessions.append(_session_folder(path))
            continue
        if not path.exists():
            raise UserError(f"{name}: no such file")
        text = read_text(path)
        lines = text.splitlines()
        kind = _kind(path, lines, mapping)
        if kind == "session":
            sessions.append((path.parent, {path.name} & set(record_files().values())))
        elif kind == "node_nmea":
            node_nmea.append((name, path, lines))
        elif kind == "gpx":
            track_logs.append(read_gpx(name, text))
        elif kind == "csv":
            for key, log in read_csv_track(name, lines, mapping).items():
                (track_logs.append(log) if key is None else by_mmsi.setdefault(key, []).append(log))
        else:
            sentences.read(name, lines)
    if sessions:
        sessions += [(path.parent, {path.name}) for _, path, _ in node_nmea]
    else:
        for name, _, lines in node_nmea:
            sentences.read(name, lines)
    return sessions, sentences, track_logs, by_mmsi


def _session(sessions: list[tuple[Path, set[str]]], names: str, period: float) -> RecordedSession:
    """The one session record the files belong to."""
    folders = {folder for folder, _ in sessions}
    if len(folders) > 1:
        raise UserError(f"{names}: files of {len(folders)} session records; replay one at a time")
    try:
        return read_session(folders.pop(), set().union(*(n for _, n in sessions)) or set(record_files().values()),
                            period)
    except ValueError as exc:
        raise UserError(f"{sessions[0][0] / TICKS_FILE}: {exc}") from None


def _track(sentences: SentenceLog, track_logs: list, by_mmsi: dict, mmsi: int | None,
           names: str) -> TrackLog | VesselChoice:
    """The track to replay (``mmsi``'s, the own ship's, or the only vessel's), or the
    vessels to choose from."""
    for number, v in sentences.vessels.items():
        if v.reports:
            by_mmsi.setdefault(number, []).append(v.track(sentences.own.files, sentences.own.bad))
    others = [v for number, v in sentences.vessels.items() if number != mmsi and v.reports and not v.own]
    if mmsi is not None:
        if mmsi not in by_mmsi:
            heard = ", ".join(str(m) for m in sorted(by_mmsi)) or "none"
            raise UserError(f"--mmsi {mmsi}: no position reports of that vessel in {names} "
                            f"(vessels with positions: {heard})")
        return _merged(by_mmsi[mmsi], others)
    own = ([sentences.own] if sentences.own.fixes else []) + track_logs
    if own:
        return _merged(own, others)
    if len(by_mmsi) == 1:
        return _merged(next(iter(by_mmsi.values())))
    if by_mmsi:
        listing = {number: v.listing() for number, v in sentences.vessels.items() if number in by_mmsi}
        for number, logs in by_mmsi.items():
            if number not in listing:
                t = [f[0] for log in logs for f in log.fixes]
                listing[number] = {"mmsi": number, "name": "", "position_reports": len(t), "first": min(t),
                                   "last": max(t)}
        return VesselChoice([listing[n] for n in sorted(listing)])
    bad = Counter(sentences.own.bad)
    for log in track_logs:
        bad.update(log.bad)
    found = f"; bad data: {', '.join(f'{n} {k}' for k, n in sorted(bad.items()))}" if bad else ""
    raise UserError(f"{names}: no usable track: no position in it (looked for {LOOKED_FOR}){found}")


def check_span(files: list[str], start: float, end: float, step: float, absolute: bool = True) -> int:
    """The number of steps of ``step`` s from logged time ``start`` to ``end`` (s); a
    UserError naming the files, the span and how to narrow it (--from/--to) when it is
    longer than MAX_SPAN_S (30 days: more than 5 million steps at 0.5 s) or not finite."""
    span = end - start
    if not (math.isfinite(span) and span <= MAX_SPAN_S):
        days = span / 86400.0
        where = (f"from {_utc(start)} to {_utc(end)} UTC" if absolute and math.isfinite(span)
                 else f"{span:.6g} s")
        raise UserError(f"{', '.join(files)}: the track spans {days:.6g} days ({where}), over the "
                        f"{MAX_SPAN_S / 86400.0:g} days one replay steps through every {step:g} s; "
                        f"narrow it with --from and --to (e.g. --from 0 --to {int(MAX_SPAN_S)})")
    return max(1, math.ceil(span / step - 1e-9))


def _utc(t: float) -> str:
    """A unix time as ISO 8601 UTC text, or the number where no date holds it."""
    try:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S")
    except (OverflowError, ValueError, OSError):
        return f"{t:.6g} s"


def _merged(logs: list[TrackLog], others: list | None = None) -> TrackLog:
    """One track log from the logs of one voyage (several files), with the other AIS
    vessels heard in them (``sentences.Vessel``, replayed as traffic)."""
    out = TrackLog([], others=others or [])
    for log in logs:
        out.merge(log)
    return out
