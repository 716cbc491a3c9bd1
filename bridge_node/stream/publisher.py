"""The physics process's side of the state stream (the Clone pattern's server).

``StatePublisher.publish(events)`` is called by the physics loop after every step. It only
encodes the events and hands the frames over an IPC socket in a private folder (mode 0700,
so no other user's process can reach it; a loopback TCP port took any local connection) to
the publisher, which runs in its own process (never blocking: if the publisher falls behind by ``HANDOVER_HWM``
messages the step is counted as dropped, and subscribers resynchronise). A process, not a
thread: a thread woken by every step took the GIL from the physics thread inside each hand
over, and the physics thread waited for it to finish with the step (0.15 ms a step at the
median, up to the interpreter's 5 ms switch interval, 9 % of the main job's tick). The
publisher sends each message on the PUB socket, whose high-water mark drops a slow
subscriber's messages instead of waiting for it, and keeps a ``WorldView`` of everything
published, from which it answers snapshot requests on the ROUTER socket: a late joiner gets
every placed tile and every floe row, frozen channel included, and the other vessels, then
follows the live stream. Every ``HEARTBEAT_S`` it also publishes the last sequence number,
so a subscriber that lost the last steps before a pause notices it too. A handed-over
message that does not decode, or does not fit a view, is counted (``malformed``) and
dropped; the stream goes on.
"""
from __future__ import annotations

import logging
import multiprocessing as mp
import multiprocessing.connection
import shutil
import time
from pathlib import Path

import numpy as np
import zmq

from bridge_node.common.children import private_folder
from bridge_node.stream.codec import HEARTBEAT, CodecError, decode, encode
from bridge_node.stream.settings import StreamSettings
from bridge_node.stream.world_view import WorldView
from sim_core.world import WorldEvents

log = logging.getLogger("icebridge.stream")
HANDOVER_HWM = 1000  # messages between the physics loop and the publisher process
SNAPSHOT_REQUEST = b"snapshot"
STOP = b"stop"
HEARTBEAT_S = 0.5
START_TIMEOUT_S = 60.0  # for the publisher process to import and bind (a loaded machine)
_SENT, _SNAPSHOTS, _MALFORMED = 0, 1, 2  # indices of the shared counters


class StatePublisher:
    """The publisher process (PUB socket for steps, ROUTER socket for snapshots) and the
    physics side's handover socket; a context manager. ``sent`` and ``snapshots`` are
    counted by the publisher process and read here at any time."""

    def __init__(self, settings: StreamSettings, context: zmq.Context | None = None) -> None:
        self.settings = settings
        self.context = context or zmq.Context.instance()
        self.dropped = 0  # steps the publisher could not take in time
        self._push: zmq.Socket | None = None
        self._process: mp.process.BaseProcess | None = None
        self._pipe: mp.connection.Connection | None = None
        self._counters = None
        self._error: str | None = None
        self._folder: Path | None = None  # the private folder of the handover socket

    def open(self) -> None:
        """Start the publisher process, which binds the stream's sockets and a loopback
        handover socket; raises zmq.ZMQError if it cannot bind (e.g. address in use)."""
        ctx = mp.get_context("spawn")  # a fresh interpreter: no inherited ZeroMQ context or threads
        self._counters = ctx.RawArray("q", 3)
        self._folder = private_folder("stream")  # 0700: this user's alone
        ours, theirs = ctx.Pipe()
        self._process = ctx.Process(target=serve, args=(self.settings, self._counters, theirs,
                                                        f"ipc://{self._folder / 'handover'}"),
                                    name="state-publisher", daemon=True)
        self._process.start()
        theirs.close()
        try:
            kind, *detail = ours.recv() if ours.poll(START_TIMEOUT_S) else ("error", None, "did not start in time")
        except (EOFError, OSError):  # it ended before it said anything
            kind, detail = "error", [None, "ended at start"]
        if kind == "error":
            if self._process.is_alive():
                self._process.terminate()
            self._process.join(5.0)
            ours.close()
            shutil.rmtree(self._folder, ignore_errors=True)
            raise zmq.ZMQError(detail[0], f"the publisher process: {detail[1]} (exit code {self._process.exitcode})"
                               if detail[0] is None else detail[1])
        self._pipe = ours
        self._push = self.context.socket(zmq.PUSH)
        self._push.setsockopt(zmq.SNDHWM, HANDOVER_HWM)
        self._push.setsockopt(zmq.LINGER, 0)
        self._push.connect(detail[0])

    @property
    def sent(self) -> int:
        """Messages the publisher has sent on the PUB socket."""
        return 0 if self._counters is None else int(self._counters[_SENT])

    @property
    def snapshots(self) -> int:
        """Snapshot requests the publisher has answered."""
        return 0 if self._counters is None else int(self._counters[_SNAPSHOTS])

    @property
    def malformed(self) -> int:
        """Handed-over messages the publisher dropped: not decoded, or out of a view's bounds."""
        return 0 if self._counters is None else int(self._counters[_MALFORMED])

    def publish(self, events: WorldEvents, input_time: float | None = None, traffic: np.ndarray | None = None) -> None:
        """Hand one step's events and the traffic picture (``TRAFFIC_DTYPE`` rows; None:
        no other vessels) to the publisher; never blocks."""
        try:
            self._push.send_multipart(encode(events, input_time, traffic), flags=zmq.NOBLOCK, copy=False)
        except zmq.Again:
            self.dropped += 1

    @property
    def error(self) -> str | None:
        """Why the publisher process stopped, if it did."""
        if self._error is None and self._pipe is not None:
            self._error = self._stop_reason(stopping=False)
        return self._error

    def _stop_reason(self, stopping: bool) -> str | None:
        """What the publisher process said when it stopped on an error; a process gone
        without a word is an error unless it was told to stop."""
        try:
            if self._pipe.poll():
                return self._pipe.recv()[1]
        except (EOFError, OSError):
            if not stopping:
                return f"the publisher process ended (exit code {self._process.exitcode})"
        return None

    def close(self) -> None:
        """Let the publisher send what it was handed, stop it and release the sockets;
        safe to call twice, never hangs."""
        if self._push is None:
            return
        if self._process.is_alive():
            try:
                self._push.send_multipart([STOP], flags=zmq.NOBLOCK)
            except zmq.Again:
                pass
            self._process.join(5.0)
            if self._process.is_alive():
                self._process.terminate()
                self._process.join(5.0)
        if self._error is None:
            self._error = self._stop_reason(stopping=True)
        self._push.close(linger=0)
        self._push = None
        self._pipe.close()
        self._pipe = None
        shutil.rmtree(self._folder, ignore_errors=True)

    def __enter__(self) -> "StatePublisher":
        if self._push is None:
            self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _bind(context: zmq.Context, settings: StreamSettings, handover: str) -> list[zmq.Socket]:
    """The handover (PULL on ``handover``, an IPC socket), PUB and ROUTER sockets, bound."""
    pull, pub, router = (context.socket(kind) for kind in (zmq.PULL, zmq.PUB, zmq.ROUTER))
    pull.setsockopt(zmq.RCVHWM, HANDOVER_HWM)
    pub.setsockopt(zmq.SNDHWM, settings.send_hwm)
    pub.setsockopt(zmq.LINGER, 500)  # ms: the last steps still reach subscribers on close
    try:
        pull.bind(handover)
        pub.bind(settings.publish)
        router.bind(settings.snapshot)
    except zmq.ZMQError:
        for s in (pull, pub, router):
            s.close(linger=0)
        raise
    return [pull, pub, router]


