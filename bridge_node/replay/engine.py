"""The replay loop: steps the world along a source (a track driven kinematically, or a
session re-simulated), paced to a speed factor of logged time or as fast as possible,
with pause, faster, slower and seek forward, and the outputs of a run.

Each step is the exercise's one tick (``bridge_node.exercise.tick``) with the source as its
order source, paced by the one pacer. Every step's ship state goes to the configured links
(their output rates follow the logged clock) and every step's events to the state stream
the render processes draw. A seek runs the world ahead to its target without outputs, so
the ice there is what the voyage left, then sends the render processes a snapshot.
"""
from __future__ import annotations

import csv
import math
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from bridge_node.exercise.listeners import ReplayLinkOutputs, StreamOutput, WorldTraffic
from bridge_node.exercise.fleet import Bridge, fleet_listeners
from bridge_node.exercise.pacer import Pacer
from bridge_node.exercise.tick import ExerciseTick, TickOutcome
from bridge_node.links.arbiter import Decision
from bridge_node.links.messages import Alarm
from bridge_node.links.hub import LinkHub
from bridge_node.exercise.order_refusals import OrderRefusals
from bridge_node.common.output_files import OutputFile
from bridge_node.stream.publisher import StatePublisher
from sim_core.frames.geodesy import local_to_geodetic
from sim_core.frames.units import KNOT
from sim_core.ice.floes import BreakCause
from sim_core.ice.tiles import broken_counts
from sim_core.ship.resistance import BROKEN_CHANNEL, LEVEL_ICE, OPEN_WATER
from sim_core.instructor import Command
from sim_core.world import Controls, WorldData, WorldEvents, WorldModel, snapshot

MIN_SPEED, MAX_SPEED = 1.0, 1000.0  # speed factors of logged time a paced replay allows
SEEK_STEPS_S = {"f": 60.0, "F": 600.0, "right": 60.0}  # key -> logged seconds a seek jumps ahead
BEHIND_S = 1.0  # wall s behind the schedule after which it restarts from now (no burst)
CONDITIONS = {LEVEL_ICE: "level_ice", BROKEN_CHANNEL: "broken_channel", OPEN_WATER: "open_water"}


class Source(Protocol):
    """What a replay steps along: ``steps`` steps of ``dt`` s; logged time (s: unix when
    ``absolute``) at the start of step k; the orders for step k (a kinematic pose, or the
    console's; one per ship in a record of several), alarm changes, and the links' clock (s)."""

    dt: float
    steps: int
    absolute: bool

    def logged_time(self, k: int) -> float: ...

    def inputs(self, k: int) -> tuple[Controls | Sequence[Controls] | None, list[Alarm], float]: ...

    def commands(self, k: int) -> tuple[Command, ...]: ...


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
        with OutputFile(path, "the replayed track (--out)") as tmp, open(tmp, "w", newline="", encoding="ascii") as f:
            out = csv.writer(f)
            out.writerow(["time", "latitude_deg", "longitude_deg", "north_m", "east_m", "heading_deg", "sog_kn", "ice"])
            for t, north, east, heading, sog, condition in self.rows:
                lat, lon = local_to_geodetic(north, east, *origin)
                out.writerow([f"{t:.3f}", f"{math.degrees(lat):.9f}", f"{math.degrees(lon):.9f}", f"{north:.3f}",
                              f"{east:.3f}", f"{math.degrees(heading):.3f}", f"{sog / KNOT:.3f}",
                              CONDITIONS[condition]])
        return path


class StepOrders:
    """A replay source as the tick's order and command source: ``clock`` reads step k's
    inputs and returns its clock, then ``poll`` and ``take`` hand the tick its orders and
    commands, and it moves on to step k+1."""

    def __init__(self, source: Source) -> None:
        self.source, self.k = source, 0
        self._next = Decision(Controls(), [], {})
        self._commands: tuple[Command, ...] = ()

    def clock(self) -> float:
        """Read the next step's inputs; its clock, s."""
        controls, alarms, now = self.source.inputs(self.k)
        self._next = Decision(controls or Controls(), list(alarms), {})
        self._commands = self.source.commands(self.k)
        return now

    def poll(self, now: float) -> Decision:
        self.k += 1
        return self._next

    def take(self, model: WorldModel, data: WorldData) -> tuple[Command, ...]:
        return self._commands


