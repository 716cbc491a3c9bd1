"""A logged track, SI inside (s, rad, m, m/s): what the logs gave (``TrackLog``), cleaned
(``clean``: sorted, impossible jumps skipped, gaps checked) and placed on the ice field
(``TrackPath``), which gives the ship's kinematic pose at any logged time.

Between fixes the position follows a piecewise cubic Hermite curve in the local north/east
frame (Fritsch & Carlson, "Monotone piecewise cubic interpolation", SIAM J. Numer. Anal.
17(2), 1980; scipy's ``CubicHermiteSpline``) through every fix with the velocity the log
gave there (speed over ground along the course over ground); where it gave none, the
derivative of the parabola through the fix and its neighbours (three-point formula, de
Boor, "A Practical Guide to Splines", 1978, ch. IV). A sparse log (AIS archives, one report
a minute) so replays as a ship moving between its fixes, not one that waits and jumps. Fixes further apart than ``max_gap`` are a gap, interpolated like any other interval unless
it is long for the vessel's speed (it would run over ``max_run`` m through it) or the data
contradicts itself there (the curve's speed leaves the logged speeds at its ends by more
than the tolerance and the noise allow: the fixes' distance is impossible at the logged
speeds). Such a gap is held (the ship waits at the last fix, at rest, until the next) and
listed with the reason. Heading comes from the log's heading (HDT, THS, HDG, AIS, a CSV
column), failing that its course over ground, failing that the track's own velocity; it is
interpolated linearly on the circle (the shorter way round) and held through held gaps."""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from bridge_node.replay.settings import GAP_SPEED_TOLERANCE, MAX_GAP_RUN_M, ReplaySettings
from sim_core.frames.geodesy import geodetic_to_local, radii
from sim_core.frames.ship_frame import world_vector_to_ship
from sim_core.frames.units import KNOT
from sim_core.world import Controls, KinematicPose

MIN_COURSE_SPEED = 0.5 * KNOT  # m/s: slower than this, course over ground is noise
MATCH_S = 1.0  # s: a speed or course sample this close to a fix is the fix's
POSITION_NOISE = 10.0  # m: a fix's error, AIS "high accuracy" (ITU-R M.1371) and plain GNSS
SPEED_NOISE = 0.5 * KNOT  # m/s: a logged speed's error (AIS rounds to 0.1 kn; GNSS SOG noise)
GAP_SAMPLES = 32  # points per gap at which the interpolated speed is checked


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
    """Fixes further apart than the gap limit, from start to end (s). ``reason``: why it
    was held (``long`` or ``contradicted``, with the figures), empty when interpolated;
    ``run``: the distance (m) the vessel would cover through it at its logged speed."""

    start: float
    end: float
    reason: str = ""
    run: float = 0.0


@dataclass(frozen=True)
class Jump:
    """A fix skipped at time t (s): ``distance`` (m) from the last good fix implies ``speed`` (m/s)."""

    time: float
    distance: float
    speed: float


