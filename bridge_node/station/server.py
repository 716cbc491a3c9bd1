"""The station's web server: Starlette on uvicorn. ``/`` is the page (shipped in
``static/``), ``/ws`` its WebSocket: the server sends the exercise's geometry once, then a
binary frame about ten times a second (only what changed since the last one that browser
got: a slow browser skips frames, it never falls behind); the page sends commands as JSON
(``{"type": "command", "id": n, "command": {...}}``), which go to the node's control
endpoint, and gets the node's reply (``{"type": "reply", "id": n, "ok": ..., "error": ...}``)."""
from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from dataclasses import dataclass
from pathlib import Path

import anyio
from starlette.applications import Starlette
from starlette.responses import FileResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from bridge_node.control.client import request
from bridge_node.control.commands import MAX_COMMAND_BYTES
from bridge_node.common.errors import UserError
from bridge_node.station.gate import TokenGate
from bridge_node.station.picture import ClientCursor, Frame, message_for

STATIC = Path(__file__).resolve().parent / "static"
COMMAND_TIMEOUT_S = 3.0
log = logging.getLogger("icebridge.station")


@dataclass(frozen=True)
class ControlTarget:
    """Where the station sends the instructor's commands."""

    endpoint: str
    token: str | None


class Broadcast:
    """The latest frame (or waiting text), handed over from the feed thread to every
    connected browser's sender on the event loop."""

    def __init__(self) -> None:
        self.frame: Frame | None = None
        self.waiting: str | None = "starting"
        self.loop: asyncio.AbstractEventLoop | None = None
        self.wakers: set[asyncio.Event] = set()

    def _wake(self) -> None:
        for event in self.wakers:
            event.set()

    def _wake_from_thread(self) -> None:
        try:
            if self.loop is not None:
                self.loop.call_soon_threadsafe(self._wake)
        except RuntimeError:  # the server has stopped (its loop is closed): nobody to tell
            pass

    def publish(self, frame: Frame) -> None:
        """A new frame (from any thread)."""
        self.frame, self.waiting = frame, None
        self._wake_from_thread()

    def wait_for_node(self, text: str) -> None:
        """No state to show, and why (from any thread)."""
        self.waiting = text
        self._wake_from_thread()


def _check_command(text: str) -> tuple[object, dict | str]:
    """The id and command of a page's message, or its id and why it is refused."""
    if len(text) > MAX_COMMAND_BYTES:
        return None, f"message of {len(text)} bytes; at most {MAX_COMMAND_BYTES}"
    try:
        message = json.loads(text)
    except ValueError:
        return None, "not JSON"
    if not isinstance(message, dict) or message.get("type") != "command":
        return None, "not a command message"
    ident, command = message.get("id"), message.get("command")
    if not isinstance(command, dict):
        return ident, "command: not a JSON object"
    return ident, command


async def _send_command(target: ControlTarget | None, text: str) -> dict:
    """The reply to one command message of the page (the node's, or why it never got there)."""
    ident, command = _check_command(text)
    if target is None and not isinstance(command, str):
        command = "a debrief plays a record: there is no node to command"
    if isinstance(command, str):
        return {"type": "reply", "id": ident, "ok": False, "error": command}
    try:
        reply = await anyio.to_thread.run_sync(request, target.endpoint, {"command": command}, target.token,
                                               COMMAND_TIMEOUT_S)
    except UserError as exc:
        reply = {"ok": False, "error": str(exc)}
    return {"type": "reply", "id": ident, "command": command.get("command"), "ok": bool(reply.get("ok")),
            "error": reply.get("error"), "reply": reply}


class Station:
    """The ASGI app: page, static assets and WebSocket, behind the ``TokenGate``. A debrief
    (``target`` None) sends its ``debrief`` message after the geometry, and serves its
    time plots at ``/plots.png``."""

    def __init__(self, geometry: bytes, broadcast: Broadcast, target: ControlTarget | None, token: str | None,
                 loopback_only: bool, info: dict, debrief: tuple[bytes, bytes] | None = None) -> None:
        self.geometry, self.broadcast, self.target, self.info = geometry, broadcast, target, info
        self.debrief = debrief
        app = Starlette(routes=[
            Route("/", self.index), Route("/index.html", self.index), Route("/plots.png", self.plots),
            WebSocketRoute("/ws", self.socket),
            Mount("/static", app=StaticFiles(directory=STATIC), name="static"),
        ], lifespan=self._lifespan)
        self.app = TokenGate(app, token, loopback_only)
        self.clients = 0

    @contextlib.asynccontextmanager
    async def _lifespan(self, _app):
        self.broadcast.loop = asyncio.get_running_loop()
        yield

    async def index(self, _request) -> FileResponse:
        return FileResponse(STATIC / "index.html", headers={"cache-control": "no-store"})

    async def plots(self, _request) -> Response:
        if self.debrief is None:
            return Response("no record open: the time plots belong to a debrief", 404)
        return Response(self.debrief[1], media_type="image/png", headers={"cache-control": "no-store"})

    async def socket(self, ws: WebSocket) -> None:
        await ws.accept()
        self.clients += 1
        wake = asyncio.Event()
        self.broadcast.wakers.add(wake)
        try:
            await ws.send_text(json.dumps({"type": "hello", **self.info}))
            await ws.send_bytes(self.geometry)
            if self.debrief is not None:
                await ws.send_bytes(self.debrief[0])
            sender = asyncio.create_task(self._sender(ws, wake))
            try:
                await self._receiver(ws)
            finally:
                sender.cancel()
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass  # the browser went away
        finally:
            self.broadcast.wakers.discard(wake)
            self.clients -= 1

    async def _receiver(self, ws: WebSocket) -> None:
        while True:
            text = await ws.receive_text()
            await ws.send_text(json.dumps(await _send_command(self.target, text)))

    async def _sender(self, ws: WebSocket, wake: asyncio.Event) -> None:
        try:
            await self._send_frames(ws, wake)
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass  # the browser went away: the receiver ends too

    async def _send_frames(self, ws: WebSocket, wake: asyncio.Event) -> None:
        cursor, sent, waiting = ClientCursor(), 0, None
        wake.set()
        while True:
            await wake.wait()
            wake.clear()
            b = self.broadcast
            if b.waiting is not None:
                if b.waiting != waiting:
                    waiting = b.waiting
                    await ws.send_text(json.dumps({"type": "waiting", "text": waiting}))
                continue
            waiting = None
            frame = b.frame
            if frame is not None and frame.number != sent:
                sent = frame.number
                await ws.send_bytes(message_for(frame, cursor))