def serve(settings: StreamSettings, counters, pipe: mp.connection.Connection, handover: str) -> None:
    """The publisher process: bind, say where the handover is (or why not), then relay and
    answer snapshots until told to stop or the physics process is gone."""
    context = zmq.Context()
    try:
        sockets = _bind(context, settings, handover)
    except zmq.ZMQError as exc:
        pipe.send(("error", exc.errno, str(exc)))
        return
    pipe.send(("ready", handover))
    pull, pub, router = sockets
    try:
        _relay(pull, pub, router, counters)
    except (zmq.ZMQError, ValueError) as exc:  # reported by ``error``; the physics loop goes on
        log.error("state publisher stopped: %s", exc)
        pipe.send(("stopped", str(exc)))
    finally:
        pull.close(linger=0)
        router.close(linger=0)
        pub.close()
        context.term()


def _relay(pull: zmq.Socket, pub: zmq.Socket, router: zmq.Socket, counters) -> None:
    view = WorldView()
    poller = zmq.Poller()
    poller.register(pull, zmq.POLLIN)
    poller.register(router, zmq.POLLIN)
    beat = time.monotonic()
    parent = mp.parent_process()
    while True:
        ready = dict(poller.poll(int(HEARTBEAT_S * 1000)))
        if pull in ready:
            frames = pull.recv_multipart()
            if frames == [STOP]:
                return
            try:
                events, _, traffic = decode(frames)
            except CodecError as exc:
                counters[_MALFORMED] += 1
                log.warning("state publisher: dropped a handed-over message: %s", exc)
                continue
            view.traffic = traffic
            view.apply(events)
            pub.send_multipart(frames)  # PUB drops at a subscriber's high-water mark
            counters[_SENT] += 1
        if router in ready:
            identity, *request = router.recv_multipart()
            if request == [SNAPSHOT_REQUEST] and view.ship is not None:
                router.send_multipart([identity, *encode(view.to_snapshot(), traffic=view.traffic)])
                counters[_SNAPSHOTS] += 1
            else:
                router.send_multipart([identity, b"not-ready"])
        if time.monotonic() - beat >= HEARTBEAT_S:  # after the step just relayed: it names that one
            if parent is not None and not parent.is_alive():
                return
            if view.ship is not None:
                pub.send_multipart([HEARTBEAT, str(view.seq).encode()])
            beat = time.monotonic()