@dataclass
class Series:
    """Samples of a quantity against time (s), for interpolation; angles unwrapped (so
    that linear interpolation goes the shorter way round the circle). ``held``: per
    interval between samples, whether it overlaps a held gap (see ``hold``)."""

    t: np.ndarray
    value: np.ndarray
    held: np.ndarray | None = None

    @classmethod
    def of(cls, samples: list[tuple[float, float]], angle: bool = False) -> Series | None:
        """Sorted samples with one per time (the first), or None if there are none."""
        if not samples:
            return None
        a = np.array(sorted(samples, key=lambda s: s[0]), dtype=float)
        keep = np.concatenate([[True], np.diff(a[:, 0]) > 0.0])
        a = a[keep]
        return cls(a[:, 0], np.unwrap(a[:, 1]) if angle else a[:, 1])

    def hold(self, gaps: list[Gap]) -> Series:
        """This series held through the intervals between samples that overlap the gaps."""
        self.held = np.zeros(max(len(self.t) - 1, 0), dtype=bool)
        for g in gaps:
            lo = max(int(np.searchsorted(self.t, g.start, side="right")) - 1, 0)
            self.held[lo:int(np.searchsorted(self.t, g.end, side="left"))] = True
        return self

    def at(self, q: float, max_gap: float | None = None) -> tuple[float, float]:
        """Value and rate of change (per s) at time q: linear between samples however far
        apart (at the first, the first interval's rate), held (rate 0) before the first,
        after the last and on held intervals. ``max_gap`` is ignored: ``hold`` decides."""
        t, v = self.t, self.value
        if len(t) == 1 or q < t[0]:
            return float(v[0]), 0.0
        if q >= t[-1]:
            return float(v[-1]), 0.0
        i = int(np.searchsorted(t, q, side="right")) - 1
        if self.held is not None and self.held[i]:
            return float(v[i]), 0.0
        rate = (v[i + 1] - v[i]) / (t[i + 1] - t[i])
        return float(v[i] + (q - t[i]) * rate), float(rate)


@dataclass
class Track:
    """A cleaned track: fixes (t s, latitude and longitude rad) in time order without
    impossible jumps, the heading series and where it came from, the held gaps (``gaps``)
    and the interpolated ones (``bridged``), the jumps, and the velocity at each fix
    (north, east m/s: the Hermite curve's tangents)."""

    log: TrackLog
    t: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    heading: Series
    heading_source: str  # "heading", "course" or "track"
    speed: Series | None
    gaps: list[Gap]
    jumps: list[Jump]
    velocity: np.ndarray | None = None
    bridged: list[Gap] = field(default_factory=list)

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


def estimated_velocity(t: np.ndarray, ne: np.ndarray) -> np.ndarray:
    """Velocity (m/s, rows north, east) at each time t (s) of the points ne (m): the
    derivative of the parabola through a point and its two neighbours (three-point
    formula on an uneven grid), the chord's slope at the two ends; zero for one point."""
    v = np.zeros_like(ne, dtype=float)
    if len(t) < 2:
        return v
    h = np.diff(t)
    slope = np.diff(ne, axis=0) / h[:, None]
    v[0], v[-1] = slope[0], slope[-1]
    w = (h[1:] / (h[:-1] + h[1:]))[:, None]  # weight of the slope before: the longer the one after
    v[1:-1] = w * slope[:-1] + (1.0 - w) * slope[1:]
    return v


def _matched(series: Series | None, t: np.ndarray) -> np.ndarray:
    """The sample of series nearest each time t (s), NaN where none is within MATCH_S."""
    out = np.full(len(t), np.nan)
    if series is None:
        return out
    j = np.searchsorted(series.t, t)
    lo, hi = np.clip(j - 1, 0, len(series.t) - 1), np.clip(j, 0, len(series.t) - 1)
    pick = np.where(np.abs(series.t[lo] - t) <= np.abs(series.t[hi] - t), lo, hi)
    near = np.abs(series.t[pick] - t) <= MATCH_S
    out[near] = series.value[pick][near]
    return out


def fix_velocity(log: TrackLog, t: np.ndarray, ne: np.ndarray) -> np.ndarray:
    """Velocity at each fix (m/s, rows north, east): the logged speed over ground along the
    logged course; the estimated velocity's direction where no course was logged (slow, or
    not in the log) and its size where no speed was."""
    estimate = estimated_velocity(t, ne)
    speed, course = _matched(Series.of(log.speed), t), _matched(Series.of(log.course), t)
    size = np.where(np.isfinite(speed), speed, np.hypot(estimate[:, 0], estimate[:, 1]))
    direction = np.where(np.isfinite(course), course, np.arctan2(estimate[:, 1], estimate[:, 0]))
    return size[:, None] * np.column_stack([np.cos(direction), np.sin(direction)])