def _stats_listener(stats: ReplayStats, model: WorldModel, data: WorldData,
                    orders: StepOrders) -> Callable[[TickOutcome], None]:
    """A listener adding each step to ``stats`` (logged time at the step's end)."""
    source = orders.source

    def note(outcome: TickOutcome) -> None:
        _note(stats, model, data, outcome.events, source.logged_time(orders.k - 1) + source.dt, source.dt)
    return note


def _note(stats: ReplayStats, model: WorldModel, data: WorldData, events: WorldEvents, logged: float,
          dt: float) -> None:
    """Add one step to the statistics."""
    s, scene = events.ship, model.scene
    if stats.rows:
        stats.distance += math.hypot(s.north - stats.rows[-1][1], s.east - stats.rows[-1][2])
    stats.rows.append((logged, s.north, s.east, s.heading, s.speed_over_ground, data.ship.ice_condition))
    stats.time_in[CONDITIONS[data.ship.ice_condition]] += dt
    east, north = s.east - events.ice_offset[0], s.north - events.ice_offset[1]  # on the field, where it has drifted
    off = not (0.0 <= north <= scene.ny * scene.side and 0.0 <= east <= scene.nx * scene.side)
    if off and stats.off_field and stats.off_field[-1][1] >= logged - 1.5 * dt:
        stats.off_field[-1][1] = logged
    elif off:
        stats.off_field.append([logged, logged])


def run_replay(model: WorldModel, data: WorldData, source: Source, playback: Playback, hub: LinkHub | None,
               publisher: StatePublisher | None,
               show: Callable[[int, ReplayStats, Playback], list[str]] | None = None,
               fleet: Sequence[Bridge] = ()) -> ReplayStats:
    """Step the world along the source until its end, ``playback.stop`` or Ctrl-C, its
    state out on ``hub``'s links and ``publisher``'s stream (either may be None); with
    ``fleet`` (every own ship's bridge, the first's hub ``hub``), each other ship's state
    on its own links, each ship's traffic picture holding the others, and the collision
    alarms. Steps before ``playback.seek_to`` run ahead without outputs.
    ``show(k, stats, playback)`` is called about every 0.2 s of wall time (and while
    paused) and returns the keys pressed since."""
    stats = ReplayStats()
    orders = StepOrders(source)
    bridges = [*(WorldTraffic(b.hub.traffic, model.origin) for b in fleet[1:]),
               *fleet_listeners(model, hub, fleet, ReplayLinkOutputs)]
    links = ReplayLinkOutputs(hub) if hub is not None else None
    world_traffic = WorldTraffic(hub.traffic, model.origin) if hub is not None else None
    stream = StreamOutput(publisher, hub.traffic if hub else None, model.origin,
                          lambda: snapshot(model, data)) if publisher is not None else None
    tick = ExerciseTick(model, data, orders, [_stats_listener(stats, model, data, orders), *bridges,
                                               *(x for x in (world_traffic, links, stream) if x is not None)], orders)
    stats.refusals = tick.refusals
    pacer = Pacer(source.dt / (playback.speed or 1.0), BEHIND_S)
    start, shown, seeking, speed = time.monotonic(), 0.0, playback.seek_to > 0, playback.speed
    try:
        while orders.k < source.steps and not playback.stop:
            k = orders.k
            if show is not None and (time.monotonic() - shown >= 0.2 or playback.paused):
                shown = time.monotonic()
                for key in show(k, stats, playback):
                    playback.key(key, k, source.dt)
            if playback.paused:
                time.sleep(0.05)
                pacer.restart()
                continue
            if seeking and k >= playback.seek_to:  # arrived: the render processes resynchronise
                if publisher is not None:
                    publisher.publish(snapshot(model, data))
                pacer.restart()
            seeking = k < playback.seek_to
            if playback.speed != speed:
                speed = playback.speed
                pacer.retime(source.dt / (speed or 1.0))
            tick(source.dt, orders.clock(), send=not seeking)
            pacer.advance()
            if not seeking and playback.speed is not None:
                pacer.wait()
    except KeyboardInterrupt:
        pass
    stats.steps, stats.sim_s, stats.wall_s = orders.k, orders.k * source.dt, time.monotonic() - start
    stats.console_orders_ignored = sum(x.console_orders_ignored for x in (links, *bridges)
                                       if isinstance(x, ReplayLinkOutputs))
    broken = broken_counts(data.ice)
    stats.broken_by_hull, stats.broken_by_contact = int(broken[BreakCause.HULL]), int(broken[BreakCause.CONTACT])
    return stats
