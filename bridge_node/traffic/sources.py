"""Where the traffic picture's own vessels come from: the config's scripted vessels
(``ScriptedTraffic``), AIS logs replayed (``AisLogTraffic``) and, in ``icebridge replay``,
a session record's DIS traffic (``DisLogTraffic``). Each starts at its first ``vessels``
call (the first tick that publishes) and keeps to the node's monotonic clock, as the DIS
link's dead reckoning does; SI inside (m, m/s, rad).
"""
from __future__ import annotations

import contextlib
import math
from collections import Counter
from collections.abc import Iterable, Sequence

import numpy as np

from bridge_node.links.dis.kind import DIS, DisRecord, read_dis_log
from bridge_node.links.dis.link import HeardEntities, PduError
from bridge_node.links.dis.settings import DisLinkSettings
from bridge_node.links.messages import Vessel
from bridge_node.links.settings import LinkSettingsBase
from bridge_node.links.traffic_picture import TrafficPicture
from bridge_node.replay.engine import Source
from bridge_node.replay.sentences import Vessel as LoggedVessel
from bridge_node.replay.session import SessionSource
from bridge_node.replay.settings import ReplaySettings
from bridge_node.replay.track import TrackPath, TrackSource, clean_for
from bridge_node.traffic.settings import ScriptedVessel
from sim_core.frames.geodesy import local_to_geodetic
from sim_core.frames.units import KNOT


class _Clock:
    """Seconds since the first call of ``since_start`` (monotonic ``now``, s)."""

    _start: float | None = None

    def since_start(self, now: float) -> float:
        if self._start is None:
            self._start = now
        return now - self._start


class ScriptedMotion:
    """Kinematics of one scripted vessel: along its waypoints at constant speed (legs joined
    by instant turns), or straight on from its start; ``at(t)`` gives north, east (m),
    course (rad) and speed (m/s) t s after the start."""

    def __init__(self, s: ScriptedVessel) -> None:
        self.speed = s.speed_kn * KNOT
        points = s.waypoints + s.waypoints[:1] if s.loop else s.waypoints or [[s.north, s.east]]
        self.points = np.array(points, dtype=float)
        legs = np.diff(self.points, axis=0)
        self.legs, self.courses = legs, np.arctan2(legs[:, 1], legs[:, 0]) % (2 * math.pi)
        self.reach = np.concatenate([[0.0], np.cumsum(np.hypot(legs[:, 0], legs[:, 1]))])  # m to each point
        self.loop, self.course = s.loop, math.radians(s.course_deg or 0.0)

    def at(self, t: float) -> tuple[float, float, float, float]:
        run = self.speed * t
        if not len(self.legs):  # straight on
            return (self.points[0, 0] + run * math.cos(self.course), self.points[0, 1] + run * math.sin(self.course),
                    self.course, self.speed)
        total = self.reach[-1]
        if self.loop and total > 0.0:
            run %= total
        if run >= total:  # arrived: stopped at the last waypoint
            return self.points[-1, 0], self.points[-1, 1], float(self.courses[-1]), 0.0
        i = int(np.searchsorted(self.reach, run, side="right")) - 1
        north, east = self.points[i] + self.legs[i] * ((run - self.reach[i]) / (self.reach[i + 1] - self.reach[i]))
        return float(north), float(east), float(self.courses[i]), self.speed


class ScriptedTraffic(_Clock):
    """The vessels scripted in the config, on the field whose corner is at ``origin``
    (latitude, longitude rad)."""

    def __init__(self, vessels: Sequence[ScriptedVessel], origin: tuple[float, float]) -> None:
        self.script = [(s, ScriptedMotion(s)) for s in vessels]
        self.origin = origin

    def vessels(self, now: float) -> list[Vessel]:
        t, out = self.since_start(now), []
        for s, motion in self.script:
            north, east, course, speed = motion.at(t)
            lat, lon = local_to_geodetic(north, east, *self.origin)
            out.append(Vessel(f"script:{s.mmsi}", s.mmsi, s.name, now, lat, lon, course, course, speed, 0.0,
                              s.length, s.beam))
        return out


