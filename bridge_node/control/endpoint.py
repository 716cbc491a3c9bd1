"""The node's control endpoint: a ZeroMQ ROUTER, served from its own thread, that takes the
instructor's commands, checks them, and queues them for the tick (``CommandQueue``).

A request is one JSON object: ``{"token": ..., "command": {...}}`` to command, or
``{"token": ..., "request": "status"}`` for the exercise's state. Every request gets one
reply: ``{"ok": true, ...}`` or ``{"ok": false, "error": "..."}``. Nothing a client sends
can stop the endpoint or slow the physics: a message over ``MAX_MESSAGE_BYTES`` is dropped
by ZeroMQ itself (which drops the peer's connection), one over ``MAX_COMMAND_BYTES`` is
refused unread, at most ``per_second`` messages are taken a second, and a full queue refuses
("busy"). Past ``per_second``, up to ``REFUSALS_PER_SECOND`` more get a refusal ("flooding")
that costs no parsing; after those the endpoint reads nothing more until the next second,
so a flood waits in its sender's queue (ZeroMQ's back-pressure) and holds the interpreter
for a bounded share of each second. Each refusal is counted by its reason.
"""
from __future__ import annotations

import hmac
import json
import threading
import time
from collections import Counter
from collections.abc import Callable, Sequence
from pathlib import Path

import zmq

from bridge_node.control.commands import (
    MAX_COMMAND_BYTES,
    CommandError,
    LinkFaultCommand,
    SaveCommand,
    ShipCommand,
    WireCommand,
    parse_command,
)
from bridge_node.control.ice_command import SetIceCommand
from bridge_node.control.queue import CommandQueue
from bridge_node.control.settings import ControlSettings
from bridge_node.control.save_point import SAVES_FOLDER
from bridge_node.common.errors import UserError

MAX_MESSAGE_BYTES = 65536  # ZeroMQ drops larger messages, and the connection of their sender
POLL_MS = 100  # the thread looks at its stop flag this often
REFUSALS_PER_SECOND = 1000  # "flooding" replies a second past per_second; then nothing is read until the next
_FLOODING = json.dumps({"ok": False, "error": "flooding: too many messages a second; refused"}).encode()


