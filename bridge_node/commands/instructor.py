"""``icebridge instructor``: the instructor station, a web page for watching and commanding
a running exercise.

Its own process: it follows the node's state stream (the config's ``[stream]``;
``--connect HOST`` for a node on another PC) as render processes do, talks to the node only
through its control endpoint (``[control]``), and serves the page on ``[instructor]``'s
host and port (loopback unless ``allow_network``; with a token, the page asks for it).
Open the address it prints in a browser. Ends on Ctrl-C or SIGTERM, or after ``--duration``.

``--record DIR`` opens a session record for debrief instead: the ship's track played back on
the same map (play, pause, seek, 1-1000x) from what the node sent the instruments, with the
instructor's commands and the alarms in the event log, and time plots of speed, heading,
rudder, RPM and ice resistance (``/plots.png``; ``--export PNG`` writes them and ends).
"""
from __future__ import annotations

import argparse
import json
import logging
import math
import os
import signal
import socket
import threading
from pathlib import Path
from urllib.parse import urlsplit, urlunsplit

import uvicorn

from bridge_node.charts.field_regions import configured_regions
from bridge_node.node.config import load_config
from bridge_node.common.errors import UserError
from bridge_node.node.world_setup import build_world
from bridge_node.common.output_files import write_output
from bridge_node.station.debrief import debrief_message, load_debrief, plot_png
from bridge_node.station.feed import ControlWatch, Feed
from bridge_node.station.geometry import geometry_message
from bridge_node.station.server import Broadcast, ControlTarget, Station


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--connect", metavar="HOST", help="the node's host (default: the config's [stream] and [control])")
    p.add_argument("--port", type=int, default=None, help="TCP port of the page (default: instructor.port)")
    p.add_argument("--record", metavar="DIR", default=None, dest="debrief_record",
                   help="debrief: play this session record on the map, with its time plots, instead of a live node")
    p.add_argument("--export", metavar="PNG", default=None,
                   help="with --record: write the record's time plots to this PNG file and end")
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
    if args.export is not None and args.debrief_record is None:
        raise UserError("--export writes a record's time plots: give the record with --record DIR")
    if args.port is not None and not 1 <= args.port <= 65535:
        raise UserError(f"--port {args.port}: outside the allowed range [1, 65535]")
    if not (math.isfinite(args.wait) and 0.1 <= args.wait <= 3600.0):
        raise UserError(f"--wait {args.wait}: outside the allowed range [0.1, 3600] s")
    if args.duration is not None and not (math.isfinite(args.duration) and 0.0 < args.duration <= 7 * 86400.0):
        raise UserError(f"--duration {args.duration}: outside the allowed range (0, 604800] s")


def run(args: argparse.Namespace) -> int:
    _check(args)
    cfg = load_config(args.config)
    os.nice(cfg.instructor.niceness)  # beside the node, the physics loop comes first for the CPU
    token = cfg.control.access_token()
    if cfg.instructor.allow_network and token is None:
        raise UserError("instructor.allow_network = true needs an access token: set control.token or the "
                        "ICEBRIDGE_TOKEN environment variable")
    if args.debrief_record is not None:
        return _debrief(args, cfg, token)
    publish, snapshot = on_host(cfg.stream.publish, args.connect), on_host(cfg.stream.snapshot, args.connect)
    target = ControlTarget(on_host(cfg.control.endpoint, args.connect), token)
    sock = listen(cfg.instructor.host, args.port if args.port is not None else cfg.instructor.port)
    model = build_world(cfg, args.config)
    broadcast = Broadcast()
    watch = ControlWatch(target.endpoint, token)
    feed = Feed(model, publish, snapshot, cfg.instructor.rate_hz, watch, broadcast.publish, broadcast.wait_for_node,
                args.wait)
    station = Station(_geometry(model, cfg), broadcast, target, token, not cfg.instructor.allow_network,
                      {"mode": "live", "ship": cfg.ship.name, "stream": publish, "control": target.endpoint})
    watch.start()
    feed.start()
    try:
        url = _serve(station, sock, args, f"state stream {publish}, control {target.endpoint}")
    finally:
        feed.stop()
        watch.stop()
    print(json.dumps({"url": url, "frames": feed.frames, "resyncs": feed.resyncs, "lost": feed.lost,
                      "frame_build_ms_max": round(max(feed.build_ms, default=0.0), 2)}))
    return 0


def _geometry(model, cfg) -> bytes:
    """The station's geometry message of the configured exercise, with its ice regions."""
    return geometry_message(model, cfg.ship.name, cfg.instructor.rate_hz,
                            configured_regions(cfg.ice_field, cfg.exercise.origin_deg()), cfg.convoy,
                            [cfg.ship.shown_name(), *(ship.shown_name() for ship in cfg.ships)])


def _debrief(args: argparse.Namespace, cfg, token: str | None) -> int:
    """Play a session record (or, with --export, write its time plots and end)."""
    model = build_world(cfg, args.config)
    debrief = load_debrief(Path(args.debrief_record), model.origin)
    plots = plot_png(debrief)
    if args.export is not None:
        print(json.dumps({"plots": str(write_output(args.export, plots, "--export")),
                          "duration_s": round(debrief.end - debrief.start, 1), "events": len(debrief.events)}))
        return 0
    sock = listen(cfg.instructor.host, args.port if args.port is not None else cfg.instructor.port)
    broadcast = Broadcast()
    broadcast.waiting = None  # nothing live to wait for
    station = Station(_geometry(model, cfg), broadcast, None, token, not cfg.instructor.allow_network,
                      {"mode": "debrief", "ship": cfg.ship.name, "record": str(debrief.folder)},
                      (debrief_message(debrief, _fleet(cfg, model)), plots))
    print(json.dumps({"url": _serve(station, sock, args, f"debrief of {debrief.folder}")}))
    return 0


def _fleet(cfg, model) -> dict[int, tuple[str, float, float]]:
    """The config's other own ships as the debrief names and draws them: k -> (name,
    length m, beam m)."""
    return {k: (ship.shown_name(), model.ships[k].particulars.length, model.ships[k].particulars.beam)
            for k, ship in enumerate(cfg.ships, start=1)}


def _serve(station: Station, sock: socket.socket, args: argparse.Namespace, what: str) -> str:
    """Serve the page until SIGTERM, Ctrl-C or --duration; returns its address."""
    host, port = sock.getsockname()[:2]
    url = f"http://{'[' + host + ']' if ':' in host else host}:{port}/"
    server = uvicorn.Server(uvicorn.Config(station.app, log_level="warning", ws_max_size=1 << 16, lifespan="on"))
    signal.signal(signal.SIGTERM, lambda *_: None)  # uvicorn stops on it, then hands it on: end cleanly
    timer = threading.Timer(args.duration, lambda: setattr(server, "should_exit", True)) if args.duration else None
    logging.basicConfig(level=logging.WARNING)
    print(f"instructor station: {url} ({what})", flush=True)
    try:
        if timer:
            timer.start()
        server.run(sockets=[sock])
    finally:
        if timer:
            timer.cancel()
        sock.close()
    return url
