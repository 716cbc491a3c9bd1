"""Order arbitration: several links may give the same order; the first fresh source in the
configured priority list wins.

Two orders are arbitrated: the rudder, and the engine (telegraph position or lever,
whichever the winning source sent last). Searchlight orders are not: each one from a
searchlight source is passed on as it comes (a light holds its last order; none goes
stale). A source is fresh while its last order of that kind is younger than its link's
timeout. When the winning source goes stale the next fresh
one takes over and an alarm is raised; when every source is stale, the configured fail-safe
applies after ``fail_safe_after_s`` (hold the last order, or midships and stop) and a
second alarm is raised. Alarms clear when a source is fresh again. Alarm texts name at most
one link, so that they fit an ALR sentence whole (link names have at most 24 characters).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from bridge_node.links.messages import Alarm, ControlInput
from bridge_node.links.settings import ArbitrationSettings
from sim_core.ship.orders import OrderKind
from sim_core.world import Controls

CHANNELS = {"rudder": (OrderKind.RUDDER,), "engine": (OrderKind.TELEGRAPH, OrderKind.LEVER)}
ALARM_NUMBERS = {"rudder": (101, 111), "engine": (102, 112)}  # (source stale, fail-safe applied)


@dataclass
class _Channel:
    sources: list[str]
    latest: dict = field(default_factory=dict)  # source -> last ControlInput of this channel
    active: str | None = None
    applied: float = -math.inf  # time of the last order passed on
    all_stale_since: float | None = None
    fail_safe_applied: bool = False
    stale_alarm: bool = False  # the source-stale alarm is raised


@dataclass
class Decision:
    """One tick's outcome: orders to give the ship, alarm changes, the active sources, and
    the time (monotonic s) the newest order passed on was read, if any; in an exercise of
    several own ships, the first ship's, with the other ships' decisions in ``others``."""

    controls: Controls
    alarms: list[Alarm]
    active: dict[str, str | None]
    input_time: float | None = None
    others: tuple[Decision, ...] = ()

    def every_ships_controls(self) -> Controls | list[Controls]:
        """The orders for the world's step: this ship's, or with others one per ship."""
        return [self.controls, *(d.controls for d in self.others)] if self.others else self.controls


class OrderArbiter:
    """Keeps the latest order of every source and decides which one the ship obeys."""

    def __init__(self, settings: ArbitrationSettings, timeouts: dict[str, float]) -> None:
        self.settings = settings
        self.timeouts = timeouts
        self.channels = {name: _Channel(list(getattr(settings, name))) for name in CHANNELS}
        self.counts: dict[str, int] = {}
        self.searchlight_sources = set(settings.rudder + settings.engine if settings.searchlight is None
                                       else settings.searchlight)
        self._searchlights: list[ControlInput] = []  # orders not yet passed on

    def feed(self, inputs: list[ControlInput]) -> None:
        """Count the orders, and keep each as its source's latest of its channel."""
        for order in inputs:
            self.counts[order.source] = self.counts.get(order.source, 0) + 1
            if order.kind == OrderKind.SEARCHLIGHT and order.source in self.searchlight_sources:
                self._searchlights.append(order)
            for name, kinds in CHANNELS.items():
                ch = self.channels[name]
                if order.kind in kinds and order.source in ch.sources:
                    ch.latest[order.source] = order

    def _fresh(self, ch: _Channel, now: float) -> str | None:
        for source in ch.sources:
            order = ch.latest.get(source)
            if order is not None and now - order.time <= self.timeouts[source]:
                return source
        return None

    def _switched(self, name: str, ch: _Channel, source: str | None) -> list[Alarm]:
        """Alarm changes as the channel's winner changes from ``ch.active`` to ``source``."""
        stale_no, fail_no = ALARM_NUMBERS[name]
        if source is None:
            ch.stale_alarm = True
            return [Alarm(stale_no, f"every {name} source stale", True)]
        if ch.active is not None and ch.sources.index(source) > ch.sources.index(ch.active):
            ch.stale_alarm = True  # the winner went stale: a lower-priority source takes over
            return [Alarm(stale_no, f"{name} source stale; now {source}", True)]
        alarms = []  # the first source, or a better one fresh again: clear the alarms raised
        if ch.stale_alarm:
            alarms.append(Alarm(stale_no, f"{name} source {source} in use", False))
            ch.stale_alarm = False
        if ch.fail_safe_applied:
            alarms.append(Alarm(fail_no, f"{name} fail-safe cleared", False))
        return alarms

    def _fail_safe(self, name: str, ch: _Channel, controls: Controls, now: float) -> list[Alarm]:
        """With every source stale: apply the fail-safe once ``fail_safe_after_s`` has passed."""
        ch.all_stale_since = now if ch.all_stale_since is None else ch.all_stale_since
        if not ch.sources or ch.fail_safe_applied or now - ch.all_stale_since < self.settings.fail_safe_after_s:
            return []
        ch.fail_safe_applied = True
        if self.settings.fail_safe == "midships_stop":
            if name == "rudder":
                controls.rudder = 0.0
            else:
                controls.telegraph = "stop"
        return [Alarm(ALARM_NUMBERS[name][1], f"{name} fail-safe: {self.settings.fail_safe}", True)]

    def decide(self, now: float) -> Decision:
        """The orders to pass on at ``now`` (monotonic s): each channel's winning source's
        latest order if not passed on yet, or the fail-safe; and the alarm changes."""
        controls, alarms, newest = Controls(), [], None
        if self._searchlights:
            taken, self._searchlights = sorted(self._searchlights, key=lambda o: o.time), []
            controls.searchlights = tuple(o.value for o in taken)
            newest = taken[-1].time
        for name, ch in self.channels.items():
            source = self._fresh(ch, now)
            if source != ch.active:
                alarms += self._switched(name, ch, source)
                ch.active = source
                ch.applied = -math.inf
            if source is None:
                alarms += self._fail_safe(name, ch, controls, now)
                continue
            ch.all_stale_since = None
            ch.fail_safe_applied = False
            order = ch.latest[source]
            if order.time > ch.applied:
                ch.applied = order.time
                newest = order.time if newest is None else max(newest, order.time)
                if order.kind == OrderKind.RUDDER:
                    controls.rudder = float(order.value)
                elif order.kind == OrderKind.TELEGRAPH:
                    controls.telegraph = str(order.value)
                else:
                    controls.lever = float(order.value)
        return Decision(controls, alarms, {n: c.active for n, c in self.channels.items()}, newest)
