"""The link family, modelled on python-can: ``Link`` is the console links' ``BusABC``.

A link is built from its settings alone, opened, polled once per tick for the console's
orders (timestamped ``ControlInput`` rows), given the ship state to publish to bridge
instruments (it sends what is due at its own rates), told about alarms, and closed; it is a
context manager, and closing twice is safe. ``Link.poll`` is written once, here: it reopens
a lost device after a back-off and counts errors, and calls the protocol's small hook
``_poll_device``. Devices are opened on a worker thread (``_Opener``), never on the loop's:
python-can's slcan sleeps 2 s after opening its port, a USB adapter can take as long, and
the physics tick must not wait for either. A link never raises for bad input from the wire: it counts the error and
drops the input. Raw traffic (frames, sentences, register accesses) goes to the link's
listeners, like python-can's ``Listener``; the session record is one.

Link types register themselves by their settings' ``type`` with ``@register_link``.
"""
from __future__ import annotations

import dataclasses
import errno
import logging
import math
import queue
import threading
import time
from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar

from bridge_node.links.faults import FaultyLine, LinkFault
from sim_core.ship.orders import OrderKind
from sim_core.ship.outputs import ShipOutputs
from sim_core.ship.searchlights import MAX_SEARCHLIGHTS, SearchlightOrder

if TYPE_CHECKING:
    from bridge_node.links.settings import LinkSettings

log = logging.getLogger("icebridge.links")
# the one value type of each kind of order
ORDER_VALUES: dict[OrderKind, type] = {OrderKind.RUDDER: float, OrderKind.TELEGRAPH: str, OrderKind.LEVER: float,
                                       OrderKind.SEARCHLIGHT: SearchlightOrder}
RUDDER_ORDER_LIMIT_DEG = 90.0  # beyond this a rudder order is nonsense, not an order to clamp
ALARM_TEXT_MAX = 52  # characters: what an ALR sentence's text field holds within NMEA 0183's 82
OPEN_WAIT_S = 5.0  # ``Link.open`` waits this long for the device; a slower one is taken up by a later poll
# ETL position codes (IEC 61162-1; also the console's CAN and Modbus codes) -> telegraph positions
ETL_POSITIONS = {
    "00": "stop", "01": "dead_slow_ahead", "02": "slow_ahead", "03": "half_ahead", "04": "full_ahead",
    "05": "navigation_full_ahead", "11": "dead_slow_astern", "12": "slow_astern", "13": "half_astern",
    "14": "full_astern", "15": "crash_astern",
}


def searchlight_order(index: int, on: bool | None, bearing_deg: float | None,
                      elevation_deg: float | None) -> SearchlightOrder | str:
    """A console's searchlight order (light 0..3; bearing deg from the bow, + starboard,
    within +-180; elevation deg, + up, within +-90; None: unchanged) in rad, or the error
    kind it is counted as. The light's own train and tilt limits are the world's to check."""
    angles = [(v, limit) for v, limit in ((bearing_deg, 180.0), (elevation_deg, 90.0)) if v is not None]
    if any(not math.isfinite(v) for v, _ in angles):
        return "bad_field"
    if not 0 <= index < MAX_SEARCHLIGHTS or any(abs(v) > limit for v, limit in angles):
        return "out_of_range"
    return SearchlightOrder(index, on, *(None if v is None else math.radians(v) for v in (bearing_deg, elevation_deg)))


@dataclass(frozen=True)
class ControlInput:
    """One order from the console, typed: its ``kind`` and a ``value`` of that kind's one
    type (``ORDER_VALUES``): rudder rad (+ starboard), lever percent (-100..100), a
    telegraph position name, or a ``SearchlightOrder``. ``time`` is the node's monotonic
    clock, s. TypeError for a value of another type (a link's decoding bug, not bad input:
    the links count bad input before they make an order)."""

    time: float
    source: str  # link name
    kind: OrderKind
    value: float | str | SearchlightOrder
    engine: int = 0  # 0 centre, odd starboard, even port (NMEA convention)

    def __post_init__(self) -> None:
        kind = OrderKind(self.kind)
        object.__setattr__(self, "kind", kind)
        if isinstance(self.value, int) and not isinstance(self.value, bool) and ORDER_VALUES[kind] is float:
            object.__setattr__(self, "value", float(self.value))
        if not isinstance(self.value, ORDER_VALUES[kind]):
            raise TypeError(f"a {kind} order's value is a {ORDER_VALUES[kind].__name__}, not {self.value!r}")


