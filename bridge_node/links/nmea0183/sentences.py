"""NMEA 0183 sentences: console orders in (ROR, ETL, PRC and the proprietary searchlight
order PICBSL), ship state, the convoy's ships (TTM) and alarms out.

pynmea2 parses and renders the standard sentences. It has no ROR, ETL, PRC or ALR, so
those are registered here as ``pynmea2.TalkerSentence`` subclasses (parse and render both
work from the ``fields`` tuple). Checksums are required and verified on input, and written
on output. Angles in degrees and speeds in knots only here, at the edge.
"""
from __future__ import annotations

import datetime as dt
import math
import re
from dataclasses import dataclass

import pynmea2

from bridge_node.links.convoy import ConvoyTarget
from bridge_node.links.messages import ETL_POSITIONS, RUDDER_ORDER_LIMIT_DEG, Alarm, ControlInput, searchlight_order
from sim_core.frames.units import KNOT, NAUTICAL_MILE
from sim_core.ship.orders import OrderKind
from sim_core.ship.outputs import ShipOutputs
from sim_core.ship.searchlights import SearchlightOrder

# sentence -> default talker. Heading and rate of turn go out as IN (integrated navigation):
# gpsd up to 3.23 (Debian 12, Ubuntu 22.04) drops the gyro's HE talker in its packet lexer,
# and every gpsd accepts GP, II and IN; OpenCPN takes any talker.
DEFAULT_TALKERS = {"RMC": "GP", "GGA": "GP", "VTG": "GP", "ZDA": "GP", "HDT": "IN", "ROT": "IN", "RSA": "II",
                   "RPM": "II", "VBW": "II", "XDR": "II", "ALR": "II", "TTM": "RA"}
# talkers whose orders are taken by default: autopilot (general AG, magnetic AP), propulsion
# and remote control RC, integrated instrumentation II and integrated navigation IN
COMMON_ORDER_TALKERS = ("AG", "AP", "RC", "II", "IN")
DEFAULT_RATES = {"RMC": 1.0, "GGA": 1.0, "VTG": 1.0, "ZDA": 1.0, "HDT": 10.0, "ROT": 5.0, "RSA": 5.0,
                 "RPM": 2.0, "VBW": 1.0, "XDR": 1.0}  # Hz
TYPICAL_LENGTH = {"RMC": 72, "GGA": 74, "VTG": 40, "ZDA": 36, "HDT": 18, "ROT": 18, "RSA": 22, "RPM": 28,
                  "VBW": 44, "XDR": 62, "TTM": 140}  # characters with CR LF, to budget a line's baud rate
TTM_RATE = 1.0  # Hz: the convoy's ships (two TTM), unless ``rates`` sets it (then it counts in the budget)

_DECIMAL = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)")
# a framed sentence: $ or !, an address (talker + type, or a proprietary P...), fields of
# printable characters other than the delimiters, and a two-digit checksum
_FRAME = re.compile(r"[$!](?P<address>[A-Z][A-Z0-9]{1,7})(?P<fields>,[\x20-\x7e]*)?\*(?P<checksum>[0-9A-Fa-f]{2})")
_DELIMITERS = re.compile(r"[$!*]")


def nmea_decimal(text: str) -> float:
    """A numeric field in NMEA 0183's decimal format (optional sign, digits, optional
    fraction); Python's other float syntax (``1_0``, ``1e-400``, ``nan``) is not a number here.
    pynmea2 hands a field that fails this back as its text, which the order parser rejects."""
    if not _DECIMAL.fullmatch(text):
        raise ValueError(f"not an NMEA decimal: {text!r}")
    return float(text)


class ROR(pynmea2.TalkerSentence):
    """Rudder order: starboard (or single) and port order, deg (- to port), statuses, source."""

    fields = (("Starboard order", "stbd", nmea_decimal), ("Starboard status", "stbd_status"),
              ("Port order", "port", nmea_decimal), ("Port status", "port_status"), ("Command source", "source"))


