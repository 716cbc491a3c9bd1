"""``icebridge render-node``: render projector channels from a running node's state stream.

Connects to the node's stream (the config's ``[stream]``; ``--connect HOST`` for a node on
another PC), takes a snapshot, then renders its channels (``--channels``, default all) at
``--fps`` from the stream, one physics step behind and blending the two latest states, so
the picture moves smoothly whatever the physics rate. Window channels are shown on their
monitors; ``--frames-every S`` writes the PNG channels every S simulated seconds;
``--video FILE`` writes all its channels side by side at ``--video-fps``; ``--panorama
FILE`` writes the last picture of all channels side by side. It ends after ``--duration``
seconds, when the stream has been silent for ``--idle-exit`` seconds, or on Ctrl-C or
SIGTERM, and writes a JSON summary (frames, resyncs, input-to-pixels delay) to
``--summary``. ``--ship K`` renders from the K-th ship of ``[[ships]]``: its hull, its eyes
and its lights (``bridge_node.stream.follow``). ``--drop-every N`` and ``--frame-delay S`` inject faults for testing: drop
every N-th step message, sleep S seconds in every frame.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import signal
import threading
import time
from pathlib import Path
from urllib.parse import urlsplit, urlunsplit

from bridge_node.node.config import NodeConfig, load_config
from bridge_node.common.errors import UserError
from bridge_node.common.output_files import write_output
from bridge_node.node.realtime_loop import distribution
from bridge_node.node.world_setup import build_world
from bridge_node.render.channels import ChannelSet
from bridge_node.render.open_channels import open_channels, select_channels
from bridge_node.render.video import VideoWriter, save_png, side_by_side
from bridge_node.stream.publisher import HEARTBEAT_S
from bridge_node.stream.follow import FollowedShip, followed_model
from bridge_node.stream.settings import StreamSettings
from bridge_node.stream.subscriber import StateSubscriber, StreamError
from sim_core.ship.outputs import ShipOutputs
from sim_core.world import WorldModel

CATCH_UP_S = 6 * HEARTBEAT_S  # s spent on the node's last steps after SIGTERM (two heartbeats), at most


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--connect", metavar="HOST", help="the node's host (default: the config's [stream] endpoints)")
    p.add_argument("--channels", help="comma-separated channel names (default: all configured)")
    p.add_argument("--ship", type=int, default=0, metavar="K",
                   help="render from the K-th ship of [[ships]] (its hull, eyes and lights); 0, the default: the "
                        "first ship, [ship]")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--idle-exit", type=float, default=None, metavar="S",
                   help="stop when the stream has been silent this many seconds")
    p.add_argument("--frames-every", type=float, default=None, metavar="S",
                   help="write the PNG channels every S simulated seconds to OUT/frames/")
    p.add_argument("--video", default=None, metavar="FILE", help="write the channels side by side as a video")
    p.add_argument("--video-fps", type=float, default=5.0, help="video frames per second (default 5)")
    p.add_argument("--panorama", default=None, metavar="FILE", help="write the last picture of all channels")
    p.add_argument("--summary", default=None, metavar="FILE", help="write a JSON summary at the end")
    p.add_argument("--out", default="out", help="folder for the frames (default: out)")
    p.add_argument("--wait", type=float, default=30.0, help="seconds to wait for the node's first snapshot")
    p.add_argument("--niceness", type=int, default=0, choices=range(20), metavar="0..19",
                   help="lower this process's CPU priority by this much (the node passes render.niceness)")
    p.add_argument("--drop-every", type=int, default=None, metavar="N", help="fault injection: drop every N-th step")
    p.add_argument("--frame-delay", type=float, default=0.0, metavar="S", help="fault injection: slow every frame")


def endpoints(stream: StreamSettings, host: str | None) -> tuple[str, str]:
    """The publish and snapshot endpoints, on ``host`` instead of the configured one if given."""
    if host is None:
        return stream.publish, stream.snapshot
    out = []
    for endpoint in (stream.publish, stream.snapshot):
        parts = urlsplit(endpoint)
        out.append(urlunsplit(parts._replace(netloc=f"{host}:{parts.port}")))
    return out[0], out[1]


class _Outputs:
    """What a frame leaves behind: PNG frames, video frames, the last panorama."""

    def __init__(self, args: argparse.Namespace, channels: ChannelSet) -> None:
        self.args, self.channels = args, channels
        self.video = VideoWriter(Path(args.video), args.video_fps) if args.video else None
        self.next_png = 0.0
        self.next_video = 0.0
        self.pngs = 0

    def frame(self, sim_time: float, now: float) -> None:
        a = self.args
        if a.frames_every and sim_time >= self.next_png:
            self.next_png = sim_time + a.frames_every
            self.pngs += len(self.channels.save_png(Path(a.out) / "frames", f"t{sim_time:08.2f}_"))
        if self.video is not None and now >= self.next_video:
            self.next_video = now + 1.0 / a.video_fps
            self.video.write(side_by_side(self.channels.images()))

    def close(self) -> dict:
        out = {"png_frames": self.pngs}
        if self.video is not None:
            self.video.close()
            out |= {"video": self.args.video, "video_frames": self.video.frames}
        if self.args.panorama and self.channels.targets:
            out["panorama"] = str(save_png(side_by_side(self.channels.images()), Path(self.args.panorama),
                                           "--panorama"))
        return out


def _frame_pacing(next_frame: float, period: float) -> float:
    """Sleep until the next frame is due; returns when the one after is (a loop that fell
    more than a period behind starts again from now rather than bursting)."""
    next_frame += period
    behind = time.monotonic() - next_frame
    time.sleep(max(0.0, -behind))
    return time.monotonic() if behind > period else next_frame


def _render_loop(sub: StateSubscriber, channels: ChannelSet, outputs: _Outputs, args: argparse.Namespace,
                 stop: threading.Event) -> dict:
    """Render until the duration, the idle limit, SIGTERM or Ctrl-C (after at least one
    frame); returns frame statistics."""
    period, start = 1.0 / args.fps, time.monotonic()
    next_frame = last_message = start
    step_s, frames, delays, waiting, stepped = 0.0, 0, [], None, False
    drop = (lambda seq: seq % args.drop_every == 0) if args.drop_every else None
    try:
        while (args.duration is None or time.monotonic() - start < args.duration) and not (stop.is_set() and frames):
            before = sub.view.time
            applied = sub.poll(0, drop)
            now = time.monotonic()
            if applied:
                step_s, last_message, stepped = max(sub.view.time - before, 1e-3) / len(applied), now, True
                if sub.last_input is not None and sub.last_input[0] >= applied[0].seq and args.connect is None:
                    waiting = sub.last_input[1]  # monotonic clocks compare only on one host
            elif stepped and args.idle_exit is not None and now - last_message > args.idle_exit:
                break  # the physics has stopped stepping
            sub.view.blend((now - last_message) / step_s if step_s else 1.0)
            channels.render(sub.view)
            frames += 1
            if waiting is not None:  # the first frame that shows a state made with a new order
                delays.append((time.monotonic() - waiting) * 1e3)
                waiting = None
            outputs.frame(sub.view.time, now)
            time.sleep(args.frame_delay)
            next_frame = _frame_pacing(next_frame, period)
        if stop.is_set():  # the node asked us to finish: its last steps may still be on the way
            seq = sub.view.seq
            sub.catch_up(CATCH_UP_S)
            if sub.view.seq != seq:  # the last frame, the video's and the panorama's, shows them
                sub.view.blend(1.0)
                channels.render(sub.view)
                frames += 1
                outputs.frame(sub.view.time, float("inf"))
    except KeyboardInterrupt:
        pass
    except StreamError as exc:  # the node went away during a resync: end with what we have
        return {"frames": frames, "stream_error": str(exc), "input_to_pixels_ms": distribution(delays)}
    return {"frames": frames, "wall_s": round(time.monotonic() - start, 2), "input_to_pixels_ms": distribution(delays)}


# option -> (attribute, lowest, highest): NaN, infinity and 1e308 s would wait for ever
RANGES = {"--fps": ("fps", 1.0, 240.0), "--video-fps": ("video_fps", 0.1, 60.0), "--wait": ("wait", 0.1, 3600.0),
          "--duration": ("duration", 0.0, 1e6), "--idle-exit": ("idle_exit", 0.1, 3600.0),
          "--frames-every": ("frames_every", 0.0, 1e6), "--frame-delay": ("frame_delay", 0.0, 10.0)}


def _check(args: argparse.Namespace) -> None:
    """UserError for an option outside its range (the comparisons are false for NaN)."""
    for option, (name, lo, hi) in RANGES.items():
        value = getattr(args, name)
        if value is not None and not lo <= value <= hi:
            raise UserError(f"{option} {value} is outside the allowed range [{lo:g}, {hi:g}]")
    if args.drop_every is not None and args.drop_every < 2:
        raise UserError(f"--drop-every {args.drop_every}: must be at least 2")


def _where(ship: ShipOutputs | None) -> dict | None:
    """Where the ship the eyes ride on was last drawn (m, deg), for the summary."""
    return ship and {"north_m": round(ship.north, 1), "east_m": round(ship.east, 1),
                     "heading_deg": round(math.degrees(ship.heading), 1)}


def _followed(cfg: NodeConfig, model: WorldModel, k: int) -> FollowedShip | None:
    """How the stream turns into the k-th ship's (None: the first ship's, as published)."""
    if k == 0:
        return None
    first = model.ships[0].particulars
    return FollowedShip(k, cfg.ships[k - 1].mmsi, (cfg.ship.mmsi, first.length, first.beam))


def _write_summary(summary: dict, path: str | None) -> None:
    """Write the summary atomically (a reader never sees half of it), replacing only a
    regular file."""
    if path:
        write_output(path, json.dumps(summary), "--summary")


def run(args: argparse.Namespace) -> int:
    stop = threading.Event()  # SIGTERM from here on ends the work cleanly, with its outputs
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    os.nice(args.niceness)
    cfg = load_config(args.config)
    _check(args)
    if not 0 <= args.ship <= len(cfg.ships):
        raise UserError(f"--ship {args.ship}: the config lists {len(cfg.ships)} other ships in [[ships]]; give 0 "
                        f"to {len(cfg.ships)}")
    cfg = cfg.model_copy(update={"render": select_channels(cfg.render, args.channels.split(",") if args.channels
                                                           else None)})
    publish, snapshot = endpoints(cfg.stream, args.connect)
    model = build_world(cfg, args.config)
    follow = _followed(cfg, model, args.ship)
    model = followed_model(model, args.ship)
    channels = open_channels(cfg.render, model)
    summary: dict = {"channels": [c.name for c in cfg.render.channels], "publish": publish, "ship": args.ship}
    with StateSubscriber(publish, snapshot, timeout_s=args.wait, follow=follow) as sub:
        try:
            sub.sync(give_up=stop.is_set)
        except StreamError as exc:
            raise UserError(str(exc)) from None
        outputs = _Outputs(args, channels)
        try:
            summary |= _render_loop(sub, channels, outputs, args, stop)
        finally:
            summary |= outputs.close() | {"resyncs": sub.resyncs, "lost": sub.lost, "last_seq": sub.view.seq,
                                          "sim_time": round(sub.view.time, 3), "eye_ship": _where(sub.view.ship),
                                          "floe_memory": channels.renderer.floe_memory(sub.view)}
            _write_summary(summary, args.summary)
    print(json.dumps(summary))
    return 0
