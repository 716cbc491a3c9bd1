"""``icebridge instructor``: the instructor station, a web page for watching and commanding
a running exercise.

Its own process: it follows the node's state stream (the config's ``[stream]``;
``--connect HOST`` for a node on another PC) as render processes do, talks to the node only
through its control endpoint (``[control]``), and serves the page on ``[instructor]``'s
host and port (loopback unless ``allow_network``; with a token, the page asks for it).
Open the address it prints in a browser. Ends on Ctrl-C or SIGTERM, or after ``--duration``.
"""
from __future__ import annotations

import argparse
import json
import logging
import math
import signal
import socket
import threading
from urllib.parse import urlsplit, urlunsplit

import uvicorn

from bridge_node.node.config import load_config
from bridge_node.node.errors import UserError
from bridge_node.node.world_setup import build_world
from bridge_node.station.feed import ControlWatch, Feed
from bridge_node.station.geometry import geometry_message
from bridge_node.station.server import Broadcast, ControlTarget, Station


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--connect", metavar="HOST", help="the node's host (default: the config's [stream] and [control])")
    p.add_argument("--port", type=int, default=None, help="TCP port of the page (default: instructor.port)")
    p.add_argument("--record", metavar="DIR", default=None, dest="debrief_record",
                   help="debrief: open this session record instead of a live node (not built yet)")
    p.add_argument("--wait", type=float, default=5.0, help="seconds each try waits for the node's snapshot")
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")


def on_host(endpoint: str, host: str | None) -> str:
    """A ``tcp://HOST:PORT`` endpoint of the config, on ``host`` instead if given."""
    if host is None:
        return endpoint
    parts = urlsplit(endpoint)
    return urlunsplit(parts._replace(netloc=f"{'[' + host + ']' if ':' in host else host}:{parts.port}"))


def listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket; UserError naming the config keys if it cannot be had."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
        sock.listen(64)
    except OSError as exc:
        sock.close()
        raise UserError(f"instructor.host/port {host}:{port}: cannot listen there: {exc.strerror or exc}") from None
    return sock


def _check(args: argparse.Namespace) -> None:
    if args.debrief_record is not None:
        raise UserError("--record: the debrief mode is not built yet; open a live node instead")
    if args.port is not None and not 1 <= args.port <= 65535:
        raise UserError(f"--port {args.port}: outside the allowed range [1, 65535]")
    if not (math.isfinite(args.wait) and 0.1 <= args.wait <= 3600.0):
        raise UserError(f"--wait {args.wait}: outside the allowed range [0.1, 3600] s")
    if args.duration is not None and not (math.isfinite(args.duration) and 0.0 < args.duration <= 7 * 86400.0):
        raise UserError(f"--duration {args.duration}: outside the allowed range (0, 604800] s")


def run(args: argparse.Namespace) -> int:
    _check(args)
    cfg = load_config(args.config)
    settings = cfg.instructor
    token = cfg.control.access_token()
    if settings.allow_network and token is None:
        raise UserError("instructor.allow_network = true needs an access token: set control.token or the "
                        "ICEBRIDGE_TOKEN environment variable")
    publish, snapshot = on_host(cfg.stream.publish, args.connect), on_host(cfg.stream.snapshot, args.connect)
    target = ControlTarget(on_host(cfg.control.endpoint, args.connect), token)
    sock = listen(settings.host, args.port if args.port is not None else settings.port)
    model = build_world(cfg, args.config)
    broadcast = Broadcast()
    watch = ControlWatch(target.endpoint, token)
    feed = Feed(model, publish, snapshot, settings.rate_hz, watch, broadcast.publish, broadcast.wait_for_node,
                args.wait)
    host, port = sock.getsockname()[:2]
    url = f"http://{'[' + host + ']' if ':' in host else host}:{port}/"
    station = Station(geometry_message(model, cfg), broadcast, target, token, not settings.allow_network,
                      {"ship": cfg.ship.name, "stream": publish, "control": target.endpoint,
                       "token_needed": token is not None})
    server = uvicorn.Server(uvicorn.Config(station.app, log_level="warning", ws_max_size=1 << 16,
                                           lifespan="on"))
    signal.signal(signal.SIGTERM, lambda *_: None)  # uvicorn stops on it, then hands it on: end cleanly
    timer = threading.Timer(args.duration, lambda: setattr(server, "should_exit", True)) if args.duration else None
    logging.basicConfig(level=logging.WARNING)
    watch.start()
    feed.start()
    print(f"instructor station: {url} (state stream {publish}, control {target.endpoint})", flush=True)
    try:
        if timer:
            timer.start()
        server.run(sockets=[sock])
    finally:
        if timer:
            timer.cancel()
        feed.stop()
        watch.stop()
        sock.close()
    print(json.dumps({"url": url, "frames": feed.frames, "resyncs": feed.resyncs, "lost": feed.lost,
                      "frame_build_ms_max": round(max(feed.build_ms, default=0.0), 2)}))
    return 0
