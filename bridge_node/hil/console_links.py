"""The software console's ends, one per link kind, each the peer of one node link: the common
end here, each kind's in its own module (console_can, console_nmea, console_modbus), made by
``console_registry.make_console_link``.

A ``ConsoleLink`` holds the latest order of each channel (rudder, engine, each searchlight)
and sends it again at ``rate_hz``, as a console repeats its state; ``poll`` reads back the
instrument outputs as ``Reading`` rows (SI) and ALR alarms as ``AlarmReading`` rows. Faults
(``inject``) act on the outgoing traffic of one end, as a faulty console or cable would: the
console is the one sending the faulty traffic, the node is left as it is. Like the node's links, an end is a
context manager, and closing twice is safe.
"""
from __future__ import annotations

import heapq
import itertools
import math
import random
import time
from abc import ABC, abstractmethod
from collections import Counter
from dataclasses import dataclass, replace

import can
import serial

from bridge_node.hil.scenario import Fault
from bridge_node.links.messages import ETL_POSITIONS
from bridge_node.common.errors import UserError
from sim_core.ship.orders import OrderKind
from sim_core.ship.searchlights import SearchlightOrder

ETL_CODES = {name: code for code, name in ETL_POSITIONS.items()}  # telegraph position -> ETL code
# corrupt = "range" sends these
OUT_OF_RANGE = {OrderKind.RUDDER: math.radians(120.0), OrderKind.LEVER: 150.0, OrderKind.TELEGRAPH: "99"}
OUT_OF_RANGE_BEARING = math.radians(200.0)  # and a searchlight order trained this far
CHANNEL = {OrderKind.RUDDER: "rudder", OrderKind.TELEGRAPH: "engine", OrderKind.LEVER: "engine"}
DEVICE_ERRORS = (OSError, can.CanError, serial.SerialException)  # a port, bus or server that failed


@dataclass(frozen=True)
class Order:
    """A console order: ``kind`` OrderKind.RUDDER (value rad, + starboard), OrderKind.TELEGRAPH (a position
    name), OrderKind.LEVER (percent) or OrderKind.SEARCHLIGHT (a ``SearchlightOrder`` with every field given)."""

    kind: str
    value: float | str | SearchlightOrder

    @property
    def channel(self) -> str:
        """The channel whose latest order this is: rudder, engine, or one searchlight's."""
        return f"searchlight {self.value.index}" if self.kind == OrderKind.SEARCHLIGHT else CHANNEL[self.kind]

    def wire_value(self, corrupt: str | None) -> float | str | SearchlightOrder:
        """The value to send: the order's, or with corrupt = "range" one out of range."""
        if corrupt != "range":
            return self.value
        if self.kind == OrderKind.SEARCHLIGHT:
            return replace(self.value, bearing=OUT_OF_RANGE_BEARING)
        return OUT_OF_RANGE[self.kind]


@dataclass(frozen=True)
class Reading:
    """One instrument value read back: console monotonic time s, console end, quantity
    (rudder_angle rad, shaft_speed rev/s, heading rad, rate_of_turn rad/s) and value."""

    time: float
    role: str
    quantity: str
    value: float


@dataclass(frozen=True)
class AlarmReading:
    """One ALR sentence read back: time s, console end, alarm number, active, text."""

    time: float
    role: str
    number: int
    active: bool
    text: str


