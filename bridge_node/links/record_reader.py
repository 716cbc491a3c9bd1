"""Readers of a session record (``session_record``) that survive a torn last line.

Only newline-terminated lines are complete; an unterminated last line is torn (a power cut
or a full disk while writing) and is skipped and counted, never parsed into a wrong frame
or sentence. A complete line that does not parse is counted as malformed and skipped.
"""
from __future__ import annotations

import csv
import io
import math
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import can
from can.io.canutils import CanutilsLogReader

from bridge_node.common.errors import UserError
from bridge_node.common.input_files import LOG_LIMIT, read_input_text

MAX_UNIX_TIME = 1e10  # s (year 2286): a record line's unix time must lie in [0, this]
MAX_RECORD_TICKS = 10_000_000  # ticks a record without a tick log may span (about 2.3 days at 120 Hz)
MODBUS_COLUMNS = ("unix_time", "link", "op", "table", "address", "raw", "value")
MAX_REGISTER = 2**32  # a Modbus address or raw value at or above this is malformed


def record_time(text: str) -> float:
    """A record line's unix time (s); ValueError unless a finite number in [0, MAX_UNIX_TIME]."""
    x = float(text)
    if not 0.0 <= x <= MAX_UNIX_TIME:  # also NaN
        raise ValueError(f"unix time {text!r} out of range")
    return x


def check_tick_count(folder: Path, times: list[float], period: float) -> int:
    """The number of ticks a record without a tick log spans at ``period`` s a step (the
    first to the last line's time); UserError naming the folder when that is more than
    MAX_RECORD_TICKS (a line far from the others), so that none is made one by one."""
    if not times:
        return 0
    span = max(times) - min(times)
    n = span / period + 1.0
    if not math.isfinite(n) or n > MAX_RECORD_TICKS:
        raise UserError(f"{folder}: the record's lines span {span:.0f} s, {n:.3g} ticks of {period:g} s "
                        f"without a tick log (at most {MAX_RECORD_TICKS}); a line's time is wrong, or "
                        f"give the files of one run")
    return round(n - 1.0) + 1


@dataclass(frozen=True)
class NmeaRecord:
    """One line of ``nmea.log``: unix time (s), link name, "rx" or "tx", the sentence."""

    unix_time: float
    link: str
    direction: str
    sentence: str


def complete_lines(path: Path) -> tuple[list[str], Counter]:
    """The newline-terminated lines of a text file, and {"torn": 0 or 1}; UserError if it
    is not a regular file, is larger than LOG_LIMIT or cannot be read."""
    text = read_input_text(path, "session record file", LOG_LIMIT, errors="replace")
    lines = text.split("\n")
    tail = lines.pop()  # after the last newline: empty, or a torn line
    return lines, Counter(torn=1 if tail else 0)


def read_can_log(path: Path) -> tuple[list[can.Message], Counter]:
    """Frames of ``can.log`` (candump format), and counts of torn and malformed lines."""
    lines, counts = complete_lines(path)
    frames = []
    for line in lines:
        if not line.strip():
            continue
        try:
            read = list(CanutilsLogReader(io.StringIO(line + "\n")))
            for msg in read:
                record_time(str(msg.timestamp))
        except (ValueError, IndexError, OverflowError):  # what python-can's parser raises on a bad line
            counts["malformed"] += 1
            continue
        frames.extend(read)
    return frames, counts


def read_nmea_log(path: Path) -> tuple[list[NmeaRecord], Counter]:
    """Lines of ``nmea.log``, and counts of torn and malformed lines."""
    lines, counts = complete_lines(path)
    out = []
    for line in lines:
        parts = line.split(" ", 3)
        try:
            if parts[2] not in ("rx", "tx"):
                raise ValueError(line)
            out.append(NmeaRecord(record_time(parts[0]), parts[1], parts[2], parts[3]))
        except (ValueError, IndexError):
            counts["malformed"] += 1
    return out, counts


def _modbus_row(header: list[str], row: list[str]) -> dict:
    """A ``modbus.csv`` row as a dict of its header's columns; ValueError unless it has
    every column, a unix time in range and an integer address and raw value in
    [0, MAX_REGISTER)."""
    if len(row) != len(header):
        raise ValueError("wrong number of columns")
    out = dict(zip(header, row))
    record_time(out["unix_time"])
    if not all(x.strip().isdigit() and len(x.strip()) <= 10 and int(x) < MAX_REGISTER
               for x in (out["address"], out["raw"])):
        raise ValueError("address or raw value not a register's")
    return out


def read_modbus_csv(path: Path) -> tuple[list[dict], Counter]:
    """Rows of ``modbus.csv`` as dicts of its header's columns, and counts of torn and
    malformed rows (a field csv cannot split included). UserError naming the file when its
    header lacks a column of MODBUS_COLUMNS."""
    lines, counts = complete_lines(path)
    lines = [line.rstrip("\r") for line in lines]
    if not lines:
        return [], counts
    try:
        header = next(csv.reader(lines[:1]))
    except (csv.Error, StopIteration):
        header = []
    missing = [c for c in MODBUS_COLUMNS if c not in header]
    if missing:
        raise UserError(f"{path}: not a Modbus record: its header lacks {', '.join(missing)} "
                        f"(a record's header is {','.join(MODBUS_COLUMNS)})")
    out = []
    for line in lines[1:]:
        try:
            out.append(_modbus_row(header, next(csv.reader([line]))))
        except (csv.Error, StopIteration, ValueError):
            counts["malformed"] += 1
    return out, counts
