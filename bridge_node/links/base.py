"""The one interface every hardware link implements, like python-can's ``can.Bus``.

A link is opened, polled once per tick for the console's orders (timestamped
``ControlInput`` rows), given the ship state to publish to bridge instruments (it sends what
is due at its own rates), told about alarms, and closed. ``health()`` reports whether it is
connected, when it last heard its peer, and its error counts by kind. A link never raises
for bad input from the wire: it counts the error and drops the input.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections import Counter
from dataclasses import dataclass, field

from bridge_node.links.reconnect import Backoff
from sim_core.ship_outputs import ShipOutputs

RUDDER, TELEGRAPH, LEVER = "rudder", "telegraph", "lever"


@dataclass(frozen=True)
class ControlInput:
    """One order from the console. ``value``: rudder rad (+ starboard), lever percent
    (-100..100), or a telegraph position name. ``time`` is the node's monotonic clock, s."""

    time: float
    source: str  # link name
    kind: str  # RUDDER, TELEGRAPH or LEVER
    value: float | str
    engine: int = 0  # 0 centre, odd starboard, even port (NMEA convention)


@dataclass(frozen=True)
class Alarm:
    """An alarm the node raises: id number, text, and whether it is active now."""

    number: int
    text: str
    active: bool


@dataclass
class LinkHealth:
    """What a link reports about itself."""

    name: str
    connected: bool = False
    last_input: float = -math.inf  # monotonic s of the last valid input
    inputs: int = 0
    outputs: int = 0
    reconnects: int = 0
    errors: Counter = field(default_factory=Counter)  # kind -> count

    def as_dict(self) -> dict:
        return {"name": self.name, "connected": self.connected, "inputs": self.inputs, "outputs": self.outputs,
                "reconnects": self.reconnects, "errors": dict(self.errors)}


class Link(ABC):
    """A hardware link to the console and instruments."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._health = LinkHealth(name)

    @abstractmethod
    def open(self) -> None:
        """Open the port, bus or connection. A peer that is not there yet is not an error:
        the link reports itself disconnected and keeps trying."""

    @abstractmethod
    def poll(self, now: float) -> list[ControlInput]:
        """Orders received since the last poll; never blocks."""

    @abstractmethod
    def publish(self, state: ShipOutputs, now: float) -> None:
        """Send the outputs that are due at ``now`` (monotonic s); never blocks."""

    def publish_alarm(self, alarm: Alarm, now: float) -> None:
        """Announce an alarm on this link, where its protocol has a way to (default: none)."""

    @abstractmethod
    def close(self) -> None:
        """Release the port, bus or connection."""

    def health(self) -> LinkHealth:
        return self._health

    def _count_error(self, kind: str) -> None:
        self._health.errors[kind] += 1


    def _received(self, inputs: list[ControlInput], now: float) -> list[ControlInput]:
        if inputs:
            self._health.inputs += len(inputs)
            self._health.last_input = now
        return inputs


class DeviceLink(Link):
    """A link over one port or bus (``self.device``) that may fail at any time: a failure
    to open or a lost device is counted, and the device is reopened after a back-off."""

    device_errors: tuple[type[Exception], ...] = (OSError,)  # what opening or using the device raises

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.device = None
        self._backoff = Backoff()

    @abstractmethod
    def _open_device(self):
        """Open and return the port or bus."""

    @abstractmethod
    def _close_device(self, device) -> None:
        """Release the port or bus."""

    def _connect(self, now: float) -> None:
        try:
            self.device = self._open_device()
            self._health.connected = True
            self._backoff.succeeded()
        except self.device_errors:
            self.device = None
            self._down(now, "open_failed")

    def _lost(self, now: float, kind: str) -> None:
        """The device failed in use (kind counted): close it and retry after the back-off."""
        try:
            self._close_device(self.device)
        except self.device_errors:
            pass
        self.device = None
        self._down(now, kind)

    def _down(self, now: float, kind: str) -> None:
        self._health.connected = False
        self._count_error(kind)
        self._backoff.failed(now)

    def _reconnect_if_due(self, now: float) -> None:
        """For a link whose device is down: try to reopen it once the back-off has passed."""
        if self._backoff.ready(now):
            self._health.reconnects += 1
            self._connect(now)

    def close(self) -> None:
        if self.device is not None:
            self._close_device(self.device)
            self.device = None
        self._health.connected = False


class RateSchedule:
    """When each periodic output is next due; rates in Hz."""

    def __init__(self, rates: dict[str, float]) -> None:
        self.period = {k: 1.0 / r for k, r in rates.items() if r > 0.0}
        self.next_due = {k: -math.inf for k in self.period}

    def due(self, now: float) -> list[str]:
        """Outputs due at ``now``, each rescheduled one period on (not drifting with jitter,
        and not bursting after a stall)."""
        out = []
        for k, t in self.next_due.items():
            if now >= t:
                out.append(k)
                nxt = t + self.period[k]
                self.next_due[k] = nxt if nxt > now else now + self.period[k]
        return out
