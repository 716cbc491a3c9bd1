"""Benchmark: what the instructor station costs the main job, and its map's redraw rate.

1. The 60 Hz main job: ``icebridge run --rate 60`` on the default configuration
   (config/default.toml, with its software console and instruments link, on free loopback
   ports and its own session folder; render processes as --render says, none by default:
   bench_pipeline measures theirs) for --seconds, first without the instructor station,
   then with it (``[instructor] start = true``) and headless Chromium showing its map. Tick
   p99 of each from the run's own summary, and their same-run ratio (target: at most 1.10).
2. The map's redraw rate in headless Chromium with 10 000 live floes: this process publishes
   bench_render's world with a broken channel of 10 000 free floes, stepped at 30 Hz,
   ``icebridge instructor`` follows the stream, and the page redraws its map on every
   animation frame, as while the instructor pans. Draws and stream frames a second are
   counted in the page (its own counters), first with the floes at rest (the baseline: the
   floes' paths are kept), then drifting on a 1 kn current (every floe's path made anew with
   each frame, about ten a second). Target: 10 draws a second or more.
The core count is printed beside every figure.

Run: .venv/bin/python benchmarks/bench_station.py [--seconds S] [--render none|local] [--part 1|2]
[--browser-niceness N] (Chromium as ``nice -n N`` would start it, as the instructor guide advises for a
browser on the node's PC)
"""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Self

sys.path.insert(0, str(Path(__file__).resolve().parent))
import psutil
from bench_render import world_with_floes

from bridge_node.node.config import DEFAULT_CONFIG
from bridge_node.common.network import free_port
from bridge_node.station.harness import (
    chromium,
    http,
    open_page,
    start,
    stop,
    wait_until,
)
from bridge_node.stream.publisher import StatePublisher
from bridge_node.stream.settings import StreamSettings
from sim_core.frames.units import KNOT
from sim_core.world import snapshot, step

CORES = os.cpu_count()
FLOES = 10_000
PHYSICS_HZ = 30.0  # the floe world's steps a second (part 2)


def default_config(folder: Path, station: bool) -> tuple[Path, str, str]:
    """config/default.toml on free loopback ports with its own session folder, the station
    started by the run or not; the file, its stream's publish endpoint and the page's URL."""
    text, port = DEFAULT_CONFIG.read_text(), free_port()
    publish = f"tcp://127.0.0.1:{free_port()}"
    for old, new in (("tcp://127.0.0.1:5560", publish), ("tcp://127.0.0.1:5561", f"tcp://127.0.0.1:{free_port()}"),
                     ("tcp://127.0.0.1:5562", f"tcp://127.0.0.1:{free_port()}"), ("port = 8470", f"port = {port}"),
                     ("udp_port = 10110", f"udp_port = {free_port()}"), ("start = true", f"start = {str(station).lower()}"),
                     ('session_dir = "~/.cache/icebridge/sessions"', f'session_dir = "{folder / "sessions"}"')):
        if old not in text:
            raise SystemExit(f"config/default.toml no longer holds {old!r}: update this benchmark")
        text = text.replace(old, new)
    path = folder / f"default-{'station' if station else 'alone'}.toml"
    path.write_text(text)
    return path, publish, f"http://127.0.0.1:{port}/"


class Progress:
    """Waits for a process, saying every ``every_s`` how long it has run."""

    def __init__(self, proc: subprocess.Popen, what: str, every_s: float = 15.0) -> None:
        self.proc, self.what, self.every_s = proc, what, every_s
        self.started, self.said = time.monotonic(), 0.0

    def wait(self, once: bool = False) -> None:
        """Until the process ends (``once``: half a second at most)."""
        while self.proc.poll() is None:
            time.sleep(0.5)
            if time.monotonic() - self.started >= self.said + self.every_s:
                self.said += self.every_s
                print(f"  {self.what}: {self.said:.0f} s", flush=True)
            if once:
                return


def cpu_seconds(roots: list[int]) -> dict[int, float]:
    """User and system CPU seconds of each process of the trees under ``roots``, by pid."""
    out = {}
    for root in roots:
        with contextlib.suppress(psutil.NoSuchProcess):
            for p in [psutil.Process(root), *psutil.Process(root).children(recursive=True)]:
                with contextlib.suppress(psutil.NoSuchProcess):
                    out[p.pid] = sum(p.cpu_times()[:2])
    return out


