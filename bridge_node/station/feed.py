"""The station's feed: a thread that follows the node's state stream (a ``StateSubscriber``,
joining from a snapshot and resynchronising after a gap) and makes a ``Frame`` of the
picture ``rate_hz`` times a second, and a thread that asks the control endpoint for the
exercise's status every few seconds (its health, its links' health, the failures and
alarms it knows, on the page)."""
from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from bridge_node.control.client import request
from bridge_node.common.errors import UserError
from bridge_node.station.picture import Frame, Picture
from bridge_node.stream.subscriber import StateSubscriber, StreamError
from sim_core.world import WorldModel

log = logging.getLogger("icebridge.station")
CONTROL_EVERY_S = 3.0  # s between status requests
CONTROL_TIMEOUT_S = 2.0
SILENT_S = 5.0  # s without a step before the stream is joined afresh (the node may have restarted)


class ControlWatch:
    """Asks the node for its status every ``CONTROL_EVERY_S``; ``error`` is None while it
    answers."""

    def __init__(self, endpoint: str, token: str | None) -> None:
        self.endpoint, self.token = endpoint, token
        self.error: str | None = None  # until the first request says otherwise
        self.status: dict | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="station-control", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(CONTROL_TIMEOUT_S + 1.0)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                reply = request(self.endpoint, {"request": "status"}, self.token, CONTROL_TIMEOUT_S)
                self.status = reply.get("status")
                self.error = None if reply.get("ok") else str(reply.get("error", "refused"))
            except UserError:
                self.error = "not answering"
            self._stop.wait(CONTROL_EVERY_S)


class Feed:
    """Follows the stream in its own thread; hands each new frame to ``on_frame`` (called
    in this thread), and a text to ``on_waiting`` while there is no state to show."""

    def __init__(self, model: WorldModel, publish: str, snapshot: str, rate_hz: float, control: ControlWatch,
                 on_frame: Callable[[Frame], None], on_waiting: Callable[[str], None], wait_s: float = 5.0) -> None:
        self.picture = Picture(model)
        self.publish, self.snapshot, self.period = publish, snapshot, 1.0 / rate_hz
        self.control, self.on_frame, self.on_waiting, self.wait_s = control, on_frame, on_waiting, wait_s
        self.frames, self.resyncs, self.lost = 0, 0, 0
        self.build_ms: list[float] = []  # time to make each frame (the last 1000)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="station-feed", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5.0)

    def _run(self) -> None:
        try:
            while not self._stop.is_set():  # a fresh subscriber after the node went silent (it may have restarted)
                with StateSubscriber(self.publish, self.snapshot, timeout_s=self.wait_s) as sub:
                    if self._join(sub):
                        self._follow(sub)
                    self.resyncs, self.lost = self.resyncs + sub.resyncs, self.lost + sub.lost
        except Exception:  # the page says the feed stopped; the log has why
            log.exception("station feed stopped")
            self.on_waiting("the station's feed stopped on an error (see its log)")

    def _join(self, sub: StateSubscriber) -> bool:
        """Take a snapshot (the node may not be up yet: say so); False if none came."""
        self.on_waiting(f"waiting for the node's state stream at {self.publish}")
        try:
            sub.sync(give_up=self._stop.is_set)
        except StreamError:
            return False
        self.picture.reset()
        self.picture.log.joined(sub.view.seq, sub.view.time, sub.view.ship.utc)
        return True

    def _follow(self, sub: StateSubscriber) -> None:
        """Apply the stream's steps and make frames until stopped, until a resync fails, or
        until no step came for ``SILENT_S`` (the node ended or restarted: join again)."""
        next_frame, last_message = time.monotonic(), time.monotonic()
        while not self._stop.is_set() and time.monotonic() - last_message < SILENT_S:
            try:
                seq = sub.view.seq
                applied = sub.poll(max(0, int((next_frame - time.monotonic()) * 1000)))
            except StreamError:
                return
            for events in applied:
                self.picture.log.on_events(events)
            if sub.view.seq != seq:
                last_message = time.monotonic()
            now = time.monotonic()
            if now >= next_frame:
                next_frame = max(next_frame + self.period, now)
                self._make_frame(sub, now - last_message)

    def _make_frame(self, sub: StateSubscriber, age_s: float) -> None:
        started = time.perf_counter()
        log, view, status = self.picture.log, sub.view, self.control.status  # replaced whole by its thread
        log.on_status(status, view.time, view.ship.utc)
        alarms = log.alarms(age_s, self.control.error, view.time, view.ship.utc)
        extra = {"alarms": alarms, "stream": {"age_s": round(age_s, 2), "resyncs": sub.resyncs, "lost": sub.lost},
                 "failures": log.failures.panel(), "links": None if status is None else list(log.links.values()),
                 "control": {"error": self.control.error, "rudder_order_deg": (status or {}).get("rudder_order_deg")}}
        frame = self.picture.frame(view, extra)
        self.build_ms = [*self.build_ms[-999:], (time.perf_counter() - started) * 1e3]
        self.frames += 1
        self.on_frame(frame)