@dataclass(frozen=True)
class Alarm:
    """An alarm the node raises: id number, text, and whether it is active now. Texts are
    written to fit ALR whole (at most ``ALARM_TEXT_MAX`` characters, no commas): never cut."""

    number: int
    text: str
    active: bool

    def __post_init__(self) -> None:
        if len(self.text) > ALARM_TEXT_MAX or any(c in self.text for c in ",*$!"):
            raise ValueError(f"alarm text {self.text!r}: at most {ALARM_TEXT_MAX} characters, no , * $ !")


@dataclass(frozen=True)
class Vessel:
    """Another vessel the node knows of (one a DIS simulator sends, say), SI: rad, m/s, m.
    ``time`` is the node's monotonic clock when it was last heard of, s; dimensions 0 are
    unknown."""

    key: str  # unique among the vessels: the source and its own id
    mmsi: int
    name: str
    time: float
    latitude: float
    longitude: float
    heading: float  # true, [0, 2 pi)
    course_over_ground: float
    speed_over_ground: float
    rate_of_turn: float  # + to starboard
    length: float = 0.0
    beam: float = 0.0
    fix_valid: bool = True  # another vessel is placed only where its position is known


@dataclass
class LinkHealth:
    """What a link reports about itself; ``Link.health()`` hands out a copy."""

    name: str
    connected: bool = False
    inputs: int = 0
    outputs: int = 0
    reconnects: int = 0
    opening: bool = False  # the device is being opened on the worker thread
    errors: Counter = field(default_factory=Counter)  # kind -> count
    last_error: str = ""  # why the device last failed, in the OS's or the library's own words
    fault: str | None = None  # the instructor's fault on the link (``bridge_node.links.faults``), if any

    def as_dict(self) -> dict:
        return {"name": self.name, "connected": self.connected, "inputs": self.inputs, "outputs": self.outputs,
                "reconnects": self.reconnects, "opening": self.opening, "errors": dict(self.errors),
                "last_error": self.last_error, "fault": self.fault}


def device_error_texts(exc: BaseException) -> tuple[str, list[str]]:
    """Why a device failed: the whole message (for the log), and short forms for an alarm,
    best first: the innermost OS error's own text (``strerror``), its errno name, the message."""
    full = str(exc) or type(exc).__name__
    short, inner = [], exc
    while inner is not None:
        if isinstance(inner, OSError) and inner.errno in errno.errorcode:
            short = [inner.strerror or "", errno.errorcode[inner.errno]]
        inner = inner.__cause__ or inner.__context__
    return full, [s for s in short if s] + [full]


@dataclass(frozen=True)
class Traffic:
    """Raw traffic of one link as it went over the wire: a ``can.Message``, an NMEA sentence
    (str without CR LF), a Modbus ``RegisterAccess``, or a DIS PDU (bytes)."""

    unix_time: float  # wall clock, s
    link: str  # link name
    protocol: str  # the link's registry key: "can", "nmea0183", "modbus", "dis"
    direction: str  # "rx" / "tx"; Modbus: "read" / "write"
    data: object


class Listener(ABC):
    """Receives the raw traffic of the links it is added to, like python-can's ``Listener``.
    Called on the loop's thread; ``flush`` once per tick, ``stop`` when the hub closes."""

    @abstractmethod
    def on_traffic(self, traffic: Traffic) -> None:
        """One frame, sentence or register access in or out."""

    def flush(self) -> None:
        """Called once per tick (default: nothing)."""

    def stop(self) -> None:
        """Release what the listener holds (default: nothing)."""


