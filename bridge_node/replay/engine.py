"""The replay loop: steps the world along a source (a track driven kinematically, or a
session re-simulated), paced to a speed factor of logged time or as fast as possible,
with pause, faster, slower and seek forward, and the outputs of a run.

Every step's ship state goes to the configured links (their output rates follow the
logged clock) and every step's events to the state stream the render processes draw.
A seek runs the world ahead to its target without outputs, so the ice there is what the
voyage left, then sends the render processes a snapshot.
"""
from __future__ import annotations

import csv
import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from bridge_node.links.base import Alarm
from bridge_node.links.hub import LinkHub
from bridge_node.node.order_refusals import OrderRefusals
from bridge_node.stream.publisher import StatePublisher
from sim_core.frames.geodesy import local_to_geodetic
from sim_core.frames.units import KNOT
from sim_core.ice.floes import BreakCause
from sim_core.ice.tiles import broken_counts
from sim_core.ship.resistance import BROKEN_CHANNEL, LEVEL_ICE, OPEN_WATER
from sim_core.world import Controls, WorldData, WorldEvents, WorldModel, snapshot, step

MIN_SPEED, MAX_SPEED = 1.0, 1000.0  # speed factors of logged time a paced replay allows
SEEK_STEPS_S = {"f": 60.0, "F": 600.0, "right": 60.0}  # key -> logged seconds a seek jumps ahead
BEHIND_S = 1.0  # wall s behind the schedule after which it restarts from now (no burst)
CONDITIONS = {LEVEL_ICE: "level_ice", BROKEN_CHANNEL: "broken_channel", OPEN_WATER: "open_water"}


class Source(Protocol):
    """What a replay steps along: ``steps`` steps of ``dt`` s; logged time (s: unix when
    ``absolute``) at the start of step k; the orders for step k (a kinematic pose, or the
    console's), alarm changes, and the links' clock (s)."""

    dt: float
    steps: int
    absolute: bool

    def logged_time(self, k: int) -> float: ...

    def inputs(self, k: int) -> tuple[Controls | None, list[Alarm], float]: ...


@dataclass
class Playback:
    """How the replay runs: speed factor of logged time (None: as fast as possible),
    paused, the step a seek runs ahead to, and whether to stop."""

    speed: float | None
    paused: bool = False
    seek_to: int = 0
    stop: bool = False

    def key(self, key: str, step: int, dt: float) -> None:
        """Apply one key: space pause, + faster, - slower, f / right seek 1 min, F 10 min, q quit."""
        if key == " ":
            self.paused = not self.paused
        elif key in ("+", "=", ">"):
            self.speed = None if self.speed is None or self.speed * 2.0 > MAX_SPEED else self.speed * 2.0
        elif key in ("-", "<"):
            self.speed = MAX_SPEED if self.speed is None else max(MIN_SPEED, self.speed / 2.0)
        elif key in SEEK_STEPS_S:
            self.seek_to = max(self.seek_to, step) + round(SEEK_STEPS_S[key] / dt)
        elif key == "q":
            self.stop = True


@dataclass
class ReplayStats:
    """What the replay did: per step (logged time s, north m, east m, heading rad, speed
    over ground m/s, ice condition), time per ice condition (s), the stretches off the
    field (logged s), distance (m), wall time (s), and the cells broken."""

    rows: list = field(default_factory=list)
    time_in: Counter = field(default_factory=Counter)
    off_field: list[list[float]] = field(default_factory=list)
    distance: float = 0.0
    steps: int = 0
    wall_s: float = 0.0
    sim_s: float = 0.0
    refusals: OrderRefusals = field(default_factory=OrderRefusals)
    console_orders_ignored: int = 0
    broken_by_hull: int = 0
    broken_by_contact: int = 0

    def samples(self) -> np.ndarray:
        """The per-step rows as an (n, 6) array."""
        return np.array(self.rows, dtype=float).reshape(-1, 6)

    def write_csv(self, path: Path, origin: tuple[float, float]) -> Path:
        """The replayed track, one row per step (at its end): logged time (s), latitude and
        longitude (deg), north and east (m) from the field's corner at ``origin`` (lat, lon
        rad), heading (deg), speed over ground (kn), ice under the bow."""
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "w", newline="", encoding="ascii") as f:
            out = csv.writer(f)
            out.writerow(["time", "latitude_deg", "longitude_deg", "north_m", "east_m", "heading_deg", "sog_kn", "ice"])
            for t, north, east, heading, sog, condition in self.rows:
                lat, lon = local_to_geodetic(north, east, *origin)
                out.writerow([f"{t:.3f}", f"{math.degrees(lat):.9f}", f"{math.degrees(lon):.9f}", f"{north:.3f}",
                              f"{east:.3f}", f"{math.degrees(heading):.3f}", f"{sog / KNOT:.3f}",
                              CONDITIONS[condition]])
        return path