def shown_map(proc: subprocess.Popen, progress: Progress, url: str, browser_niceness: int) -> dict:
    """Chromium showing the station's map until the run ends, at ``browser_niceness``: the
    page's frames, and the share of one core the station's process and Chromium's took over
    the run's rest."""
    with chromium() as browser:
        wait_until(lambda: proc.poll() is None and http(url)[0] == 200, 300, "the station's page")
        open_page(browser, url, floes=0)  # the default exercise's ship reaches the ice later
        driver = psutil.Process(browser.service.process.pid)
        for p in [driver, *driver.children(recursive=True)]:  # as `nice -n N chromium` would start it
            with contextlib.suppress(psutil.NoSuchProcess):
                p.nice(browser_niceness)
        print(f"  the map is shown in Chromium (niceness {browser_niceness}) at {url}", flush=True)
        station = next(p.pid for p in psutil.Process(proc.pid).children() if "instructor" in p.cmdline())
        roots = {"station": [station], "Chromium": [browser.service.process.pid]}
        started, before = time.monotonic(), {name: cpu_seconds(pids) for name, pids in roots.items()}
        last, wall = before, math.nan
        while proc.poll() is None:  # a look every 5 s: the last before the run ends counts
            for _ in range(10):
                progress.wait(once=True)
            if proc.poll() is None:
                last, wall = {name: cpu_seconds(pids) for name, pids in roots.items()}, time.monotonic() - started
        return {"page_frames": browser.execute_script("return window.stationStats.frames"),
                "cpu": {name: sum(last[name].get(pid, t) - t for pid, t in before[name].items()) / wall * 100.0
                        for name in roots}}


def main_job(folder: Path, seconds: float, render: str, station: bool, browser_niceness: int) -> dict:
    """One ``icebridge run --rate 60`` of the default configuration; its JSON summary, with
    what ``shown_map`` says where Chromium showed the map."""
    config, _, url = default_config(folder, station)
    name = "station" if station else "alone"
    with open(folder / f"run-{name}.json", "w") as summary, open(folder / f"run-{name}.log", "w") as err:
        proc = subprocess.Popen([sys.executable, "-m", "bridge_node", "run", "--config", str(config), "--rate", "60",
                                 "--duration", f"{seconds:g}", "--json", "--out", str(folder / f"out-{name}"),
                                 "--render", render], stdout=summary, stderr=err)
    progress = Progress(proc, "with the station and Chromium" if station else "without the station")
    try:
        shown = shown_map(proc, progress, url, browser_niceness) if station else {}
        progress.wait()
    finally:
        stop(proc)
    if proc.returncode != 0:
        raise SystemExit(f"icebridge run ended with {proc.returncode}: see {folder / f'run-{name}.log'}")
    return json.loads((folder / f"run-{name}.json").read_text()) | shown


def part_main_job(seconds: float, render: str, repeats: int, browser_niceness: int) -> None:
    print(f"1. the 60 Hz main job, default configuration, render processes: {render}, {seconds:g} s a run, "
          f"{repeats} runs each way, alternating, {CORES} cores", flush=True)
    p99: dict[bool, list[float]] = {False: [], True: []}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(repeats):
            for station in (False, True):
                s = main_job(Path(tmp), seconds, render, station, browser_niceness)
                p99[station].append(s["tick_ms_p99"])
                shown = (f", {s['page_frames']} map frames in the page; CPU (% of a core) station "
                         f"{s['cpu']['station']:.0f}, Chromium {s['cpu']['Chromium']:.0f}") if station else ""
                print(f"  run {k + 1}/{repeats} {'with' if station else 'without'} the station: tick median "
                      f"{s['tick_ms_median']} ms, p99 {s['tick_ms_p99']} ms, max {s['tick_ms_max']} ms, overruns "
                      f"{s['overruns']}/{s['ticks']}{shown} ({CORES} cores)", flush=True)
    alone, shown = statistics.median(p99[False]), statistics.median(p99[True])
    print(f"  tick p99, median of the runs: without {alone:.2f} ms, with the station {shown:.2f} ms; ratio "
          f"{shown / alone:.3f} (target <= 1.10; {CORES} cores)", flush=True)


class FloePublisher:
    """Publishes a world of ``FLOES`` free floes stepped at ``PHYSICS_HZ`` in a thread; the
    current (m/s) can be changed while it runs."""

    def __init__(self, settings: StreamSettings) -> None:
        self.model, self.data, _ = world_with_floes(FLOES)
        self.settings, self.current, self.steps = settings, 0.0, 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="floe-publisher", daemon=True)

    def __enter__(self) -> Self:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(10.0)

    def _run(self) -> None:
        with StatePublisher(self.settings) as pub:
            pub.publish(snapshot(self.model, self.data))
            next_step = time.monotonic()
            while not self._stop.is_set():
                self.data.environment = dataclasses.replace(self.data.environment, current_speed=self.current,
                                                            current_to=math.pi / 2)
                pub.publish(step(self.model, self.data, 1.0 / PHYSICS_HZ), time.monotonic())
                self.steps += 1
                next_step += 1.0 / PHYSICS_HZ
                self._stop.wait(max(0.0, next_step - time.monotonic()))


