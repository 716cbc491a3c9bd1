"""A logged track, SI inside (s, rad, m, m/s): what the logs gave (``TrackLog``), cleaned
(``clean``: sorted, impossible jumps skipped, gaps marked) and placed on the ice field
(``TrackPath``), which gives the ship's kinematic pose at any logged time.

Between fixes the position is interpolated linearly; through a gap longer than the
configured limit the last state is held (the ship waits at the last fix, at rest) until the
fix after the gap. Heading comes from the log's heading (HDT, THS, HDG, AIS, a CSV column),
failing that from its course over ground, failing that from the track itself.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from sim_core.frames.geodesy import geodetic_to_local, radii
from sim_core.frames.ship_frame import world_vector_to_ship
from sim_core.frames.units import KNOT
from sim_core.world import Controls, KinematicPose

MIN_COURSE_SPEED = 0.5 * KNOT  # m/s: slower than this, course over ground is noise
MIN_TRACK_LEG = 0.5  # m: shorter legs give no course


@dataclass
class TrackLog:
    """What logs gave. Times in s (unix seconds when ``absolute``, else from an unknown
    start), angles in rad, speeds in m/s. Fixes are (t, latitude, longitude); the series
    (t, value). ``read`` counts what was used by kind, ``ignored`` the well-formed records
    not needed (sentence types), ``bad`` what was wrong by kind."""

    files: list[str]
    fixes: list[tuple[float, float, float]] = field(default_factory=list)
    heading: list[tuple[float, float]] = field(default_factory=list)  # true heading
    course: list[tuple[float, float]] = field(default_factory=list)  # over ground, when moving
    speed: list[tuple[float, float]] = field(default_factory=list)  # over ground
    absolute: bool = True
    vessel: str | None = None  # the AIS vessel replayed: MMSI and name
    others: list = field(default_factory=list)  # the log's other AIS vessels (``sentences.Vessel``): traffic
    read: Counter = field(default_factory=Counter)
    ignored: Counter = field(default_factory=Counter)
    bad: Counter = field(default_factory=Counter)

    def add_motion(self, t: float, course: float | None, speed: float | None) -> None:
        """Course (rad) and speed (m/s) over ground at t; a course is kept only when the
        speed is unknown or high enough to give one."""
        if speed is not None and math.isfinite(speed):
            self.speed.append((t, speed))
        if course is not None and math.isfinite(course) and (speed is None or speed >= MIN_COURSE_SPEED):
            self.course.append((t, course))

    def merge(self, other: TrackLog) -> None:
        """Add another log's records (another file of the same voyage)."""
        self.files += other.files
        for name in ("fixes", "heading", "course", "speed"):
            getattr(self, name).extend(getattr(other, name))
        self.absolute = self.absolute and other.absolute
        self.vessel = self.vessel or other.vessel
        self.others += other.others
        self.read.update(other.read)
        self.ignored.update(other.ignored)
        self.bad.update(other.bad)


@dataclass(frozen=True)
class Gap:
    """Fixes further apart than the gap limit: the last state was held from start to end (s)."""

    start: float
    end: float


@dataclass(frozen=True)
class Jump:
    """A fix skipped at time t (s): ``distance`` (m) from the last good fix implies ``speed`` (m/s)."""

    time: float
    distance: float
    speed: float


@dataclass
class Series:
    """Samples of a quantity against time (s), for interpolation; angles unwrapped."""

    t: np.ndarray
    value: np.ndarray

    @classmethod
    def of(cls, samples: list[tuple[float, float]], angle: bool = False) -> Series | None:
        """Sorted samples with one per time (the first), or None if there are none."""
        if not samples:
            return None
        a = np.array(sorted(samples, key=lambda s: s[0]), dtype=float)
        keep = np.concatenate([[True], np.diff(a[:, 0]) > 0.0])
        a = a[keep]
        return cls(a[:, 0], np.unwrap(a[:, 1]) if angle else a[:, 1])

    def at(self, q: float, max_gap: float) -> tuple[float, float]:
        """Value and rate of change (per s) at time q: linear between samples (at the first,
        the first interval's rate), held before the first, after the last and through gaps
        longer than max_gap (rate 0 there)."""
        t, v = self.t, self.value
        if len(t) == 1 or q < t[0]:
            return float(v[0]), 0.0
        if q >= t[-1]:
            return float(v[-1]), 0.0
        i = int(np.searchsorted(t, q, side="right")) - 1
        span = t[i + 1] - t[i]
        if span > max_gap:
            return float(v[i]), 0.0
        rate = (v[i + 1] - v[i]) / span
        return float(v[i] + (q - t[i]) * rate), float(rate)


@dataclass
class Track:
    """A cleaned track: fixes (t s, latitude and longitude rad) in time order without
    impossible jumps, the heading series and where it came from, the gaps and jumps."""

    log: TrackLog
    t: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    heading: Series
    heading_source: str  # "heading", "course" or "track"
    speed: Series | None
    gaps: list[Gap]
    jumps: list[Jump]

    @property
    def start(self) -> float:
        return float(self.t[0])

    @property
    def end(self) -> float:
        return float(self.t[-1])


def _distance(lat_a: float, lon_a: float, lat_b: float, lon_b: float) -> float:
    """Metres between two nearby points (local tangent plane at the first)."""
    north, east = geodetic_to_local(lat_b, lon_b, lat_a, lon_a)
    return math.hypot(north, east)


