"""NMEA 0183 and AIS logs: one sentence per line, with or without a leading timestamp.

Recognised line forms: raw sentences (a plain capture: time from RMC and ZDA, GGA and GLL
adding the time of day); the node's own ``nmea.log`` (``<unix time> <link> <rx|tx>
<sentence>``); OpenCPN VDR's CSV (ISO 8601 UTC time with milliseconds, then the sentence,
quoted or not); any other leading unix or ISO 8601 time; NMEA 4 tag blocks
(``\\c:<unix time>*hh\\!AIVDM...``). A line's own timestamp wins over the sentence's time.

Own-ship sentences read: RMC, GGA, GLL (position), VTG (course and speed), HDT, THS, HDG
with variation (true heading), ZDA (date); ROT and RSA are recognised and not needed.
AIS (``!AIVDM``, ``!AIVDO``, any talker): multi-part messages reassembled, types 1/2/3/18/19
give positions, 5/19/24 names and dimensions, decoded by pyais. Bad lines are counted by
kind, never fatal.
"""
from __future__ import annotations

import datetime as dt
import math
import re
from collections import Counter
from dataclasses import dataclass, field

import pynmea2
from pyais import decode as ais_decode
from pyais.exceptions import AISBaseException

from bridge_node.links.nmea0183.sentences import checksum, nmea_decimal
from bridge_node.replay.track import TrackLog
from sim_core.frames.units import KNOT

_FRAME = re.compile(r"[$!](?P<address>[A-Z][A-Z0-9]{1,7}),?(?P<fields>[^*$!]*)\*(?P<checksum>[0-9A-Fa-f]{2})")
_TAG_BLOCK = re.compile(r"\\(?P<tags>[^\\]*)\\")
USED = {"RMC", "GGA", "GLL", "VTG", "HDT", "THS", "HDG", "ZDA", "RSA", "ROT"}
AIS_POSITION = {1, 2, 3, 18, 19}
AIS_NO_SECOND = 60  # AIS UTC second 60..63: not available
MAX_SPEED_KN = 1000.0  # a logged speed over ground above this is a bad field, not a fast ship
MAX_CORRECTION_DEG = 180.0  # HDG deviation and variation: at most half a turn either way


class THS(pynmea2.TalkerSentence):
    """True heading and status (IEC 61162-1): heading deg, mode (A autonomous, E estimated,
    M manual, S simulator, V not valid). pynmea2 has no THS."""

    fields = (("Heading", "heading"), ("Mode", "mode"))


def _bearing(degrees: float | None, limit: float = 360.0) -> float | None:
    """An angle field (deg, ``0 <= degrees <= limit``, 360 the same as 0) in rad within
    [0, 2 pi); None when empty; ValueError when out of range or not finite."""
    if degrees is None:
        return None
    if not (math.isfinite(degrees) and 0.0 <= degrees <= limit):
        raise ValueError(f"angle {degrees!r} deg out of range")
    return math.radians(degrees % 360.0) % (2.0 * math.pi)


def _speed(knots: float | None) -> float | None:
    """A speed field (kn, finite, 0 to MAX_SPEED_KN) in m/s; None when empty; ValueError."""
    if knots is None:
        return None
    if not (math.isfinite(knots) and 0.0 <= knots <= MAX_SPEED_KN):
        raise ValueError(f"speed {knots!r} kn out of range")
    return knots * KNOT


def _number(text: str | None) -> float | None:
    """An NMEA decimal field, None when empty; ValueError when not a number."""
    return None if text in (None, "") else nmea_decimal(text)


def _unix(moment: dt.datetime) -> float:
    """Unix time (s) of a datetime (UTC unless it says otherwise); ValueError or
    OverflowError for one that has none (an offset of 24 h or more, a year out of range)."""
    return (moment if moment.tzinfo else moment.replace(tzinfo=dt.timezone.utc)).timestamp()


