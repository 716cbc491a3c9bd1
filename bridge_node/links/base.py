"""The link family, modelled on python-can: ``Link`` is the console links' ``BusABC``.

A link is built from its settings alone, opened, polled once per tick for the console's
orders (timestamped ``ControlInput`` rows), given the ship state to publish to bridge
instruments (it sends what is due at its own rates), told about alarms, and closed; it is a
context manager, and closing twice is safe. ``Link.poll`` is written once, here: it reopens
a lost device after a back-off and counts errors, and calls the protocol's small hook
``_poll_device``. Devices are opened on a worker thread (``Opener``), never on the loop's:
python-can's slcan sleeps 2 s after opening its port, a USB adapter can take as long, and
the physics tick must not wait for either. A link never raises for bad input from the wire: it counts the error and
drops the input. Raw traffic (frames, sentences, register accesses) goes to the link's
listeners, like python-can's ``Listener``; the session record is one.

Each protocol's module registers its link class with the rest of its kind (``links.kind``).
What links exchange (orders, alarms, vessels, health, traffic) is in ``links.messages``; what a
device needs around it (back-off, opener thread, queued writer, rate schedule) in
``links.device_io``.
"""
from __future__ import annotations

import dataclasses
import logging
import time
from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Iterable
from typing import TYPE_CHECKING, ClassVar

from bridge_node.links.convoy import ConvoyTarget
from bridge_node.links.device_io import Backoff, Opener
from bridge_node.links.faults import FaultyLine, LinkFault
from bridge_node.links.messages import (
    ALARM_TEXT_MAX,
    Alarm,
    ControlInput,
    LinkHealth,
    Listener,
    Traffic,
    Vessel,
    device_error_texts,
)
from sim_core.ship.orders import OrderKind
from sim_core.ship.outputs import ShipOutputs

if TYPE_CHECKING:
    from bridge_node.links.settings import LinkSettingsBase

log = logging.getLogger("icebridge.links")
OPEN_WAIT_S = 5.0  # ``Link.open`` waits this long for the device; a slower one is taken up by a later poll


