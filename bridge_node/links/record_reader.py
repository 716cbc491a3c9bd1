"""Readers of a session record (``session_record``) that survive a torn last line.

Only newline-terminated lines are complete; an unterminated last line is torn (a power cut
or a full disk while writing) and is skipped and counted, never parsed into a wrong frame
or sentence. A complete line that does not parse is counted as malformed and skipped.
"""
from __future__ import annotations

import csv
import io
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import can
from can.io.canutils import CanutilsLogReader

from bridge_node.node.input_files import LOG_LIMIT, read_input_text


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
            frames.extend(CanutilsLogReader(io.StringIO(line + "\n")))
        except (ValueError, IndexError):  # what python-can's parser raises on a bad line
            counts["malformed"] += 1
    return frames, counts


def read_nmea_log(path: Path) -> tuple[list[NmeaRecord], Counter]:
    """Lines of ``nmea.log``, and counts of torn and malformed lines."""
    lines, counts = complete_lines(path)
    out = []
    for line in lines:
        parts = line.split(" ", 3)
        try:
            out.append(NmeaRecord(float(parts[0]), parts[1], parts[2], parts[3]))
        except (ValueError, IndexError):
            counts["malformed"] += 1
    return out, counts


def read_modbus_csv(path: Path) -> tuple[list[dict], Counter]:
    """Rows of ``modbus.csv`` as dicts of its header's columns, and counts of torn and
    malformed rows."""
    lines, counts = complete_lines(path)
    rows = list(csv.reader(line.rstrip("\r") for line in lines))
    if not rows:
        return [], counts
    header, out = rows[0], []
    for row in rows[1:]:
        if len(row) != len(header):
            counts["malformed"] += 1
            continue
        try:
            float(row[0])
        except ValueError:
            counts["malformed"] += 1
            continue
        out.append(dict(zip(header, row)))
    return out, counts