def prefix_time(prefix: str) -> float | None:
    """Unix time (s) of a line's leading timestamp: unix seconds (or milliseconds), or an
    ISO 8601 date and time (``T`` or a space between them, ``-`` or ``/`` in the date);
    None when there is none."""
    tokens = [t.strip("()") for t in re.split(r"[\s,;\"]+", prefix) if t.strip("()")]
    for i, token in enumerate(tokens):
        try:
            x = float(token)
        except ValueError:
            x = None
        if x is not None and 1e8 < x < 1e10:
            return x
        if x is not None and 1e11 < x < 1e13:
            return x * 1e-3
        for text in (token, " ".join(tokens[i:i + 2])):
            try:
                return _unix(dt.datetime.fromisoformat(text.replace("/", "-")))
            except (ValueError, OverflowError):
                continue
    return None


def split_line(line: str) -> tuple[float | None, str | None, str | None]:
    """(the line's own unix time or None, the framed sentence or None, the kind of problem
    or None). A line with no ``$`` or ``!`` has no sentence and no problem."""
    tag_time = None
    tag = _TAG_BLOCK.match(line)
    if tag:
        for item in tag["tags"].split("*")[0].split(","):
            if item.startswith("c:"):
                tag_time = prefix_time(item[2:])
        line = line[tag.end():]
    starts = [i for i in (line.find("$"), line.find("!")) if i >= 0]
    if not starts:
        return tag_time, None, None
    body = line[min(starts):]
    frame = _FRAME.match(body)
    when = tag_time if tag_time is not None else prefix_time(line[:min(starts)])
    if frame is None:
        return when, None, "no_checksum" if "*" not in body else "malformed"
    sentence = frame.group(0)
    if checksum(sentence[1:sentence.index("*")]) != int(frame["checksum"], 16):
        return when, None, "bad_checksum"
    return when, sentence, None


@dataclass
class Vessel:
    """What an AIS log says of one vessel: its reports by message type, name and
    dimensions (m), and its position reports as a track log."""

    mmsi: int
    own: bool = False  # heard as !AIVDO
    name: str = ""
    length: float = 0.0
    beam: float = 0.0
    messages: Counter = field(default_factory=Counter)  # message type -> count
    first: float | None = None
    last: float | None = None
    reports: list[tuple] = field(default_factory=list)  # (t or None, UTC second or None, lat, lon, sog, cog,
    # heading), SI; None: unknown

    def heard(self, kind: int | str, when: float | None) -> None:
        """Count one message of this kind, heard at unix time ``when`` (None: unknown)."""
        self.messages[kind] += 1
        if when is not None:
            self.first = when if self.first is None else min(self.first, when)
            self.last = when if self.last is None else max(self.last, when)

    def listing(self) -> dict:
        """One row of the vessel list: MMSI, name, counts and time span."""
        return {"mmsi": self.mmsi, "name": self.name, "own": self.own, "messages": dict(sorted(self.messages.items())),
                "position_reports": len(self.reports), "first": self.first, "last": self.last,
                "length_m": self.length or None, "beam_m": self.beam or None}

    def track(self, files: list[str], bad: Counter) -> TrackLog:
        """The position reports as a track log (the files' bad data counted with it).
        Reports without a line time are timed by their UTC second, counting on from 0 s."""
        log = TrackLog(list(files), vessel=f"{self.mmsi} {self.name}".strip(), bad=Counter(bad))
        log.absolute = all(r[0] is not None for r in self.reports)
        t, last_second = 0.0, None
        for when, second, lat, lon, sog, cog, heading in self.reports:
            if not log.absolute:
                if second is None or second >= AIS_NO_SECOND:
                    log.bad["no_time"] += 1
                    continue
                t += 0.0 if last_second is None else (second - last_second) % 60
                last_second, when = second, t
            log.fixes.append((when, lat, lon))
            log.add_motion(when, cog, sog)
            if heading is not None:
                log.heading.append((when, heading))
            log.read["position report"] += 1
        return log


