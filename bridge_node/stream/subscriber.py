"""A consumer's side of the state stream (the Clone pattern's client).

It subscribes first, then asks the snapshot service for the whole state and applies it to
its ``WorldView``; from then on it applies every step whose sequence number follows the
view's. Updates older than the snapshot are skipped; a gap in the sequence (messages lost
to a high-water mark, the network, or a restart of the node), or a heartbeat naming a step
it has not seen, makes it ask for a snapshot again rather than draw a wrong state.
"""
from __future__ import annotations

import time

import numpy as np
import zmq

from bridge_node.stream.codec import HEARTBEAT, CodecError, decode
from bridge_node.stream.follow import FollowedShip
from bridge_node.stream.publisher import SNAPSHOT_REQUEST
from bridge_node.stream.world_view import WorldView
from sim_core.world import WorldEvents


class StreamError(RuntimeError):
    """The node does not answer: no snapshot within the timeout."""


class StateSubscriber:
    """SUB + DEALER sockets and the view they keep; a context manager."""

    def __init__(self, publish: str, snapshot: str, timeout_s: float = 10.0,
                 context: zmq.Context | None = None, follow: FollowedShip | None = None) -> None:
        """``follow``: the view is the world as another own ship's bridge sees it
        (``bridge_node.stream.follow``; None: as the node's first ship's)."""
        self.context = context or zmq.Context.instance()
        self.publish_endpoint, self.snapshot_endpoint = publish, snapshot
        self.timeout_s = timeout_s
        self.follow = follow
        self.view = WorldView()
        self.resyncs = 0  # snapshots taken after a gap
        self.lost = 0  # steps missed (before each resync)
        self.malformed = 0
        self.heartbeats = 0  # heartbeats received
        self.last_input: tuple[int, float] | None = None  # (seq, monotonic input time) of the last input
        self._sub = self.context.socket(zmq.SUB)
        self._sub.setsockopt(zmq.SUBSCRIBE, b"")
        self._sub.setsockopt(zmq.RCVHWM, 1000)
        self._sub.connect(publish)
        self._dealer: zmq.Socket | None = None

    def sync(self, give_up=lambda: False) -> None:
        """Ask for a snapshot and apply it; StreamError if none comes within the timeout
        (or when ``give_up()`` turns true while waiting)."""
        deadline = time.monotonic() + self.timeout_s
        self._request()
        while True:
            if self._dealer.poll(200):
                frames = self._dealer.recv_multipart()
                if frames != [b"not-ready"]:
                    try:
                        message = decode(frames)
                    except CodecError:
                        self.malformed += 1
                        continue
                    if message[0].seq >= self.view.seq:  # not a stale reply to an earlier request
                        self._apply(message)
                        return
                    continue
                time.sleep(0.05)  # the node has not stepped yet: ask again
                self._request()
            if time.monotonic() > deadline or give_up():
                self._dealer.close(linger=0)  # a fresh socket next time drops a stale reply
                self._dealer = None
                raise StreamError(f"no snapshot from {self.snapshot_endpoint} within {self.timeout_s:g} s: "
                                  "is the node running, and is its [stream] the same?")

    def _request(self) -> None:
        if self._dealer is None:
            self._dealer = self.context.socket(zmq.DEALER)
            self._dealer.connect(self.snapshot_endpoint)
        self._dealer.send(SNAPSHOT_REQUEST)

    def _apply(self, message: tuple[WorldEvents, float | None, np.ndarray]) -> None:
        events, input_time, traffic = message
        if self.follow is not None:
            try:
                events, traffic = self.follow(events, traffic)
            except ValueError as exc:  # a node of another exercise: its ships are not the config's
                raise StreamError(f"{self.publish_endpoint}: {exc}") from None
        self.view.traffic = traffic
        self.view.apply(events)
        if input_time is not None:
            self.last_input = (events.seq, input_time)

    def poll(self, timeout_ms: int = 0, drop=None) -> list[WorldEvents]:
        """Apply every pending step (waiting up to timeout_ms for the first message, step or
        heartbeat); returns the events applied. ``drop(seq)`` may discard messages on
        purpose (fault injection)."""
        applied, wait = [], timeout_ms
        while self._sub.poll(wait):
            frames, wait = self._sub.recv_multipart(), 0
            if frames[0] == HEARTBEAT:
                self._heartbeat(frames)
                continue
            try:
                message = decode(frames)
            except CodecError:
                self.malformed += 1
                continue
            events = message[0]
            if events.seq <= self.view.seq or (drop is not None and drop(events.seq)):
                continue
            if events.seq != self.view.seq + 1:
                self._resync(events.seq - self.view.seq - 1)
                continue
            self._apply(message)
            applied.append(events)
        return applied

    def catch_up(self, timeout_s: float) -> list[WorldEvents]:
        """Apply what is pending, then wait for the publisher's second heartbeat from now
        (each names the last step it has sent) and apply every step up to it,
        resynchronising if one was lost: at the end of a run, this is the last state the
        node published before it asked us to finish. Returns the events applied; gives up
        after ``timeout_s`` (the node is gone), plus a resync's own wait.

        The first heartbeat may have been sent before the last steps reached the publisher
        (they pass from the node to the publisher process, and from there to us); the
        second comes a heartbeat period later."""
        applied = self.poll(0)
        seen, deadline = self.heartbeats, time.monotonic() + timeout_s
        while self.heartbeats < seen + 2:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            applied += self.poll(max(1, int(left * 1000)))
        return applied

    def _heartbeat(self, frames: list[bytes]) -> None:
        try:
            seq = int(frames[1])
        except (IndexError, ValueError):
            self.malformed += 1
            return
        self.heartbeats += 1
        if seq > self.view.seq:  # steps published before the heartbeat never arrived
            self._resync(seq - self.view.seq)

    def _resync(self, lost: int) -> None:
        self.lost += lost
        self.resyncs += 1
        self.sync()

    def close(self) -> None:
        """Release the sockets; safe to call twice."""
        for s in (self._sub, self._dealer):
            if s is not None:
                s.close(linger=0)
        self._dealer = None

    def __enter__(self) -> "StateSubscriber":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