class Link(ABC):
    """A link to the console and instruments over one device (port, bus, or worker thread)
    held in ``self.device``, which may fail at any time: a failure to open it or its loss in
    use is counted, and it is reopened after a back-off (0.1 s doubling to 1 s).

    Engine orders (telegraph, lever) for another engine than the link's ``engine`` are
    counted as ``other_engine`` and dropped: the ship has one shaft."""

    open_errors: ClassVar[tuple[type[Exception], ...]] = (OSError,)  # opening the device raises these
    lost_errors: ClassVar[tuple[type[Exception], ...]] = (OSError,)  # a device that failed in use raises these
    lost_kind: ClassVar[str] = "device_lost"  # error kind counted for a device lost in use
    up_when_open: ClassVar[bool] = True  # False: ``connected`` waits for the peer to answer
    simulator_peer: ClassVar[bool] = False  # True: a link to other simulators, sent the ship as it is, not as
    # its sensors read it (``WorldEvents.instruments``)

    def __init__(self, settings: LinkSettingsBase) -> None:
        self.settings = settings
        self.name: str = settings.name
        self.device = None
        self.listeners: list[Listener] = []
        self._health = LinkHealth(self.name)
        self._backoff = Backoff()
        self._active = False  # between open() and close()
        self._opener: Opener | None = None  # the device being opened
        self._failed = False  # a real failure since the link was last up
        self._down_reasons: list[str] = []  # short forms of why the device last failed
        self._fault: FaultyLine | None = None  # the instructor's fault on the link

    def open(self, wait: float | None = OPEN_WAIT_S) -> None:
        """Open the device (on the opener's thread), waiting up to ``wait`` s for it (None:
        until it has opened or failed); a slower device is taken up by a later poll. A peer
        that is not there yet is not an error: the link reports itself disconnected and
        keeps trying. Opening an open link does nothing."""
        self.begin_open()
        self.await_open(wait)

    def begin_open(self) -> None:
        """Start opening the device on the opener's thread (nothing if open or opening), so
        that several links open at once."""
        if self._active:
            return
        self._active = True
        self._start_open()

    def await_open(self, wait: float | None) -> None:
        """Wait up to ``wait`` s (None: until it has opened or failed) for the device being
        opened, and take it into use if it is there."""
        if self._opener is not None and self._opener.wait(wait):
            self._take_device(time.monotonic())

    def close(self) -> None:
        """Release the device (one still opening is closed when it opens); safe to call twice."""
        self._active = False
        opener, self._opener = self._opener, None
        if opener is not None:
            opener.abandon()
            self._health.opening = False
        device, self.device = self.device, None
        if device is not None:
            self._close_device(device)
        self._health.connected = False

    def __enter__(self) -> Link:
        self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def poll(self, now: float) -> list[ControlInput]:
        """Orders received since the last poll (``now``: monotonic s); never blocks (not even
        for a reopen: a device the opener has opened is taken up by the next poll). Reopens a
        lost device once its back-off has passed."""
        if not self._active:
            return []
        if self.device is None:
            if self._fault is not None and self._fault.disconnects:
                return []
            if self._opener is None and self._backoff.ready(now):
                self._health.reconnects += 1
                self._start_open()
            elif self._opener is not None and self._opener.wait(0.0):
                self._take_device(now)
            return []
        inputs = []
        try:
            for order in self._poll_device(now):  # orders before a failure are kept
                if order.kind != OrderKind.RUDDER and order.engine != self.settings.engine:
                    self._count_error("other_engine")
                else:
                    inputs.append(order)
        except self.lost_errors as exc:
            self._note_failure(exc, "lost")
            self._lost(now)
        if self._fault is not None:
            inputs = self._fault.orders(inputs, now, self._count_error)
            self._fault = None if self._fault.over else self._fault
        self._health.inputs += len(inputs)
        return inputs

    def set_fault(self, fault: LinkFault, now: float) -> None:
        """Put the instructor's ``fault`` on the link (kind "none": clear it) at ``now`` (s);
        a disconnect closes the device until the fault is cleared. Orders a delay holds
        still come, when due, after the fault changes."""
        line = FaultyLine(fault)
        line.held = self._fault.held if self._fault is not None else []
        self._fault = None if line.over else line
        self._health.fault = None if fault.kind == "none" else fault.kind
        if fault.kind != "disconnect" or not self._active:
            return
        if self._opener is not None:
            self._opener.abandon()
            self._opener, self._health.opening = None, False
        if self.device is not None:
            self._lost(now, "fault_disconnect")
        self._failed, self._health.connected = True, False
        self._down_reasons = ["disconnected by the instructor"]

    @abstractmethod
    def publish(self, state: ShipOutputs, now: float) -> None:
        """Send the outputs that are due at ``now`` (monotonic s); never blocks."""

    def publish_alarm(self, alarm: Alarm, now: float) -> None:
        """Announce an alarm on this link, where its protocol has a way to (default: none)."""

    def vessels(self, now: float) -> list[Vessel]:
        """The other vessels this link hears of, as of ``now`` (monotonic s; default: none)."""
        return []

    def publish_vessels(self, vessels: list[Vessel], now: float) -> None:
        """Send the other vessels that are due, where the protocol has a way to (default: none)."""

    def publish_targets(self, targets: list[ConvoyTarget], now: float) -> None:
        """Send the convoy's ships as tracked targets, where the protocol has a way to
        (default: none); called before ``publish`` each tick."""
    @property
    def connected(self) -> bool:
        """Whether the device is open (or, for a link with ``up_when_open`` False, the peer answers)."""
        return self._health.connected

    def down_text(self) -> str:
        """The link-down alarm's text: with why the device failed, in the OS's or python-can's
        own words, where that fits an ALR sentence whole (the whole message is in the log)."""
        plain = f"link {self.name} down"
        for reason in self._down_reasons:
            text = f"{plain}: {reason}"
            if len(text) <= ALARM_TEXT_MAX and not any(c in text for c in ",*$!"):
                return text
        return plain

    @property
    def failed(self) -> bool:
        """Down after a real failure (an open or a request that failed, a device lost), until
        the link is up again; a link still waiting for its first answer has not failed."""
        return self._failed and not self._health.connected

    def health(self) -> LinkHealth:
        """A snapshot of the link's state and counters."""
        return dataclasses.replace(self._health, errors=Counter(self._health.errors))

    def add_listener(self, listener: Listener) -> None:
        self.listeners.append(listener)

    def remove_listener(self, listener: Listener) -> None:
        self.listeners.remove(listener)

    # --- for the protocols ---

    @abstractmethod
    def _open_device(self):
        """Open and return the port, bus or worker; raises one of ``open_errors``. Runs on
        the opener's thread while ``self.device`` is None: it may touch only what the loop
        leaves alone until the device is in use."""

    @abstractmethod
    def _close_device(self, device) -> None:
        """Release the port, bus or worker."""

    @abstractmethod
    def _poll_device(self, now: float) -> Iterable[ControlInput]:
        """The orders waiting on the open device; raises one of ``lost_errors`` if it failed."""

    def _count_error(self, kind: str, n: int = 1) -> None:
        if n:
            self._health.errors[kind] += n

    def _report(self, direction: str, data: object, unix_time: float | None = None) -> None:
        """Hand raw traffic to the listeners (``unix_time`` default: now)."""
        if self.listeners:
            t = Traffic(time.time() if unix_time is None else unix_time, self.name, self.settings.type, direction, data)
            for listener in self.listeners:
                listener.on_traffic(t)

    def _note_failure(self, exc: BaseException, what: str) -> None:
        """Keep why the device failed (``what``: "open" or "lost"); logged once per new reason,
        not at every retry."""
        full, self._down_reasons = device_error_texts(exc)
        text = f"cannot open the device: {full}" if what == "open" else f"device lost: {full}"
        if text != self._health.last_error:
            log.warning("link %s: %s", self.name, text)
        self._health.last_error = text

    def _start_open(self) -> None:
        self._opener = Opener(self._open_device, self._close_device, self.name)
        self._health.opening = True

    def _take_device(self, now: float) -> None:
        """Take the finished opener's device into use, or count why it did not open (an
        exception other than ``open_errors`` is a bug, and raised here)."""
        device, error = self._opener.take()
        self._opener = None
        self._health.opening = False
        if error is not None:
            if not isinstance(error, self.open_errors):
                raise error
            self._note_failure(error, "open")
            self._down(now, "open_failed")
            return
        self.device = device
        self._health.connected = self.up_when_open
        self._down_reasons = []
        self._backoff.succeeded()

    def _lost(self, now: float, kind: str | None = None) -> None:
        """The device failed in use (``kind`` counted, default ``lost_kind``): close it and
        reopen it after the back-off."""
        try:
            self._close_device(self.device)
        except self.lost_errors + self.open_errors:
            pass
        self.device = None
        self._down(now, kind or self.lost_kind)

    def _down(self, now: float, kind: str) -> None:
        self._health.connected = False
        self._failed = True
        self._count_error(kind)
        self._backoff.failed(now)