def _check_gaps(t: np.ndarray, ne: np.ndarray, velocity: np.ndarray, max_gap: float, max_run: float,
                tolerance: float) -> list[Gap]:
    """Every gap (fixes further apart than max_gap s) with the reason to hold it, if any:
    ``long`` when the vessel would run more than max_run m through it, at the faster of its
    end speeds or the straight line's mean speed; ``contradicted`` when the Hermite curve's
    speed anywhere in it leaves [slower end speed (1 - tolerance), faster (1 + tolerance)]
    by more than the noise of the logged speeds and of the two fixes allows."""
    idx = np.nonzero(np.diff(t) > max_gap)[0]
    if not len(idx):
        return []
    span = t[idx + 1] - t[idx]
    s = np.linspace(0.0, 1.0, GAP_SAMPLES + 1)
    rate = CubicHermiteSpline(t, ne, velocity).derivative()
    curve = np.hypot(*np.moveaxis(rate(t[idx, None] + s[None, :] * span[:, None]), -1, 0))
    ends = np.hypot(velocity[:, 0], velocity[:, 1])
    fast, slow = np.maximum(ends[idx], ends[idx + 1]), np.minimum(ends[idx], ends[idx + 1])
    chord = np.hypot(*(ne[idx + 1] - ne[idx]).T)
    run = np.maximum(fast * span, chord)
    noise = SPEED_NOISE + 1.5 * 2.0 * POSITION_NOISE / span  # a cubic's peak speed moves 1.5x a chord error
    high, low, gaps = curve.max(axis=1), curve.min(axis=1), []
    for k, i in enumerate(idx):
        if run[k] > max_run:
            why = f"long: {run[k]:.0f} m at {run[k] / span[k] / KNOT:.1f} kn over {max_run:.0f} m"
        elif high[k] > fast[k] * (1.0 + tolerance) + noise[k]:
            why = f"contradicted: {high[k] / KNOT:.1f} kn needed, {fast[k] / KNOT:.1f} kn logged"
        elif low[k] < slow[k] * (1.0 - tolerance) - noise[k]:
            why = f"contradicted: {low[k] / KNOT:.1f} kn needed, {slow[k] / KNOT:.1f} kn logged"
        else:
            why = ""
        gaps.append(Gap(float(t[i]), float(t[i + 1]), why, float(run[k])))
    return gaps


def _heading(log: TrackLog, t: np.ndarray, velocity: np.ndarray) -> tuple[Series, str]:
    """The heading series and its source: the logged heading, the logged course, or the
    direction of the velocity at the fixes where the vessel moved."""
    heading = Series.of(log.heading, angle=True)
    if heading is not None:
        return heading, "heading"
    course = Series.of(log.course, angle=True)
    if course is not None:
        return course, "course"
    moving = np.hypot(velocity[:, 0], velocity[:, 1]) >= MIN_COURSE_SPEED
    track = Series.of(list(zip(t[moving], np.arctan2(velocity[moving, 1], velocity[moving, 0]))), angle=True)
    return track or Series(np.array([t[0]]), np.array([0.0])), "track"


def clean(log: TrackLog, max_gap: float, max_speed: float, max_run: float = MAX_GAP_RUN_M,
          tolerance: float = GAP_SPEED_TOLERANCE) -> Track | None:
    """The log's fixes in time order (one per time), impossible jumps (faster than
    max_speed m/s) skipped, the velocity at each fix, and the gaps (fixes more than
    max_gap s apart) checked: held when long (over max_run m) or contradicted (speed off
    by more than the fraction ``tolerance``), else interpolated. None if it has no fix."""
    if not log.fixes:
        return None
    a = np.array(sorted(log.fixes, key=lambda f: f[0]), dtype=float)
    a = a[np.concatenate([[True], np.diff(a[:, 0]) > 0.0])]  # RMC and GGA of one fix: the first
    a, jumps = _skip_jumps(a, max_speed)
    t, lat, lon = a[:, 0], a[:, 1], a[:, 2]
    ne = np.column_stack(geodetic_to_local(lat, lon, lat[0], lon[0]))
    velocity = fix_velocity(log, t, ne)
    checked = _check_gaps(t, ne, velocity, max_gap, max_run, tolerance)
    held = [g for g in checked if g.reason]
    heading, source = _heading(log, t, velocity)
    return Track(log, t, lat, lon, heading.hold(held), source, Series.of(log.speed), held, jumps, velocity,
                 [g for g in checked if not g.reason])