class Outputs:
    """The replay's outputs: the configured links (polled only to keep them up; a live
    console's orders are counted and ignored) and the state stream. The links run on the
    source's clock, moved to start at this process's monotonic clock (their own timers,
    a serial line's budget say, started on it). The hub's traffic picture goes on the
    stream too, placed on the field whose corner is at ``origin`` (latitude, longitude rad)."""

    def __init__(self, hub: LinkHub | None, publisher: StatePublisher | None,
                 origin: tuple[float, float]) -> None:
        self.hub, self.publisher, self.origin = hub, publisher, origin
        self._offset: float | None = None  # monotonic s - source clock s

    def publish(self, events: WorldEvents, clock: float, alarms: list[Alarm], stats: ReplayStats,
                send: bool = True) -> None:
        """One step's alarm changes, and unless not ``send`` (a seek) its events, out at the
        source's clock (s)."""
        if self._offset is None:
            self._offset = time.monotonic() - clock
        now = clock + self._offset
        if self.hub is not None:
            for alarm in alarms:  # raised while seeking too: announced once it ends
                self.hub.raise_alarm(alarm, now)
            if send:
                for link in self.hub.links:
                    stats.console_orders_ignored += len(link.poll(now))
                self.hub.publish(events.ship, now)
        if self.publisher is not None and send:
            self.publisher.publish(events, traffic=self.hub.traffic.table(self.origin) if self.hub else None)

    def resync(self, model: WorldModel, data: WorldData) -> None:
        """After a seek: the whole state to the stream (render processes take it as a snapshot)."""
        if self.publisher is not None:
            self.publisher.publish(snapshot(model, data))


def _note(stats: ReplayStats, model: WorldModel, data: WorldData, events: WorldEvents, logged: float,
          dt: float) -> None:
    """Add one step to the statistics."""
    s, scene = events.ship, model.scene
    if stats.rows:
        stats.distance += math.hypot(s.north - stats.rows[-1][1], s.east - stats.rows[-1][2])
    stats.rows.append((logged, s.north, s.east, s.heading, s.speed_over_ground, data.ship.ice_condition))
    stats.time_in[CONDITIONS[data.ship.ice_condition]] += dt
    off = not (0.0 <= s.north <= scene.ny * scene.side and 0.0 <= s.east <= scene.nx * scene.side)
    if off and stats.off_field and stats.off_field[-1][1] >= logged - 1.5 * dt:
        stats.off_field[-1][1] = logged
    elif off:
        stats.off_field.append([logged, logged])


def run_replay(model: WorldModel, data: WorldData, source: Source, playback: Playback, outputs: Outputs,
               show: Callable[[int, ReplayStats, Playback], list[str]] | None = None) -> ReplayStats:
    """Step the world along the source until its end, ``playback.stop`` or Ctrl-C. Steps
    before ``playback.seek_to`` run ahead without outputs. ``show(k, stats, playback)``
    is called about every 0.2 s of wall time (and while paused) and returns the keys
    pressed since."""
    stats = ReplayStats()
    start = anchor_wall = time.monotonic()
    anchor_k, anchor_speed, shown, seeking = 0, playback.speed, 0.0, playback.seek_to > 0
    k = 0
    try:
        while k < source.steps and not playback.stop:
            now_wall = time.monotonic()
            if show is not None and (now_wall - shown >= 0.2 or playback.paused):
                shown = now_wall
                for key in show(k, stats, playback):
                    playback.key(key, k, source.dt)
            if playback.paused:
                time.sleep(0.05)
                anchor_wall, anchor_k = time.monotonic(), k
                continue
            if seeking and k >= playback.seek_to:  # arrived: the render processes resynchronise
                outputs.resync(model, data)
                anchor_wall, anchor_k = time.monotonic(), k
            seeking = k < playback.seek_to
            if playback.speed != anchor_speed:
                anchor_wall, anchor_k, anchor_speed = time.monotonic(), k, playback.speed
            controls, alarms, now = source.inputs(k)
            events = step(model, data, source.dt, controls)
            logged = source.logged_time(k) + source.dt
            _note(stats, model, data, events, logged, source.dt)
            alarms = alarms + stats.refusals.note(events.rejected, now)
            k += 1
            outputs.publish(events, now, alarms, stats, send=not seeking)
            if seeking:
                continue
            if playback.speed is not None:
                due = anchor_wall + (k - anchor_k) * source.dt / playback.speed
                wait = due - time.monotonic()
                if wait > 0.0:
                    time.sleep(wait)
                elif wait < -BEHIND_S:  # fell behind: restart the schedule rather than burst
                    anchor_wall, anchor_k = time.monotonic(), k
    except KeyboardInterrupt:
        pass
    stats.steps, stats.sim_s, stats.wall_s = k, k * source.dt, time.monotonic() - start
    broken = broken_counts(data.ice)
    stats.broken_by_hull, stats.broken_by_contact = int(broken[BreakCause.HULL]), int(broken[BreakCause.CONTACT])
    return stats