def _skip_jumps(fixes: np.ndarray, max_speed: float) -> tuple[np.ndarray, list[Jump]]:
    """Fixes (rows t, lat, lon, in time order) without those farther from the last good fix
    than max_speed (m/s) allows; a bad first fix (impossible to the second, while the
    second and third agree) is dropped too."""
    def speed(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
        d = _distance(a[1], a[2], b[1], b[2])
        return d, d / max(b[0] - a[0], 1e-9)

    jumps = []
    start = 0
    while len(fixes) - start >= 3 and speed(fixes[start], fixes[start + 1])[1] > max_speed >= \
            speed(fixes[start + 1], fixes[start + 2])[1]:
        d, v = speed(fixes[start], fixes[start + 1])
        jumps.append(Jump(float(fixes[start, 0]), d, v))
        start += 1
    keep = [start]
    for i in range(start + 1, len(fixes)):
        d, v = speed(fixes[keep[-1]], fixes[i])
        if v > max_speed:
            jumps.append(Jump(float(fixes[i, 0]), d, v))
        else:
            keep.append(i)
    return fixes[keep], sorted(jumps, key=lambda j: j.time)


def _track_course(t: np.ndarray, north: np.ndarray, east: np.ndarray, max_gap: float) -> list[tuple[float, float]]:
    """Course of each leg between fixes (rad), at the leg's middle; gaps and legs too short
    to show a direction give none."""
    out = []
    for i in range(len(t) - 1):
        dn, de = north[i + 1] - north[i], east[i + 1] - east[i]
        if t[i + 1] - t[i] <= max_gap and math.hypot(dn, de) >= MIN_TRACK_LEG:
            out.append((0.5 * (t[i] + t[i + 1]), math.atan2(de, dn)))
    return out


def clean(log: TrackLog, max_gap: float, max_speed: float) -> Track | None:
    """The log's fixes in time order (one per time), impossible jumps skipped, gaps
    longer than max_gap (s) marked, and a heading series; None if it has no fix."""
    if not log.fixes:
        return None
    a = np.array(sorted(log.fixes, key=lambda f: f[0]), dtype=float)
    a = a[np.concatenate([[True], np.diff(a[:, 0]) > 0.0])]  # RMC and GGA of one fix: the first
    a, jumps = _skip_jumps(a, max_speed)
    t, lat, lon = a[:, 0], a[:, 1], a[:, 2]
    gaps = [Gap(float(t[i]), float(t[i + 1])) for i in np.nonzero(np.diff(t) > max_gap)[0]]
    heading, source = Series.of(log.heading, angle=True), "heading"
    if heading is None:
        heading, source = Series.of(log.course, angle=True), "course"
    if heading is None:
        north, east = zip(*(geodetic_to_local(p, q, lat[0], lon[0]) for p, q in zip(lat, lon)))
        heading = Series.of(_track_course(t, np.array(north), np.array(east), max_gap), angle=True) or \
            Series(np.array([t[0]]), np.array([0.0]))
        source = "track"
    return Track(log, t, lat, lon, heading, source, Series.of(log.speed), gaps, jumps)


def origin_under(lat: float, lon: float, north: float, east: float) -> tuple[float, float]:
    """Latitude and longitude (rad) of the field's south-west corner that puts the point
    (lat, lon) at (north, east) metres from it."""
    lat0 = lat
    for _ in range(4):  # the radii depend on the origin's latitude: converges at once
        m, _n = radii(lat0)
        lat0 = lat - north / m
    _m, n = radii(lat0)
    return lat0, lon - east / (n * math.cos(lat0))


class TrackPath:
    """A cleaned track placed on the field: the ship's pose at any logged time."""

    def __init__(self, track: Track, origin: tuple[float, float], max_gap: float) -> None:
        self.track, self.max_gap = track, max_gap
        local = np.array([geodetic_to_local(p, q, *origin) for p, q in zip(track.lat, track.lon)])
        self.north, self.east = Series(track.t, local[:, 0]), Series(track.t, local[:, 1])

    def position(self, t: float) -> tuple[float, float]:
        """North and east (m) at logged time t."""
        return self.north.at(t, self.max_gap)[0], self.east.at(t, self.max_gap)[0]

    def pose(self, t: float, dt: float) -> KinematicPose:
        """The pose at the end (t, s) of a step of dt s, with the step's velocity and turn
        rate (zero through a held gap)."""
        mid = t - 0.5 * dt
        north, east = self.position(t)
        vn, ve = self.north.at(mid, self.max_gap)[1], self.east.at(mid, self.max_gap)[1]
        psi = self.track.heading.at(t, self.max_gap)[0] % (2.0 * math.pi)
        surge, sway = world_vector_to_ship((ve, vn), psi)
        return KinematicPose(north, east, psi, surge, sway, self.track.heading.at(mid, self.max_gap)[1])


class TrackSource:
    """A replay source: steps of dt s along a placed track from logged time t0 to t1 (s),
    the ship driven kinematically; the links' clock is the logged time."""

    def __init__(self, path: TrackPath, t0: float, t1: float, dt: float) -> None:
        self.path, self.t0, self.dt = path, t0, dt
        self.steps = max(1, math.ceil((t1 - t0) / dt - 1e-9))
        self.absolute = path.track.log.absolute

    def logged_time(self, k: int) -> float:
        return self.t0 + k * self.dt

    def inputs(self, k: int) -> tuple[Controls, list, float]:
        t = self.t0 + (k + 1) * self.dt
        return Controls(kinematic=self.path.pose(t, self.dt)), [], t