class SentenceLog:
    """Reads NMEA 0183 and AIS log files: the own ship's track (from ``$`` sentences) and
    the vessels the AIS messages tell of."""

    def __init__(self) -> None:
        self.own = TrackLog([])
        self.vessels: dict[int, Vessel] = {}
        self._date: dt.date | None = None
        self._time: float | None = None  # unix s (or seconds from the first day when no date)
        self._day = 0  # days added to a time of day without a date (midnight rollovers)
        self._parts: dict[tuple, tuple[float | None, list[str]]] = {}  # (time of part 1, parts so far)

    # --- lines ---

    def read(self, path: str, lines: list[str]) -> None:
        """Add one file's lines (a first line without a sentence is a header)."""
        self.own.files.append(path)
        for k, raw in enumerate(lines):
            line = raw.strip()
            if not line or line.startswith("#"):
                continue
            when, sentence, problem = split_line(line)
            if problem:
                self.own.bad[problem] += 1
            elif sentence is None:
                if k:
                    self.own.bad["no_sentence"] += 1
            elif sentence[0] == "!":
                self._ais(sentence, when)
            else:
                self._nmea(sentence, when)
        if self._parts:  # messages the file ends in the middle of
            self.own.bad["incomplete_multipart"] += len(self._parts)
            self._parts.clear()

    # --- own ship: NMEA 0183 ---

    def _clock(self, msg, kind: str) -> float | None:
        """The sentence's own time (RMC, ZDA; GGA and GLL with the last date), kept as the
        time of the untimed sentences that follow; None before any time is known.
        ValueError or OverflowError (a bad line, counted by the caller) for a date or time
        no datetime holds; the clock is left as it was then."""
        if (kind == "RMC" and msg.data[8]) or kind == "ZDA":
            moment = msg.datetime
            date, unix = moment.date(), _unix(moment)
            self._date, self._time = date, unix
        elif kind in ("GGA", "GLL") and msg.timestamp is not None:
            tod = msg.timestamp
            seconds = tod.hour * 3600 + tod.minute * 60 + tod.second + tod.microsecond * 1e-6
            if self._date is not None:
                self._time = _unix(dt.datetime.combine(self._date, dt.time())) + seconds
            else:
                self.own.absolute = False
                if self._time is not None and seconds + 86400 * self._day < self._time - 43200:
                    self._day += 1
                self._time = seconds + 86400 * self._day
        return self._time

    def _nmea(self, sentence: str, when: float | None) -> None:
        kind = sentence[3:6] if len(sentence) >= 6 else ""
        if kind not in USED:
            self.own.ignored[kind or sentence[:6]] += 1
            return
        try:
            msg = pynmea2.parse(sentence)
            t = self._clock(msg, kind)
            t = when if when is not None else t
            if t is None:
                self.own.bad["no_time"] += 1
                return
            self._own(kind, msg, t)
        except (pynmea2.ParseError, ValueError, OverflowError, TypeError, AttributeError, IndexError):
            self.own.bad["bad_field"] += 1  # OverflowError: a date or time field too large for a date

    def _own(self, kind: str, msg, t: float) -> None:
        """One own-ship sentence at time t into the log. ValueError (counted by the caller
        as ``bad_field``) for a field out of range: a position, a speed below 0 or above
        MAX_SPEED_KN, an angle outside [0, 360] deg; nothing of the sentence is kept then."""
        log = self.own
        if kind in ("RMC", "VTG"):  # read before the fix is kept: a bad field drops the sentence
            course, speed = (_number(msg.data[7]), _number(msg.data[6])) if kind == "RMC" else \
                (_number(msg.data[0]), _number(msg.data[4]))
            course, speed = _bearing(course), _speed(speed)
        if kind in ("RMC", "GGA", "GLL"):
            valid = msg.status == "A" if kind != "GGA" else (msg.gps_qual or "0") != "0"
            if not valid:
                log.bad["no_fix"] += 1
                return
            lat, lon = msg.latitude, msg.longitude
            if not (msg.lat and msg.lon and -90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
                log.bad["bad_field"] += 1
                return
            log.fixes.append((t, math.radians(lat), math.radians(lon)))
        if kind in ("RMC", "VTG"):
            log.add_motion(t, course, speed)
        elif kind in ("HDT", "THS", "HDG") and not self._heading(kind, msg, t):
            return
        log.read[kind] += 1

    def _heading(self, kind: str, msg, t: float) -> bool:
        """A true heading (HDT, THS, HDG with variation) into the log, in [0, 2 pi); False
        (counted ``no_heading``) when the sentence gives none; ValueError when out of range."""
        if kind == "HDG":
            heading, deviation, variation = (_number(msg.data[i]) for i in (0, 1, 3))
            if heading is None or variation is None:  # magnetic only: no true heading
                self.own.bad["no_heading"] += 1
                return False
            _bearing(heading)
            east = {"E": 1.0, "W": -1.0}
            corrections = [_bearing(x, MAX_CORRECTION_DEG) or 0.0 for x in (deviation, variation)]
            true = math.radians(heading) + corrections[0] * east.get(msg.data[2], 1.0) + \
                corrections[1] * east.get(msg.data[4], 1.0)
            self.own.heading.append((t, true % (2.0 * math.pi)))
            return True
        heading = _bearing(_number(msg.data[0]))
        if heading is None or (kind == "THS" and msg.data[1] == "V"):
            self.own.bad["no_heading"] += 1
            return False
        self.own.heading.append((t, heading))
        return True

    # --- other vessels: AIS ---

    def _ais(self, sentence: str, when: float | None) -> None:
        fields = sentence.split(",")
        try:
            count, index = int(fields[1]), int(fields[2])
        except (IndexError, ValueError):
            self.own.bad["malformed"] += 1
            return
        key = (fields[0][3:6], fields[3], fields[4] if len(fields) > 4 else "")
        if count == 1:
            self._ais_message([sentence], when)
            return
        started, parts = self._parts.get(key, (None, None))
        if index == 1:
            if parts is not None:  # the last message of this sequence never ended
                self.own.bad["incomplete_multipart"] += 1
            self._parts[key] = (when, [sentence])
        elif parts is None or len(parts) != index - 1:
            self.own.bad["incomplete_multipart"] += 1
            self._parts.pop(key, None)
        else:
            parts.append(sentence)
            if index == count:
                del self._parts[key]
                self._ais_message(parts, started if started is not None else when)

    def _ais_message(self, parts: list[str], when: float | None) -> None:
        """One whole AIS message: the vessel heard, its name and dimensions, its position
        report. A message too short for its fields (pyais gives None for those) or with a
        position off the Earth is counted, never fatal."""
        try:
            msg = ais_decode(*parts)
        except (AISBaseException, ValueError, IndexError):
            self.own.bad["ais_undecodable"] += 1
            return
        if not isinstance(getattr(msg, "mmsi", None), int):
            self.own.bad["ais_undecodable"] += 1
            return
        v = self.vessels.setdefault(msg.mmsi, Vessel(msg.mmsi))
        v.own = v.own or parts[0][3:6] == "VDO"
        v.heard(msg.msg_type, when)
        name = getattr(msg, "shipname", None)
        if isinstance(name, str) and name.strip():
            v.name = name.strip()
        size = [getattr(msg, k, None) for k in ("to_bow", "to_stern", "to_port", "to_starboard")]
        if all(isinstance(x, int) for x in size):
            v.length = float(size[0] + size[1]) or v.length
            v.beam = float(size[2] + size[3]) or v.beam
        if msg.msg_type in AIS_POSITION:
            report = _ais_report(msg, when)
            if report is None:
                self.own.bad["ais_no_position"] += 1
                return
            v.reports.append(report)


def _ais_field(msg, name: str, unavailable: float) -> float | None:
    """A numeric AIS field, None when missing, not a finite number or at or above the
    value that means "not available"."""
    x = getattr(msg, name, None)
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) or x < 0 or x >= unavailable:
        return None
    return float(x)


def _ais_report(msg, when: float | None) -> tuple | None:
    """A position report as (t, UTC second, lat, lon, sog, cog, heading), SI; None when it
    has no position on the Earth (a missing field, or 91/181 deg: not available)."""
    lat, lon = getattr(msg, "lat", None), getattr(msg, "lon", None)
    if not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in (lat, lon)) \
            or abs(lat) > 90.0 or abs(lon) > 180.0:
        return None
    second = getattr(msg, "second", None)
    speed, course, heading = (_ais_field(msg, "speed", 102.3), _ais_field(msg, "course", 360.0),
                              _ais_field(msg, "heading", 360.0))
    return (when, second if isinstance(second, int) else None, math.radians(lat), math.radians(lon),
            None if speed is None else speed * KNOT, None if course is None else math.radians(course),
            None if heading is None else math.radians(heading))