class ControlEndpoint:
    """Serves the control endpoint while started; ``status()`` gives the exercise's state
    for status requests. A context manager; stopping twice is safe."""

    def __init__(self, settings: ControlSettings, queue: CommandQueue, status: Callable[[], dict],
                 links: Sequence[str] = (), record: Path | None = None, ice: Sequence[str] = (),
                 ships: int = 1) -> None:
        self.settings, self.queue, self.status = settings, queue, status
        self.ships = ships  # the exercise's own ships
        self.links, self.record = tuple(links), record  # the links' names; the session record's folder
        self.ice = tuple(ice)  # the names of the ice the exercise can lay (``SceneModel.class_names``)
        self._save_names: set[str] = set()  # save points asked for (a file is written at its tick)
        self.token = settings.access_token()
        if settings.allow_network and self.token is None:
            raise UserError("control.allow_network = true needs an access token: set control.token or the "
                            "ICEBRIDGE_TOKEN environment variable")
        self.counts: Counter = Counter()  # "accepted", and refusals by reason
        self._stop = threading.Event()
        self._context = zmq.Context()
        self._socket = self._context.socket(zmq.ROUTER)
        self._socket.setsockopt(zmq.MAXMSGSIZE, MAX_MESSAGE_BYTES)
        self._socket.setsockopt(zmq.LINGER, 0)
        try:
            self._socket.bind(settings.endpoint)
        except zmq.ZMQError as exc:
            self._socket.close()
            self._context.term()
            raise UserError(f"control.endpoint = {settings.endpoint!r}: cannot listen there: {exc}") from None
        self._thread = threading.Thread(target=self._serve, name="icebridge-control", daemon=True)
        self._second, self._taken = 0, 0  # the second counted (monotonic, whole), messages taken in it

    def __enter__(self) -> ControlEndpoint:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    def stop(self) -> None:
        """Stop serving and close the socket; safe to call twice."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5.0)
        if not self._socket.closed:
            self._socket.close()
            self._context.term()

    def _serve(self) -> None:
        poller = zmq.Poller()
        poller.register(self._socket, zmq.POLLIN)
        while not self._stop.is_set():
            if not poller.poll(POLL_MS):
                continue
            frames = self._socket.recv_multipart()
            if len(frames) < 2:
                continue
            now = time.monotonic()
            if int(now) != self._second:
                self._second, self._taken = int(now), 0
            self._taken += 1
            if self._taken <= self.settings.per_second:
                reply = json.dumps(self._answer(frames[-1])).encode()
            else:
                self.counts["flooding"] += 1
                reply = _FLOODING
            self._socket.send_multipart([*frames[:-1], reply])
            if self._taken >= self.settings.per_second + REFUSALS_PER_SECOND:
                self._stop.wait(self._second + 1.0 - time.monotonic())

    def _refuse(self, reason: str, error: str) -> dict:
        self.counts[reason] += 1
        return {"ok": False, "error": error}

    def _answer(self, payload: bytes) -> dict:
        """The reply to one request."""
        if len(payload) > MAX_COMMAND_BYTES:
            return self._refuse("oversized", f"message of {len(payload)} bytes; at most {MAX_COMMAND_BYTES}")
        try:
            request = json.loads(payload)
        except (ValueError, RecursionError):
            return self._refuse("malformed", "not a JSON object")
        if not isinstance(request, dict):
            return self._refuse("malformed", "not a JSON object")
        token = request.get("token")
        if self.token is not None and not (isinstance(token, str) and hmac.compare_digest(token, self.token)):
            return self._refuse("unauthorised", "access token missing or wrong")
        if request.get("request") == "status":
            self.counts["status"] += 1
            return {"ok": True, "status": self.status()}
        return self._command(request.get("command"))

    def _command(self, message: object) -> dict:
        try:
            command = parse_command(message)
            extra = self._node_check(command)
        except CommandError as exc:
            return self._refuse("invalid", str(exc))
        if not self.queue.put(command):
            return self._refuse("busy", f"{self.queue.capacity} commands already wait for the physics; refused")
        self.counts["accepted"] += 1
        return {"ok": True, "queued": command.command, **extra}

    def _node_check(self, command: WireCommand) -> dict:
        """What a command to the node needs of this node (a link it has, a record to save
        in); CommandError if it is not there. Returns what the reply adds (a save's path)."""
        if isinstance(command, LinkFaultCommand) and command.link not in self.links:
            raise CommandError(f"link = {json.dumps(command.link)}: no such link; the node's links: "
                               f"{', '.join(self.links) or 'none'}")
        if isinstance(command, SetIceCommand) and command.ice not in self.ice:
            raise CommandError(f"ice = {json.dumps(command.ice)}: this exercise has no such ice; it has: "
                               f"{', '.join(json.dumps(name) for name in self.ice) or 'none'}")
        if isinstance(command, ShipCommand) and command.ship >= self.ships:
            raise CommandError(f"ship = {command.ship}: this exercise has {self.ships} own ship(s): 0 ([ship])"
                               + (f" to {self.ships - 1} ([[ships]])" if self.ships > 1 else ""))
        if not isinstance(command, SaveCommand):
            return {}
        if self.record is None:
            raise CommandError("save: this run keeps no session record (--no-record): there is nothing to "
                               "re-simulate a save point from")
        path = self.record / SAVES_FOLDER / f"{command.name}.json"
        if path.exists() or command.name in self._save_names:
            raise CommandError(f"name = {json.dumps(command.name)}: the save point {path} exists already")
        self._save_names.add(command.name)
        return {"path": str(path.resolve())}
