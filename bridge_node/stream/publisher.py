"""The physics process's side of the state stream (the Clone pattern's server).

``StatePublisher.publish(events)`` is called by the physics loop after every step. It only
encodes the events and hands the frames to the publisher's own thread over an in-process
socket (never blocking: if that thread falls behind by ``HANDOVER_HWM`` messages the step
is counted as dropped, and subscribers resynchronise). The thread sends each message on
the PUB socket, whose high-water mark drops a slow subscriber's messages instead of
waiting for it, and keeps a ``WorldView`` of everything published, from which it answers
snapshot requests on the ROUTER socket: a late joiner gets every placed tile and every
floe row, frozen channel included, and the other vessels, then follows the live stream.
Every ``HEARTBEAT_S`` it also publishes the last sequence number, so a subscriber that lost
the last steps before a pause notices it too.
"""
from __future__ import annotations

import itertools
import logging
import threading
import time

import numpy as np
import zmq

from bridge_node.stream.codec import HEARTBEAT, decode, encode
from bridge_node.stream.settings import StreamSettings
from bridge_node.stream.world_view import WorldView
from sim_core.world import WorldEvents

log = logging.getLogger("icebridge.stream")
HANDOVER_HWM = 1000  # messages between the physics thread and the publisher thread
SNAPSHOT_REQUEST = b"snapshot"
HEARTBEAT_S = 0.5
_instances = itertools.count()


class StatePublisher:
    """PUB socket for steps, ROUTER socket for snapshots, one thread; a context manager."""

    def __init__(self, settings: StreamSettings, context: zmq.Context | None = None) -> None:
        self.settings = settings
        self.context = context or zmq.Context.instance()
        self.dropped = 0  # steps the publisher thread could not take in time
        self.sent = 0
        self.snapshots = 0
        self._inproc = f"inproc://icebridge-publisher-{next(_instances)}"
        self._push: zmq.Socket | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None

    def open(self) -> None:
        """Start the thread, which creates and binds its sockets (all ZeroMQ sockets are
        used by the thread that made them); raises zmq.ZMQError, e.g. address in use."""
        self._thread = threading.Thread(target=self._serve, name="state-publisher", daemon=True)
        self._thread.start()
        self._ready.wait()
        if self._error is not None:
            self._thread.join()
            raise self._error
        self._push = self.context.socket(zmq.PUSH)
        self._push.setsockopt(zmq.SNDHWM, HANDOVER_HWM)
        self._push.connect(self._inproc)

    def publish(self, events: WorldEvents, input_time: float | None = None, traffic: np.ndarray | None = None) -> None:
        """Hand one step's events and the traffic picture (``TRAFFIC_DTYPE`` rows; None:
        no other vessels) to the publisher thread; never blocks."""
        try:
            self._push.send_multipart(encode(events, input_time, traffic), flags=zmq.NOBLOCK, copy=False)
        except zmq.Again:
            self.dropped += 1

    def _bind(self) -> list[zmq.Socket]:
        pull, pub, router = (self.context.socket(kind) for kind in (zmq.PULL, zmq.PUB, zmq.ROUTER))
        pub.setsockopt(zmq.SNDHWM, self.settings.send_hwm)
        pub.setsockopt(zmq.LINGER, 500)  # ms: the last steps still reach subscribers on close
        try:
            pull.bind(self._inproc)
            pub.bind(self.settings.publish)
            router.bind(self.settings.snapshot)
        except zmq.ZMQError:
            for s in (pull, pub, router):
                s.close(linger=0)
            raise
        return [pull, pub, router]

    def _serve(self) -> None:
        try:
            pull, pub, router = self._bind()
        except zmq.ZMQError as exc:
            self._error = exc
            self._ready.set()
            return
        self._ready.set()
        try:
            self._loop(pull, pub, router)
        except (zmq.ZMQError, ValueError) as exc:  # reported by close(); the physics loop goes on
            self._error = exc
            log.error("state publisher stopped: %s", exc)
        finally:
            pull.close(linger=0)
            router.close(linger=0)
            pub.close()

    def _loop(self, pull: zmq.Socket, pub: zmq.Socket, router: zmq.Socket) -> None:
        view = WorldView()
        poller = zmq.Poller()
        poller.register(pull, zmq.POLLIN)
        poller.register(router, zmq.POLLIN)
        beat = time.monotonic()
        while True:
            ready = dict(poller.poll(int(HEARTBEAT_S * 1000)))
            if time.monotonic() - beat >= HEARTBEAT_S and view.ship is not None:
                pub.send_multipart([HEARTBEAT, str(view.seq).encode()])
                beat = time.monotonic()
            if pull in ready:
                frames = pull.recv_multipart()
                if frames == [b"stop"]:
                    return
                events, _, view.traffic = decode(frames)
                view.apply(events)
                pub.send_multipart(frames)  # PUB drops at a subscriber's high-water mark
                self.sent += 1
            if router in ready:
                identity, *request = router.recv_multipart()
                if request == [SNAPSHOT_REQUEST] and view.ship is not None:
                    router.send_multipart([identity, *encode(view.to_snapshot(), traffic=view.traffic)])
                    self.snapshots += 1
                else:
                    router.send_multipart([identity, b"not-ready"])

    @property
    def error(self) -> str | None:
        """Why the publisher thread stopped, if it did."""
        return None if self._error is None else str(self._error)

    def close(self) -> None:
        """Stop the thread and release the sockets; safe to call twice, never hangs."""
        if self._push is None:
            return
        if self._thread.is_alive():
            try:
                self._push.send_multipart([b"stop"], flags=zmq.NOBLOCK)
            except zmq.Again:
                pass
            self._thread.join(5.0)
        self._push.close(linger=0)
        self._push = None

    def __enter__(self) -> "StatePublisher":
        if self._push is None:
            self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()