class AisLogTraffic(_Clock):
    """Vessels of an AIS log (``sentences.Vessel``), replayed: at the first call the logged
    time is ``start`` (None: the first position report); each vessel is there from its first
    position report to its last, moving between them as ``TrackPath`` places a replayed
    ship (linear, held through gaps longer than ``replay.max_gap_s``, impossible jumps
    skipped), with the name and dimensions the log gave. A log without times counts each
    vessel's reports on from 0 s by their UTC second."""

    def __init__(self, logged: Iterable[LoggedVessel], origin: tuple[float, float], replay: ReplaySettings,
                 start: float | None = None) -> None:
        self.origin, self.max_gap = origin, replay.max_gap_s
        self.paths = []
        for v in logged:
            track = clean_for(v.track([], Counter()), replay)
            if track is not None:
                self.paths.append((v, TrackPath(track, origin, replay.max_gap_s)))
        self.t0 = start if start is not None else min((path.track.start for _, path in self.paths), default=0.0)

    def vessels(self, now: float) -> list[Vessel]:
        t, out = self.t0 + self.since_start(now), []
        for v, path in self.paths:
            if not path.track.start <= t <= path.track.end:
                continue
            (north, vn), (east, ve) = path.north.at(t, self.max_gap), path.east.at(t, self.max_gap)
            heading, rate = path.track.heading.at(t, self.max_gap)
            lat, lon = local_to_geodetic(north, east, *self.origin)
            out.append(Vessel(f"ais:{v.mmsi}", v.mmsi, v.name, now, lat, lon, heading % (2 * math.pi),
                              math.atan2(ve, vn) % (2 * math.pi), math.hypot(vn, ve), rate, v.length, v.beam))
        return out


class DisLogTraffic(_Clock):
    """The vessels a recorded session heard on DIS (the ``rx`` PDUs of its ``dis.log``),
    played on the record's clock: at the first call the logged time is ``start`` (unix s);
    each PDU is taken as its link (``links``: DIS link settings by name) took it, at its
    logged time, and dead-reckoned from there."""

    def __init__(self, records: Iterable[DisRecord], links: dict[str, DisLinkSettings], start: float) -> None:
        self.records = sorted((r for r in records if r.direction == "rx" and r.link in links),
                              key=lambda r: r.unix_time)
        self.heard = {name: HeardEntities(s) for name, s in links.items()}
        self.t0, self._next = start, 0

    def vessels(self, now: float) -> list[Vessel]:
        t = self.t0 + self.since_start(now)
        while self._next < len(self.records) and self.records[self._next].unix_time <= t:
            r = self.records[self._next]
            self._next += 1
            with contextlib.suppress(PduError):  # the live link counted these
                self.heard[r.link].hear(r.pdu, now - (t - r.unix_time))
        return [v for heard in self.heard.values() for v in heard.vessels(now)]


def replay_traffic(source: Source, first: int, origin: tuple[float, float], replay: ReplaySettings,
                   links: Sequence[LinkSettingsBase]) -> TrafficPicture:
    """The picture of ``icebridge replay``, on the logged clock from step ``first`` (the
    first the links publish): a track log's other AIS vessels; a session record's DIS
    vessels (its ``dis.log``, through the config's DIS ``links``)."""
    if isinstance(source, TrackSource) and source.path.track.log.others:  # its clock: the end of each step
        return TrafficPicture([AisLogTraffic(source.path.track.log.others, origin, replay,
                                             source.logged_time(first) + source.dt)])
    dis = {s.name: s for s in links if s.type == DIS.name}
    if isinstance(source, SessionSource) and dis and (source.session.folder / DIS.record.file).is_file():
        records, _ = read_dis_log(source.session.folder / DIS.record.file)  # a torn or bad line loses only its PDU
        return TrafficPicture([DisLogTraffic(records, dis, source.logged_time(first))])
    return TrafficPicture()