class Backoff:
    """Delay before the next reconnect attempt: ``first`` s, doubling per failure up to ``cap`` s."""

    def __init__(self, first: float = 0.1, cap: float = 1.0) -> None:
        self.first, self.cap = first, cap
        self.delay = first
        self.next_try = -math.inf

    def ready(self, now: float) -> bool:
        return now >= self.next_try

    def failed(self, now: float) -> None:
        self.next_try = now + self.delay
        self.delay = min(self.cap, 2.0 * self.delay)

    def succeeded(self) -> None:
        self.delay = self.first
        self.next_try = -math.inf


class _Opener:
    """Opens one device on a worker thread. The loop takes the result (``take``) when
    ``done``; a device that opens after its link was closed (``abandon``) is closed here."""

    def __init__(self, open_device: Callable[[], object], close_device: Callable[[object], None],
                 name: str) -> None:
        self._close_device, self._name = close_device, name
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._abandoned = False
        self._result: tuple[object, BaseException | None] = (None, None)
        threading.Thread(target=self._run, args=(open_device,), name=f"open-{name}", daemon=True).start()

    def _run(self, open_device: Callable[[], object]) -> None:
        device, error = None, None
        try:
            device = open_device()
        except BaseException as exc:  # handed to the loop's thread, which decides what it means
            error = exc
        with self._lock:
            if not self._abandoned:
                self._result = (device, error)
                self._done.set()
                return
        if device is not None:
            try:
                self._close_device(device)
            except Exception as exc:  # noqa: BLE001 (the link is closed: the log is all that is left)
                log.warning("%s: closing a device that opened after its link closed: %s", self._name, exc)

    def wait(self, timeout: float | None) -> bool:
        """Whether the open has finished, waiting up to ``timeout`` s (None: until it has)."""
        return self._done.wait(timeout) if timeout is None or timeout > 0.0 else self._done.is_set()

    def take(self) -> tuple[object, BaseException | None]:
        """The opened device, or None and why not (call once ``done``)."""
        return self._result

    def abandon(self) -> None:
        """The link was closed: close the device, now if it is open, else when it opens."""
        with self._lock:
            self._abandoned = True
            device, self._result = self._result[0], (None, None)
        if device is not None:
            self._close_device(device)


class QueuedWriter:
    """Writes on a worker thread, so the loop never waits for a far end that does not read:
    the loop gathers a tick's items (``put``; beyond ``size`` items waiting, an item is
    refused) and hands them over at once (``flush``), so the thread wakes once a tick, not
    once an item (every wake takes the interpreter lock from the loop). The thread writes
    with ``write`` and hands what it raises of ``errors`` back (``failures``); anything
    else it raises ends it and is handed back too. Closing lets queued items go and does
    not wait: the thread calls ``finish`` (closing the device) once its write is through; a
    ``write`` that waits should give up when ``closing`` is set."""

    def __init__(self, write: Callable[[object], None], finish: Callable[[], None],
                 errors: tuple[type[Exception], ...], name: str, size: int) -> None:
        self._write, self._finish, self._errors, self._size = write, finish, errors, size
        self._batches: queue.SimpleQueue = queue.SimpleQueue()
        self._batch: list = []
        self._handed = self._written = 0  # items handed over (the loop counts) and written (the thread)
        self._failures: queue.SimpleQueue = queue.SimpleQueue()
        self.closing = threading.Event()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def put(self, item: object) -> bool:
        """Add ``item`` to the batch ``flush`` hands over; False if ``size`` items are
        already waiting (the item is dropped)."""
        if self._handed - self._written + len(self._batch) >= self._size:
            return False
        self._batch.append(item)
        return True

    def flush(self) -> None:
        """Hand the gathered items to the thread."""
        if self._batch:
            self._handed += len(self._batch)
            self._batches.put(self._batch)
            self._batch = []

    def failures(self) -> list[Exception]:
        """What the thread's writes raised since the last call (and why it ended, if it did)."""
        out = []
        while not self._failures.empty():
            out.append(self._failures.get_nowait())
        return out

    def _run(self) -> None:
        try:
            while (batch := self._batches.get()) is not None:
                for item in batch:
                    if not self.closing.is_set():
                        try:
                            self._write(item)
                        except self._errors as exc:
                            self._failures.put(exc)
                self._written += len(batch)
        except Exception as exc:  # noqa: BLE001 (a bug in a write: the link is told it lost the device)
            self._failures.put(OSError(f"writer stopped: {exc!r}"))
            self._written = -(1 << 62)  # refuse everything from now on
        try:
            self._finish()
        except self._errors:  # a device already lost; the link has let go of it
            pass

    def close(self) -> None:
        """Let queued items go and have the thread finish (not waited for)."""
        self.closing.set()
        self._batch = []
        self._batches.put(None)