SPIN = ("window.benchSpin = true; (function spin() { if (!window.benchSpin) return; map.dirty = true; "
        "requestAnimationFrame(spin); })();")
COUNTS = "const s = window.stationStats; return [performance.now(), s.draws, s.frames, s.floes, s.drawMs, s.applyMs];"


def page_rates(browser, seconds: float) -> dict:
    """Draws and frames a second in the page over ``seconds``, with the floes shown and the
    last draw's and frame's ms."""
    t0, draws0, frames0, *_ = browser.execute_script(COUNTS)
    time.sleep(seconds)
    t1, draws1, frames1, floes, draw_ms, apply_ms = browser.execute_script(COUNTS)
    dt = (t1 - t0) / 1e3
    return {"draws_s": (draws1 - draws0) / dt, "frames_s": (frames1 - frames0) / dt, "floes": floes,
            "draw_ms": draw_ms, "apply_ms": apply_ms}


def measure_view(browser, world: FloePublisher, view: str, seconds: float) -> dict:
    """Draws a second with the floes at rest, then drifting, in one view of the map; printed."""
    browser.execute_script(view)
    rates = {}
    for name, current_kn in (("at rest", 0.0), ("drifting", 1.0)):
        world.current = current_kn * KNOT
        time.sleep(2.0)  # the current's frames reach the page
        rates[name] = r = page_rates(browser, seconds)
        print(f"    floes {name}: {r['draws_s']:.1f} draws/s, {r['frames_s']:.1f} stream frames/s applied, "
              f"{r['floes']} floes in the page, last draw {r['draw_ms']:.0f} ms, last frame applied "
              f"{r['apply_ms']:.0f} ms; physics {world.steps} steps so far ({CORES} cores)", flush=True)
    return rates


def part_map(seconds: float) -> None:
    print(f"2. the map in headless Chromium with {FLOES} live floes, redrawn on every animation frame, "
          f"{CORES} cores", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        config, publish, url = default_config(folder, False)
        snapshot_endpoint = next(line.split('"')[1] for line in config.read_text().splitlines()
                                 if line.startswith("snapshot"))
        with FloePublisher(StreamSettings(publish=publish, snapshot=snapshot_endpoint)) as world:
            station = start(folder, "station", "instructor", "--config", str(config))
            views = {"the whole field": "map.fitField();",
                     "2 px/m on the broken channel, floe outlines drawn": "map.setFollow(false); map.scale = 2; "
                     f"map.cx = {world.data.ship.eta[1]:.1f}; map.cy = 200;"}
            try:
                wait_until(lambda: station.poll() is None and http(url)[0] == 200, 300, "the station's page")
                with chromium() as browser:
                    open_page(browser, url, floes=int(0.9 * FLOES), timeout=300)
                    browser.execute_script(SPIN)
                    for name, view in views.items():
                        print(f"  {name}:", flush=True)
                        rest, drift = measure_view(browser, world, view, seconds).values()
                        print(f"    draws/s drifting / at rest: {drift['draws_s'] / rest['draws_s']:.2f}; drifting "
                              f"{drift['draws_s']:.1f} draws/s (target >= 10; {CORES} cores)", flush=True)
            finally:
                stop(station)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="length of each main-job run, s (part 1)")
    ap.add_argument("--map-seconds", type=float, default=15.0, help="each measurement of the map, s (part 2)")
    ap.add_argument("--render", choices=("none", "local"), default="none", help="render processes in part 1")
    ap.add_argument("--repeats", type=int, default=2, help="runs without and with the station, alternating (part 1)")
    ap.add_argument("--part", choices=("1", "2", "all"), default="all")
    ap.add_argument("--browser-niceness", type=int, default=0, choices=range(20), metavar="0..19",
                    help="Chromium's niceness in part 1 (the station's own is [instructor] niceness)")
    args = ap.parse_args()
    print(f"instructor station benchmark, {CORES} cores", flush=True)
    if args.part in ("1", "all"):
        part_main_job(args.seconds, args.render, args.repeats, args.browser_niceness)
    if args.part in ("2", "all"):
        part_map(args.map_seconds)


if __name__ == "__main__":
    main()