class ETL(pynmea2.TalkerSentence):
    """Engine telegraph: time, O order / A answer-back, position code, sub-telegraph,
    location, engine number."""

    fields = (("Time", "time"), ("Message type", "message_type"), ("Position", "position"),
              ("Sub-telegraph", "sub_telegraph"), ("Location", "location"), ("Engine", "engine"))


class PRC(pynmea2.TalkerSentence):
    """Propulsion remote control: lever %, status, RPM demand, mode, pitch demand, mode,
    location, engine number."""

    fields = (("Lever", "lever", nmea_decimal), ("Lever status", "lever_status"), ("RPM demand", "rpm"),
              ("RPM mode", "rpm_mode"), ("Pitch demand", "pitch"), ("Pitch mode", "pitch_mode"),
              ("Location", "location"), ("Engine", "engine"))


class ALR(pynmea2.TalkerSentence):
    """Alarm: time, alarm number, condition (A threshold exceeded, V not), acknowledged
    (A / V), text."""

    fields = (("Time", "time"), ("Number", "number"), ("Condition", "condition"),
              ("Acknowledged", "acknowledged"), ("Text", "text"))


ORDER_SENTENCES = frozenset({"ROR", "ETL", "PRC"})  # the sentence types that carry orders
# proprietary (P, maker mnemonic ICB, type SL): light 0..3, A on / V off, bearing deg from the
# bow (+ starboard), elevation deg (+ up); an empty field leaves that as it was. No talker:
# taken whatever ``allowed_talkers`` says.
SEARCHLIGHT_SENTENCE = "PICBSL"
_STATUS = {"A": True, "V": False, "": None}


class SentenceError(ValueError):
    """A sentence that is not a usable order; ``kind`` names the error for the counters."""

    def __init__(self, kind: str, detail: str) -> None:
        super().__init__(f"{kind}: {detail}")
        self.kind = kind


def _engine(text: str) -> int:
    try:
        n = int(text) if text else 0
    except ValueError:
        raise SentenceError("bad_field", f"engine number {text!r}") from None
    if not 0 <= n <= 9:
        raise SentenceError("out_of_range", f"engine number {n}")
    return n


def _finite(value, what: str, limit: float) -> float:
    if value is None or not math.isfinite(value):
        raise SentenceError("bad_field", f"{what} {value!r}")
    if abs(value) > limit:
        raise SentenceError("out_of_range", f"{what} {value} beyond +-{limit}")
    return float(value)


def checksum(body: str) -> int:
    """NMEA 0183 checksum: XOR of the characters between ``$``/``!`` and ``*``."""
    value = 0
    for c in body:
        value ^= ord(c)
    return value


def parse_order(line: str, now: float, source: str,
                allowed_talkers: frozenset[str] | None = frozenset(COMMON_ORDER_TALKERS)) -> list[ControlInput]:
    """The orders in one console sentence (``allowed_talkers`` None: any talker). Raises
    SentenceError (with a kind for the counters): ``malformed`` only for what cannot be
    framed as a sentence; ``ignored`` for a well-formed sentence that is not an order (AIS,
    position, types this node does not read, of any length); the rest for orders that are
    unchecked, out of range or invalid."""
    line = line.strip()
    if not line.startswith(("$", "!")):
        raise SentenceError("malformed", "not a sentence")
    if "*" not in line:
        raise SentenceError("no_checksum", "checksum missing")
    frame = _FRAME.fullmatch(line)
    if frame is None or _DELIMITERS.search(frame["fields"] or ""):
        raise SentenceError("malformed", "cannot be framed as a sentence")
    if checksum(line[1:line.index("*")]) != int(frame["checksum"], 16):
        raise SentenceError("bad_checksum", "checksum does not match")
    address = frame["address"]
    if line[0] == "$" and address == SEARCHLIGHT_SENTENCE:
        return [ControlInput(now, source, OrderKind.SEARCHLIGHT, _searchlight_order(frame["fields"] or ""))]
    if line[0] != "$" or len(address) != 5 or address[2:] not in ORDER_SENTENCES:
        raise SentenceError("ignored", f"{address} is not a console order")
    if allowed_talkers is not None and address[:2] not in allowed_talkers:
        raise SentenceError("talker_not_allowed", f"talker {address[:2]!r}")
    try:
        return _orders(pynmea2.parse(line, check=True), now, source)
    except SentenceError:
        raise
    except (pynmea2.ParseError, ValueError, TypeError, AttributeError) as exc:
        raise SentenceError("bad_field", str(exc)) from None


