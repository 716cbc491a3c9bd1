"""AIS on the NMEA 0183 outputs: the own ship as ``!AIVDO`` (types 1 and 5), so an ECDIS
or chart plotter shows it as own vessel, and the other vessels as ``!AIVDM``, at the class A
reporting intervals of ITU-R M.1371. pyais encodes the 6-bit payloads and the sentences.

Reporting intervals of a class A station under way (M.1371, Table 1): 10 s at 0-14 kn
(3 1/3 s while changing course), 6 s at 14-23 kn (2 s while changing course), 2 s above
23 kn; static and voyage data (type 5) every 6 min. A vessel counts as changing course while
its rate of turn exceeds ``TURNING_DEG_PER_MIN`` (M.1371 leaves the threshold to the
equipment; this is the node's). The node does not model anchoring, so the 3 min interval at
anchor never applies.
"""
from __future__ import annotations

import datetime as dt
import math
from typing import Protocol

from pydantic import Field
from pyais import encode_dict

from sim_core.frames.units import KNOT
from sim_core.params import Params

STATIC_PERIOD_S = 360.0
TURNING_DEG_PER_MIN = 5.0
SIX_BIT_TEXT = r"^[A-Z0-9 @\[\\\]^_!\"#$%&'()*+,\-./:;<=>?]*$"  # AIS 6-bit ASCII
SIX_BIT_CHARS = frozenset("@ABCDEFGHIJKLMNOPQRSTUVWXYZ[\\]^_ !\"#$%&'()*+,-./0123456789:;<=>?")  # ITU-R M.1371 Table 47


class AisSettings(Params):
    """AIS of one NMEA 0183 link (``[links.ais]``): the own ship's identity and static data
    as its transponder would be set up, and whether the other vessels go out too."""

    mmsi: int = Field(ge=100_000_000, le=999_999_999)
    name: str = Field("", max_length=20, pattern=SIX_BIT_TEXT)
    call_sign: str = Field("", max_length=7, pattern=SIX_BIT_TEXT)
    imo: int = Field(0, ge=0, le=999_999_999, description="0: none")
    ship_type: int = Field(70, ge=0, le=99, description="70: cargo")
    to_bow: int = Field(ge=0, le=511, description="m from the GNSS antenna to the bow")
    to_stern: int = Field(ge=0, le=511, description="m from the antenna to the stern")
    to_port: int = Field(ge=0, le=63, description="m from the antenna to port")
    to_starboard: int = Field(ge=0, le=63, description="m from the antenna to starboard")
    draught: float = Field(0.0, ge=0.0, le=25.5, description="m")
    destination: str = Field("", max_length=20, pattern=SIX_BIT_TEXT)
    other_vessels: bool = Field(True, description="send the other vessels as !AIVDM")


class Moving(Protocol):
    """What a position report needs; ``ShipOutputs`` and ``Vessel`` both have it (SI)."""

    latitude: float
    longitude: float
    heading: float
    course_over_ground: float
    speed_over_ground: float
    rate_of_turn: float
    fix_valid: bool


def report_interval(speed_over_ground: float, rate_of_turn: float) -> float:
    """Class A position report interval under way, s; speed m/s, rate of turn rad/s."""
    kn = speed_over_ground / KNOT
    turning = abs(math.degrees(rate_of_turn)) * 60.0 > TURNING_DEG_PER_MIN
    if kn > 23.0:
        return 2.0
    if kn > 14.0:
        return 2.0 if turning else 6.0
    return 10.0 / 3.0 if turning else 10.0


def position_report(mmsi: int, v: Moving, utc: dt.datetime, sentence: str) -> list[str]:
    """Type 1 (position report, class A, under way using engine) as ``sentence`` VDO or VDM."""
    rot = math.degrees(v.rate_of_turn) * 60.0  # deg/min; pyais encodes it as ROT_AIS
    # pyais truncates to the field's resolution: round first (0.1 kn, 1/10000 min, 0.1 deg)
    fields = {"speed": min(102.2, round(v.speed_over_ground / KNOT, 1)), "accuracy": 1,
              "lon": round(math.degrees(v.longitude) * 600_000) / 600_000,
              "lat": round(math.degrees(v.latitude) * 600_000) / 600_000,
              "course": round(math.degrees(v.course_over_ground), 1) % 360.0}
    if not v.fix_valid:  # no fix: ITU-R M.1371 "not available" values
        fields = {"speed": 102.3, "accuracy": 0, "lon": 181.0, "lat": 91.0, "course": 360.0}
    return encode_dict({"type": 1, "mmsi": mmsi, "status": 0, "turn": max(-708.0, min(708.0, rot)), **fields,
                        "heading": round(math.degrees(v.heading)) % 360, "second": utc.second},
                       talker_id="AI", sentence_type=sentence)