def clean_for(log: TrackLog, settings: ReplaySettings) -> Track | None:
    """``clean`` with the limits of the ``[replay]`` settings."""
    return clean(log, settings.max_gap_s, settings.max_speed_kn * KNOT, settings.max_gap_run_m,
                 settings.gap_speed_tolerance)


def origin_under(lat: float, lon: float, north: float, east: float) -> tuple[float, float]:
    """Latitude and longitude (rad) of the field's south-west corner that puts the point
    (lat, lon) at (north, east) metres from it."""
    lat0 = lat
    for _ in range(4):  # the radii depend on the origin's latitude: converges at once
        m, _n = radii(lat0)
        lat0 = lat - north / m
    _m, n = radii(lat0)
    return lat0, lon - east / (n * math.cos(lat0))


class _Coordinate(Series):
    """North or east (m) of a placed track against time: ``at`` gives the Hermite curve's
    value and rate (``max_gap`` ignored: the track's held gaps rule)."""

    def __init__(self, path: TrackPath, axis: int) -> None:
        super().__init__(path.track.t, path.local[:, axis])
        self.path, self.axis = path, axis

    def at(self, q: float, max_gap: float | None = None) -> tuple[float, float]:
        position, velocity = self.path.state(q)
        return float(position[self.axis]), float(velocity[self.axis])


class TrackPath:
    """A cleaned track placed on the field: the ship's pose at any logged time, on the
    track's Hermite curve, held through its held gaps. ``max_gap`` is kept for callers."""

    def __init__(self, track: Track, origin: tuple[float, float], max_gap: float) -> None:
        self.track, self.max_gap = track, max_gap
        self.local = np.column_stack(geodetic_to_local(track.lat, track.lon, *origin))
        velocity = track.velocity if track.velocity is not None else estimated_velocity(track.t, self.local)
        self._curve = CubicHermiteSpline(track.t, self.local, velocity) if len(track.t) > 1 else None
        self._rate = self._curve.derivative() if self._curve is not None else None
        self._held = np.isin(track.t[:-1], [g.start for g in track.gaps])
        self.north, self.east = _Coordinate(self, 0), _Coordinate(self, 1)

    def state(self, q: float) -> tuple[np.ndarray, np.ndarray]:
        """Position and velocity (north, east: m and m/s) at logged time q (s): held
        before the first fix, after the last and through held gaps (velocity 0 there)."""
        t = self.track.t
        if len(t) == 1 or q < t[0]:
            return self.local[0], np.zeros(2)
        if q >= t[-1]:
            return self.local[-1], np.zeros(2)
        i = int(np.searchsorted(t, q, side="right")) - 1
        if self._held[i]:
            return self.local[i], np.zeros(2)
        return self._curve(q), self._rate(q)

    def position(self, t: float) -> tuple[float, float]:
        """North and east (m) at logged time t."""
        return tuple(float(x) for x in self.state(t)[0])

    def pose(self, t: float, dt: float) -> KinematicPose:
        """The pose at the end (t, s) of a step of dt s, with the velocity and turn rate at
        the step's middle (zero through a held gap)."""
        mid = t - 0.5 * dt
        north, east = self.position(t)
        vn, ve = self.state(mid)[1]
        psi = self.track.heading.at(t, self.max_gap)[0] % (2.0 * math.pi)
        surge, sway = world_vector_to_ship((float(ve), float(vn)), psi)
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

    def commands(self, k: int) -> tuple:
        return ()  # a track log holds no instructor commands
