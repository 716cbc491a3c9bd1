"""What a link's device needs around it: the back-off between reopenings, the worker thread
that opens a device off the loop's thread, the queued writer for devices whose writes block,
the queued reader for devices whose reads block, and the schedule of outputs due at their
rates."""
from __future__ import annotations

import collections
import logging
import math
import queue
import threading
from collections.abc import Callable

log = logging.getLogger("icebridge.links")


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


class Opener:
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
        return _drain(self._failures)

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


class QueuedReader:
    """Reads on a worker thread, so the loop never waits for a device whose reads block (the
    serial-line CAN adapters of python-can wait up to their port's timeout in every receive,
    however short the receive's own timeout): the thread calls ``read``, which waits up to
    its own timeout and returns None when nothing came, and queues what it returns; the loop
    takes what is queued (``take``) without waiting. Beyond ``size`` items waiting, an item
    is dropped and counted (``dropped``). What ``read`` raises ends the thread and is handed
    back (``failures``), unless the reader is closing.

    python-can's ``Notifier`` and ``BufferedReader`` read on a thread too, but on a lost port
    the notifier's thread either ends with a traceback on the console or, given an error
    handler, calls the failing receive again at once, without end; and the buffer has no
    bound. So this small reader, which ``QueuedWriter`` mirrors."""

    def __init__(self, read: Callable[[], object | None], name: str, size: int) -> None:
        self._read, self._size = read, size
        self._items: collections.deque = collections.deque()  # thread appends, loop pops: both thread-safe
        self._failures: queue.SimpleQueue = queue.SimpleQueue()
        self.dropped = 0
        self.closing = threading.Event()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def take(self, limit: int) -> list:
        """Up to ``limit`` items read since the last call, oldest first."""
        out = []
        while self._items and len(out) < limit:
            out.append(self._items.popleft())
        return out

    def failures(self) -> list[Exception]:
        """Why the thread ended (a read raised), once; empty while it reads."""
        return _drain(self._failures)

    def _run(self) -> None:
        while not self.closing.is_set():
            try:
                item = self._read()
            except Exception as exc:  # noqa: BLE001 (handed to the loop, which decides what it means)
                if not self.closing.is_set():
                    self._failures.put(exc)
                return
            if item is None:
                continue
            if len(self._items) >= self._size:
                self.dropped += 1
            else:
                self._items.append(item)

    def close(self, wait: float = 0.0) -> None:
        """Have the thread stop after the read in hand, waiting up to ``wait`` s for it."""
        self.closing.set()
        if wait > 0.0:
            self._thread.join(wait)


def _drain(items: queue.SimpleQueue) -> list:
    """Everything in a queue now, without waiting."""
    out = []
    while not items.empty():
        out.append(items.get_nowait())
    return out


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