def static_report(mmsi: int, name: str, dims: tuple[int, int, int, int], utc: dt.datetime, sentence: str,
                  seq_id: int, settings: AisSettings | None = None) -> list[str]:
    """Type 5 (static and voyage data; two sentences sharing ``seq_id``): the own ship's from
    its settings, another vessel's with what is known (name, dimensions to bow, stern, port,
    starboard in m)."""
    s = settings
    return encode_dict({"type": 5, "mmsi": mmsi, "ais_version": 0, "imo": s.imo if s else 0,
                        "callsign": s.call_sign if s else "", "shipname": name, "ship_type": s.ship_type if s else 0,
                        "to_bow": dims[0], "to_stern": dims[1], "to_port": dims[2], "to_starboard": dims[3],
                        "epfd": 1, "month": utc.month, "day": utc.day, "hour": utc.hour, "minute": utc.minute,
                        "draught": s.draught if s else 0.0, "destination": s.destination if s else "", "dte": 0},
                       talker_id="AI", sentence_type=sentence, seq_id=seq_id)


def six_bit_text(text: str, length: int = 20) -> str:
    """``text`` as AIS 6-bit text of at most ``length`` characters: upper case, and any
    character the 6-bit alphabet lacks (``{ | } ~ ` ``, control and non-ASCII characters)
    as a space. A name heard from another simulator may hold any of them; pyais raises
    on them, so every other vessel's name goes through here before it is encoded."""
    return "".join(c if c in SIX_BIT_CHARS else " " for c in text.upper()[:length]).rstrip()


class AisReporter:
    """Own ship and other vessels as AIS sentences, each when its reports are due."""

    def __init__(self, settings: AisSettings) -> None:
        self.settings = settings
        self._next: dict[tuple[str, int], float] = {}  # (vessel key, message type) -> when due, monotonic s
        self._seq = 0

    def _due(self, key: str, msg: int, interval: float, now: float) -> bool:
        if now < self._next.get((key, msg), -math.inf):
            return False
        self._next[(key, msg)] = now + interval
        return True

    def _static(self, mmsi: int, name: str, dims: tuple[int, int, int, int], utc: dt.datetime, sentence: str,
                settings: AisSettings | None) -> list[str]:
        self._seq = (self._seq + 1) % 10
        return static_report(mmsi, name, dims, utc, sentence, self._seq, settings)

    def own_ship(self, state: Moving, now: float, utc: dt.datetime) -> list[str]:
        """The own ship's ``!AIVDO`` reports due at ``now`` (monotonic s)."""
        s, out = self.settings, []
        if self._due("own", 1, report_interval(state.speed_over_ground, state.rate_of_turn), now):
            out += position_report(s.mmsi, state, utc, "VDO")
        if self._due("own", 5, STATIC_PERIOD_S, now):
            dims = (s.to_bow, s.to_stern, s.to_port, s.to_starboard)
            out += self._static(s.mmsi, s.name, dims, utc, "VDO", s)
        return out

    def others(self, vessels: list[Moving], now: float, utc: dt.datetime) -> list[str]:
        """The other vessels' ``!AIVDM`` reports due at ``now``; their dimensions are split
        half to each end and side, as no antenna position is known."""
        if not self.settings.other_vessels:
            return []
        out = []
        for v in vessels:
            if self._due(v.key, 1, report_interval(v.speed_over_ground, v.rate_of_turn), now):
                out += position_report(v.mmsi, v, utc, "VDM")
            if self._due(v.key, 5, STATIC_PERIOD_S, now):
                half_l, half_b = min(511, round(v.length / 2)), min(63, round(v.beam / 2))
                out += self._static(v.mmsi, six_bit_text(v.name), (half_l, half_l, half_b, half_b), utc, "VDM", None)
        keys = {"own"} | {v.key for v in vessels}
        self._next = {k: t for k, t in self._next.items() if k[0] in keys}  # forget vessels gone
        return out