class RateSchedule:
    """When each periodic output is next due; rates in Hz."""

    def __init__(self, rates: dict[str, float]) -> None:
        self.period = {k: 1.0 / r for k, r in rates.items() if r > 0.0}
        self.next_due = {k: -math.inf for k in self.period}

    def due(self, now: float) -> list[str]:
        """Outputs due at ``now`` (monotonic s), each rescheduled one period on (not drifting
        with jitter, and not bursting after a stall)."""
        out = []
        for k, t in self.next_due.items():
            if now >= t:
                out.append(k)
                nxt = t + self.period[k]
                self.next_due[k] = nxt if nxt > now else now + self.period[k]
        return out


class Link(ABC):
    """A link to the console and instruments over one device (port, bus, or worker thread)
    held in ``self.device``, which may fail at any time: a failure to open it or its loss in
    use is counted, and it is reopened after a back-off (0.1 s doubling to 1 s).

    Engine orders (telegraph, lever) for another engine than the link's ``engine`` are
    counted as ``other_engine`` and dropped: the ship has one shaft."""

    type_name: ClassVar[str] = ""  # the settings' ``type``; set by ``register_link``
    open_errors: ClassVar[tuple[type[Exception], ...]] = (OSError,)  # opening the device raises these
    lost_errors: ClassVar[tuple[type[Exception], ...]] = (OSError,)  # a device that failed in use raises these
    lost_kind: ClassVar[str] = "device_lost"  # error kind counted for a device lost in use
    up_when_open: ClassVar[bool] = True  # False: ``connected`` waits for the peer to answer
    simulator_peer: ClassVar[bool] = False  # True: a link to other simulators, sent the ship as it is, not as
    # its sensors read it (``WorldEvents.instruments``)

    def __init__(self, settings: LinkSettings) -> None:
        self.settings = settings
        self.name: str = settings.name
        self.device = None
        self.listeners: list[Listener] = []
        self._health = LinkHealth(self.name)
        self._backoff = Backoff()
        self._active = False  # between open() and close()
        self._opener: _Opener | None = None  # the device being opened
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

    def _count_error(self, kind: str) -> None:
        self._health.errors[kind] += 1

    def _report(self, direction: str, data: object, unix_time: float | None = None) -> None:
        """Hand raw traffic to the listeners (``unix_time`` default: now)."""
        if self.listeners:
            t = Traffic(time.time() if unix_time is None else unix_time, self.name, self.type_name, direction, data)
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
        self._opener = _Opener(self._open_device, self._close_device, self.name)
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


LINK_TYPES: dict[str, type[Link]] = {}  # settings ``type`` -> link class


def register_link(type_name: str) -> Callable[[type[Link]], type[Link]]:
    """Class decorator: links of settings ``type = type_name`` are built with this class."""

    def register(cls: type[Link]) -> type[Link]:
        cls.type_name = type_name
        LINK_TYPES[type_name] = cls
        return cls
    return register