def _rudder_order(msg: ROR) -> float:
    """ROR's order, rad. The ship model has one rudder: the starboard field is a single
    rudder's, and a ship whose single rudder is wired as port sends only the port field;
    with both valid (twin rudders, moved together in the model) the order is their mean,
    which is the twin rudders' lift while it is linear in the angle."""
    valid = [_finite(order, "rudder order", RUDDER_ORDER_LIMIT_DEG)
             for order, status in ((msg.stbd, msg.stbd_status), (msg.port, msg.port_status)) if status == "A"]
    if not valid:
        raise SentenceError("invalid_status", "ROR has no valid order (status A)")
    return math.radians(sum(valid) / len(valid))


def _searchlight_order(fields: str) -> SearchlightOrder:
    """The searchlight order of PICBSL's fields (",light,status,bearing,elevation")."""
    try:
        light, status, bearing, elevation = fields.split(",")[1:]
        if not light.isdigit():
            raise ValueError(light)
        order = searchlight_order(int(light), _STATUS[status], *(nmea_decimal(v) if v else None
                                                                 for v in (bearing, elevation)))
    except (ValueError, KeyError):
        raise SentenceError("bad_field", f"searchlight order {fields!r}") from None
    if isinstance(order, str):
        raise SentenceError(order, f"searchlight order {fields!r}")
    return order


def _orders(msg, now: float, source: str) -> list[ControlInput]:
    if isinstance(msg, ROR):
        return [ControlInput(now, source, OrderKind.RUDDER, _rudder_order(msg))]
    if isinstance(msg, ETL):
        if msg.message_type != "O":
            raise SentenceError("ignored", "ETL answer-back")
        if msg.position not in ETL_POSITIONS:
            raise SentenceError("out_of_range", f"ETL position {msg.position!r}")
        return [ControlInput(now, source, OrderKind.TELEGRAPH, ETL_POSITIONS[msg.position], _engine(msg.engine))]
    if msg.lever_status != "A":  # PRC
        raise SentenceError("invalid_status", "PRC lever status is not A")
    return [ControlInput(now, source, OrderKind.LEVER, _finite(msg.lever, "lever", 100.0), _engine(msg.engine))]


def _lat(rad: float) -> tuple[str, str]:
    deg = abs(math.degrees(rad))
    d = int(deg)
    return f"{d:02d}{(deg - d) * 60:07.4f}", "N" if rad >= 0 else "S"


def _lon(rad: float) -> tuple[str, str]:
    deg = abs(math.degrees(rad))
    d = int(deg)
    return f"{d:03d}{(deg - d) * 60:07.4f}", "E" if rad >= 0 else "W"


@dataclass(frozen=True)
class _Fix:
    """The GNSS fields of RMC, GGA and VTG: with a fix, or empty with the status that says
    there is none (RMC V, GGA quality 0, mode N: receivers send this when they lose the fix)."""

    status: str
    position: tuple[str, str, str, str]
    sog: str
    cog: str
    sog_kmh: str
    mode: str
    nav_status: str
    quality: str
    satellites: str
    hdop: str
    altitude: str


def _fix_fields(s: ShipOutputs) -> _Fix:
    if not s.fix_valid:
        return _Fix("V", ("", "", "", ""), "", "", "", "N", "V", "0", "00", "", "")
    # mode A (autonomous): chart plotters ignore S (simulator) fixes; nav status S (safe)
    return _Fix("A", (*_lat(s.latitude), *_lon(s.longitude)), f"{s.speed_over_ground / KNOT:.1f}",
                f"{math.degrees(s.course_over_ground):.1f}", f"{s.speed_over_ground * 3.6:.1f}", "A", "S", "1", "12",
                "0.8", "15.0")