class ConsoleLink(ABC):
    """One console end: orders out (held and repeated), instrument outputs in, faults."""

    kind: str = ""  # link type, as in the node's settings
    corruptions: tuple[str, ...] = ("range",)  # the ``corrupt`` kinds this end can send
    framing: str | None = None  # what corrupt = "format" sends on this end (one of corruptions)
    garbage_kind: str | None = None  # what a garbage burst is on this end; None: none

    def __init__(self, settings) -> None:
        self.settings = settings
        self.role: str = settings.role
        self.device = None
        self.held: dict[str, Order] = {}  # channel -> latest order
        self.sent = Counter()  # orders given (corrupted, duplicated, dropped, delayed), garbage, frames written
        self._faults: list[tuple[Fault, random.Random]] = []
        self._delayed: list[tuple[float, int, object]] = []  # (due s, sequence, wire item)
        self._sequence = itertools.count()
        self._next_repeat = -math.inf
        self._active = False

    # --- life cycle ---

    def open(self) -> None:
        """Open the console's end of the link (a port, bus or server); UserError with the
        operating system's or the library's own message if it cannot be opened."""
        try:
            self.device = self._open()
        except (*DEVICE_ERRORS, ValueError, ImportError) as exc:
            raise UserError(f"console end {self.role} ({self.kind}): cannot open it: {exc}") from None
        self._active = True

    def close(self) -> None:
        """Release the end; safe to call twice."""
        self._active = False
        self._release()

    def __enter__(self) -> ConsoleLink:
        self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _release(self) -> None:
        """Close the device; one already lost (its port gone) is let go without a word."""
        device, self.device = self.device, None
        if device is not None:
            try:
                self._close(device)
            except DEVICE_ERRORS:
                pass

    # --- orders and faults ---

    def unsupported(self, fault: Fault) -> str | None:
        """Why this end cannot inject ``fault``, or None."""
        if fault.kind == "corrupt" and fault.corrupt not in self.corruptions + (("format",) if self.framing else ()):
            return f"corrupt = {fault.corrupt!r} does not apply to a {self.kind} link (allowed: {self.corruptions})"
        if fault.kind == "garbage" and self.garbage_kind is None:
            return f"a garbage burst does not apply to a {self.kind} link"
        if fault.kind == "bus_off":
            return "bus_off needs the CAN adapter's pty pair, which icebridge hil run creates"
        return None

    def supports(self, kind: str) -> bool:
        """Whether this end can give orders of ``kind``."""
        return True

    def order(self, order: Order, now: float) -> None:
        """Hold ``order`` as its channel's latest and send it now (``now``: monotonic s)."""
        self.held[order.channel] = order
        self._send(order, now)

    def inject(self, fault: Fault, rng: random.Random) -> None:
        """Start ``fault``; it lasts until ``clear`` (the caller keeps the scenario's clock)."""
        self._faults.append((fault, rng))
        if fault.kind == "garbage" and self.device is not None:
            self._write_guarded(self._garbage(rng, fault.count))
            self.sent["garbage"] += fault.count
        if fault.kind == "disconnect":
            self._release()

    def clear(self, fault: Fault) -> None:
        """End ``fault``; a disconnected end is opened again at the next ``tick``."""
        self._faults = [(f, r) for f, r in self._faults if f is not fault]

    def tick(self, now: float) -> list[Reading | AlarmReading]:
        """Reopen after a disconnect, repeat the held orders when due, send delayed traffic,
        and read what came in (``now``: monotonic s)."""
        disconnected = any(f.kind == "disconnect" for f, _ in self._faults)
        if self.device is None and self._active and not disconnected:
            try:
                self.device = self._open()
            except DEVICE_ERRORS:
                return []
        if self.device is None:
            return []
        if now >= self._next_repeat:
            self._next_repeat = now + 1.0 / self.settings.rate_hz
            for order in list(self.held.values()):
                self._send(order, now)
        while self._delayed and self._delayed[0][0] <= now:
            self._write_guarded([heapq.heappop(self._delayed)[2]])
        if self.device is None:  # a write above failed and released the device
            return []
        try:
            return self._read(time.monotonic())  # stamped when read
        except DEVICE_ERRORS:
            self._release()
            return []

    def _send(self, order: Order, now: float) -> None:
        """One order through the active faults: dropped, corrupted, duplicated, delayed."""
        corrupt, copies, delay = None, 1, 0.0
        for fault, rng in self._faults:
            if fault.kind not in ("drop", "corrupt", "duplicate", "delay") or rng.random() >= fault.probability:
                continue
            if fault.kind == "drop":
                self.sent["dropped"] += 1
                return
            if fault.kind == "corrupt":
                corrupt = fault.corrupt
            elif fault.kind == "duplicate":
                copies = 2
            else:
                delay = max(delay, fault.delay_s)
        corrupt = self.framing if corrupt == "format" else corrupt
        items = self._encode(order, corrupt) * copies
        self.sent["orders"] += 1
        if corrupt:
            self.sent["corrupted"] += 1
        if copies > 1:
            self.sent["duplicated"] += 1
        if delay:
            self.sent["delayed"] += 1
            for item in items:
                heapq.heappush(self._delayed, (now + delay, next(self._sequence), item))
        else:
            self._write_guarded(items)

    def _write_guarded(self, items: list) -> None:
        """Write wire items; a device that fails is released (and reopened at the next tick)."""
        if self.device is None:
            return
        try:
            for item in items:
                self._write(item)
                self.sent["frames"] += 1
        except DEVICE_ERRORS:
            self.sent["write_failed"] += 1
            self._release()

    # --- for the link kinds ---

    @abstractmethod
    def _open(self):
        """Open and return the port, bus or server."""

    @abstractmethod
    def _close(self, device) -> None:
        """Release the port, bus or server."""

    @abstractmethod
    def _encode(self, order: Order, corrupt: str | None) -> list:
        """The wire items (frames, sentences, register writes) of one order."""

    @abstractmethod
    def _write(self, item) -> None:
        """Send one wire item on the open device."""

    def _garbage(self, rng: random.Random, count: int) -> list:
        """``count`` random wire items (default: none)."""
        return []

    @abstractmethod
    def _read(self, now: float) -> list[Reading | AlarmReading]:
        """What the node sent since the last read."""
