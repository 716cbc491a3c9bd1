"""The node's local render processes: one ``icebridge render-node`` per channel group,
started beside the physics process, watched, and restarted if one dies.

Physics never waits for them: they read the state stream, and a watchdog thread reports a
process that dies (logged, counted in the run summary) and starts it again, after a
back-off and at most ``MAX_RESTARTS`` times; it rejoins from a snapshot. Headless (no window
channels), each writes a video of its channels and, at the end, a panorama PNG. On a
machine with few cores a headless render process gets one rasteriser thread (Mesa
llvmpipe's ``LP_NUM_THREADS``), so the physics keeps its core.
"""
from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import zmq

from bridge_node.common.children import child_env, spawn
from bridge_node.node.config import NodeConfig
from bridge_node.common.errors import UserError
from bridge_node.stream.publisher import StatePublisher
from bridge_node.stream.settings import StreamSettings

log = logging.getLogger("icebridge.render")
WATCH_S = 0.5  # s between the watchdog's looks
RESTART_BACKOFF_S = (1.0, 30.0)  # first delay before a restart, doubling up to the cap
MAX_RESTARTS = 10


@dataclass
class RenderProcess:
    """One render process and what it was started with."""

    group: list[str]
    command: list[str]
    summary: Path
    stderr: Path
    proc: subprocess.Popen | None = None
    restarts: int = 0
    next_start: float = 0.0  # monotonic s: not restarted before
    log: list[str] = field(default_factory=list)


class RenderProcesses:
    """Start, watch and stop the render processes of a run."""

    def __init__(self, cfg: NodeConfig, config_path: str | None, out: Path, frames_every: float | None) -> None:
        channels = cfg.render.channels
        self.headless = not any(c.output == "window" for c in channels)
        fps = cfg.render.headless_fps if self.headless else cfg.render.fps
        self.env = os.environ.copy()
        if self.headless and (os.cpu_count() or 1) <= 4:
            self.env.setdefault("LP_NUM_THREADS", "1")
        self.out = out
        self._stop = threading.Event()
        self._lock = threading.Lock()  # check() runs on the watchdog and may be called directly
        self._watchdog: threading.Thread | None = None
        self.processes = [process for ship in [0, *(k for k, s in enumerate(cfg.ships, 1) if s.render)]
                          for process in _ship_processes(cfg, config_path, out, frames_every, ship, fps,
                                                         self.headless)]

    def _launch(self, p: RenderProcess) -> None:
        with open(p.stderr, "a", encoding="utf-8") as err:
            p.proc = spawn(p.command, env=child_env(self.env), stdout=subprocess.DEVNULL, stderr=err)

    def start(self) -> None:
        """Start every process, and the watchdog thread."""
        for p in self.processes:
            p.summary.parent.mkdir(parents=True, exist_ok=True)
            p.summary.unlink(missing_ok=True)
            p.stderr.unlink(missing_ok=True)
            self._launch(p)
        self._watchdog = threading.Thread(target=self._watch, name="render-watchdog", daemon=True)
        self._watchdog.start()

    def _watch(self) -> None:
        while not self._stop.wait(WATCH_S):
            self.check()

    def check(self) -> None:
        """Restart any process that has died, once its back-off has passed; never waits."""
        with self._lock:
            self._check(time.monotonic())

    def _check(self, now: float) -> None:
        for p in self.processes:
            if p.proc is None or p.proc.poll() is None or now < p.next_start or self._stop.is_set():
                continue
            if not p.next_start:  # just found dead: note it, restart after the back-off
                err = p.stderr.read_text(encoding="utf-8", errors="replace").strip().splitlines()[-2:]
                p.log.append(f"exit {p.proc.returncode}: {' | '.join(err)}")
                if p.restarts >= MAX_RESTARTS:
                    log.error("render process for %s died (exit %s); not restarted again after %d restarts",
                              ",".join(p.group), p.proc.returncode, p.restarts)
                    p.next_start = float("inf")
                    continue
                delay = min(RESTART_BACKOFF_S[0] * 2 ** p.restarts, RESTART_BACKOFF_S[1]) if p.restarts else 0.0
                log.error("render process for %s died (exit %s); restarting in %.0f s", ",".join(p.group),
                          p.proc.returncode, delay)
                p.next_start = now + delay
                if delay:
                    continue
            p.restarts += 1
            p.next_start = 0.0
            self._launch(p)

    def stop(self, timeout: float = 60.0) -> list[dict]:
        """Ask every process to finish (SIGTERM: it closes its video and writes its panorama
        and summary), wait, and return their summaries."""
        self._stop.set()
        if self._watchdog is not None:
            self._watchdog.join()
        for p in self.processes:
            if p.proc is not None and p.proc.poll() is None:
                p.proc.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + timeout
        out = []
        for p in self.processes:
            if p.proc is None:
                continue
            try:
                p.proc.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                p.proc.kill()
                p.proc.wait()
            try:
                summary = json.loads(p.summary.read_text()) if p.summary.exists() else {}
            except (OSError, ValueError):  # a process killed while writing it
                summary = {}
            out.append(summary | {"group": p.group, "restarts": p.restarts, "exit": p.proc.returncode,
                                  "errors": p.log[-3:], "log": str(p.stderr)})
        return out


def _ship_processes(cfg: NodeConfig, config_path: str | None, out: Path, frames_every: float | None, ship: int,
                    fps: float, headless: bool) -> list[RenderProcess]:
    """The render processes of one ship's bridge: one per channel group, from its eyes
    (``render-node --ship``); the first ship's files in ``out``, the k-th's in
    ``out/ship<k>``."""
    groups = cfg.render.groups or [[c.name for c in cfg.render.channels]]
    folder = out if ship == 0 else out / f"ship{ship}"
    processes = []
    for k, group in enumerate(groups):
        tag = "" if len(groups) == 1 else f"_{k + 1}"
        command = [sys.executable, "-m", "bridge_node", "render-node", "--channels", ",".join(group),
                   "--fps", f"{fps:g}", "--out", str(folder), "--wait", "600", "--idle-exit", "60",
                   "--summary", str(folder / f"render{tag}.json"), "--niceness", str(cfg.render.niceness),
                   "--ship", str(ship)]
        if config_path:
            command += ["--config", str(config_path)]
        if frames_every:
            command += ["--frames-every", f"{frames_every:g}"]
        if headless:
            command += ["--video", str(folder / f"video{tag}.mp4"), "--video-fps", f"{fps:g}",
                        "--panorama", str(folder / f"panorama{tag}.png")]
        processes.append(RenderProcess(group, command, folder / f"render{tag}.json", folder / f"render{tag}.log"))
    return processes


def open_stream(settings: StreamSettings) -> StatePublisher:
    """The state stream's publisher, open; UserError if its endpoints cannot be bound."""
    publisher = StatePublisher(settings)
    try:
        publisher.open()
    except zmq.ZMQError as exc:
        raise UserError(f"stream: cannot bind {settings.publish} / {settings.snapshot}: {exc} "
                        "(another node running? set [stream] endpoints)") from None
    return publisher


def wait_for_renderers(renderers: RenderProcesses | None, publisher: StatePublisher, timeout: float) -> None:
    """Before the first step (never during the run): give the render processes time to
    load the exercise and take their first snapshot."""
    if renderers is None:
        return
    deadline = time.monotonic() + timeout
    while publisher.snapshots < len(renderers.processes) and time.monotonic() < deadline:
        time.sleep(0.1)