def render_outputs(names: list[str], s: ShipOutputs, utc: dt.datetime, talkers: dict[str, str]) -> list[str]:
    """The named output sentences for a ship state, with checksums (no CR LF)."""
    hms = utc.strftime("%H%M%S.") + f"{utc.microsecond // 10000:02d}"
    rudder = f"{math.degrees(s.rudder_angle):.1f}"
    fix = _fix_fields(s)
    build = {
        "RMC": lambda: ("RMC", (hms, fix.status, *fix.position, fix.sog, fix.cog, utc.strftime("%d%m%y"), "", "",
                                fix.mode, fix.nav_status)),
        "GGA": lambda: ("GGA", (hms, *fix.position, fix.quality, fix.satellites, fix.hdop, fix.altitude, "M",
                                "25.0", "M", "", "")),
        "VTG": lambda: ("VTG", (fix.cog, "T", "", "M", fix.sog, "N", fix.sog_kmh, "K", fix.mode)),
        "ZDA": lambda: ("ZDA", (hms, f"{utc.day:02d}", f"{utc.month:02d}", f"{utc.year:04d}", "00", "00")),
        "HDT": lambda: ("HDT", (f"{math.degrees(s.heading):.1f}", "T")),
        "ROT": lambda: ("ROT", (f"{math.degrees(s.rate_of_turn) * 60.0:.1f}", "A")),
        "RSA": lambda: ("RSA", (rudder, "A", "", "V")),
        "RPM": lambda: ("RPM", ("S", "0", f"{s.shaft_rps * 60.0:.1f}", "", "A")),
        "VBW": lambda: ("VBW", (f"{s.speed_longitudinal / KNOT:.2f}", f"{s.speed_transverse / KNOT:.2f}", "A",
                                "", "", "V")),
        # the ice resistance, then pitch (bow up +) and roll (starboard down +) under the
        # transducer names of Airmar's attitude sensors
        "XDR": lambda: ("XDR", ("F", f"{s.ice_resistance:.0f}", "N", "ICE_RES", "A", f"{math.degrees(s.pitch):.1f}",
                                "D", "PTCH", "A", f"{math.degrees(s.roll):.1f}", "D", "ROLL")),
    }
    out = []
    for name in names:
        kind, fields = build[name]()
        out.append(str(getattr(pynmea2.types.talker, kind)(talkers.get(name, DEFAULT_TALKERS[name]), kind, fields)))
    return out


def render_alarm(alarm: Alarm, utc: dt.datetime, talker: str = "II") -> str:
    """ALR sentence for an alarm; its text fits whole (see ``Alarm``)."""
    hms = utc.strftime("%H%M%S.") + f"{utc.microsecond // 10000:02d}"
    return str(ALR(talker, "ALR", (hms, f"{alarm.number:03d}", "A" if alarm.active else "V", "V", alarm.text)))


def render_targets(targets: list[ConvoyTarget], utc: dt.datetime, talker: str = "RA") -> list[str]:
    """TTM (tracked target message, IEC 61162-1) for each convoy ship: its number (1 ahead,
    2 astern), distance and CPA in nautical miles, true bearing and course, speed in knots,
    TCPA in minutes (negative: past), its name, tracking, acquired as reported (AIS, DIS)."""
    hms = utc.strftime("%H%M%S.") + f"{utc.microsecond // 10000:02d}"
    out = []
    for t in targets:
        name = "".join(" " if c in ",*$!" else c for c in t.name)[:20]
        fields = (f"{t.number:02d}", f"{t.distance / NAUTICAL_MILE:.3f}", f"{math.degrees(t.bearing):.1f}", "T",
                  f"{t.speed / KNOT:.1f}", f"{math.degrees(t.course):.1f}", "T", f"{t.cpa / NAUTICAL_MILE:.3f}",
                  f"{t.tcpa / 60.0:.1f}", "N", name, "T", "", hms, "R")
        out.append(str(pynmea2.types.talker.TTM(talker, "TTM", fields)))
    return out
