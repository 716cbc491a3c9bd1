"""Benchmark: the state stream and the render processes (loopback, separate processes).

1. Stream bandwidth and delay (publish -> subscriber applied, median and p99) at 60 Hz with
   3000 and 10 000 live floes, with one and three subscriber processes.
2. The physics loop at 30 Hz on the default exercise (bow in the ice, a helm console on
   virtual CAN changing its order every 0.5 s, engine full ahead) for --seconds, without render processes
   (the baseline, same run) and with three: tick median, p99 and max, overruns, and the
   transport delays input -> outputs and input -> pixels.
Run: .venv/bin/python benchmarks/bench_pipeline.py [--seconds S]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import can
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from bench_render import world_with_floes  # noqa: E402
from conftest import free_port  # noqa: E402
from links_helpers import console_frame  # noqa: E402

from bridge_node.exercise.listeners import StreamOutput  # noqa: E402
from bridge_node.links.hub import LinkHub  # noqa: E402
from bridge_node.node.config import load_config  # noqa: E402
from bridge_node.node.realtime_loop import run_realtime  # noqa: E402
from bridge_node.node.render_processes import RenderProcesses  # noqa: E402
from bridge_node.node.world_setup import build_world, start_world, warm_up  # noqa: E402
from bridge_node.stream.codec import encode  # noqa: E402
from bridge_node.stream.publisher import StatePublisher  # noqa: E402
from bridge_node.stream.settings import StreamSettings  # noqa: E402
from bridge_node.stream.subscriber import StateSubscriber  # noqa: E402
from sim_core.world import snapshot, step  # noqa: E402


def subscriber(publish: str, snapshot_endpoint: str, seconds: float) -> None:
    """Subscriber process: apply the stream for ``seconds``; print the delays (ms)."""
    delays = []
    with StateSubscriber(publish, snapshot_endpoint, timeout_s=60.0) as sub:
        sub.sync()
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            for events in sub.poll(50):
                if sub.last_input and sub.last_input[0] == events.seq:
                    delays.append((time.monotonic() - sub.last_input[1]) * 1e3)
        print(json.dumps({"delays_ms": delays, "resyncs": sub.resyncs}))


def stream_figures(target: int, subscribers: int, seconds: float = 8.0) -> dict:
    model, data, _ = world_with_floes(target)
    settings = StreamSettings(publish=f"tcp://127.0.0.1:{free_port()}", snapshot=f"tcp://127.0.0.1:{free_port()}")
    with StatePublisher(settings) as pub:
        pub.publish(snapshot(model, data))
        procs = [subprocess.Popen([sys.executable, __file__, "--subscriber", settings.publish, settings.snapshot,
                                   str(seconds)], stdout=subprocess.PIPE, text=True) for _ in range(subscribers)]
        while pub.snapshots < subscribers:
            time.sleep(0.05)
        sizes, t0 = [], time.monotonic()
        for k in range(int(seconds * 60)):
            events = step(model, data, 1 / 60)
            sizes.append(sum(len(f) for f in encode(events)))
            pub.publish(events, time.monotonic())
            time.sleep(max(0.0, t0 + (k + 1) / 60 - time.monotonic()))
        out = [json.loads(p.communicate()[0]) for p in procs]
    delays = np.concatenate([o["delays_ms"] for o in out])
    return {"floes": target, "subscribers": subscribers, "MB_s": np.mean(sizes) * 60 / 1e6,
            "median_ms": float(np.median(delays)), "p99_ms": float(np.percentile(delays, 99)),
            "resyncs": sum(o["resyncs"] for o in out)}


def can_link():
    """The helm console's link: python-can's virtual bus, shared with this process's console."""
    from pydantic import TypeAdapter

    from bridge_node.links.registry import LinkSettings
    return TypeAdapter(LinkSettings).validate_python({"type": "can", "name": "helm", "channel": "bench-pipeline",
                                                      "allowed_sources": [0x42]})


def physics_run(seconds: float, renderers: int, folder: Path) -> dict:
    """The default exercise at 30 Hz, bow in the ice, a helm console on virtual CAN."""
    names = [c.name for c in load_config().render.channels]
    groups = [names[:1], names[1:2], names[2:]][:renderers]
    config = folder / f"bench_{renderers}.toml"
    config.write_text(  # the default exercise, bow in the ice; what render processes need to know
        '[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n[exercise]\nstart_north = -60.0\n'
        f'[stream]\npublish = "tcp://127.0.0.1:{free_port()}"\nsnapshot = "tcp://127.0.0.1:{free_port()}"\n'
        + (f"[render]\ngroups = {json.dumps(groups)}\n" if renderers else ""))
    cfg = load_config(config)
    cfg = cfg.model_copy(update={"links": [can_link()], "arbitration": cfg.arbitration.model_copy(
        update={"rudder": ["helm"], "engine": ["helm"]})})
    model = build_world(cfg, str(config))
    warm_up(model, cfg)
    data = start_world(model, cfg)
    procs = RenderProcesses(cfg, str(config), folder / f"r{renderers}", None) if renderers else None
    console, stop = can.Bus(interface="virtual", channel="bench-pipeline"), threading.Event()

    def helm() -> None:
        k = 0
        while not stop.is_set():
            console.send(console_frame("HelmOrder", RudderOrder=10.0 * (k % 2), Status=1, Counter=k % 16))
            console.send(console_frame("EngineOrder", Engine=0, Lever=0, TelegraphPosition=4, Mode=1))
            k += 1
            stop.wait(0.5)
    with StatePublisher(cfg.stream) as pub, LinkHub(cfg.links, cfg.arbitration) as hub:
        pub.publish(snapshot(model, data))
        if procs:
            procs.start()
            while pub.snapshots < renderers:
                time.sleep(0.1)
        sender = threading.Thread(target=helm, daemon=True)
        sender.start()
        stats = run_realtime(model, data, hub, 30.0, seconds, [StreamOutput(pub, None, model.origin)])
        stop.set()
        sender.join()
        rendered = procs.stop() if procs else []
    console.shutdown()
    s = stats.summary()
    pixels = [r["input_to_pixels_ms"] for r in rendered]
    return {"renderers": renderers, "tick_median": s["tick_ms_median"], "tick_p99": s["tick_ms_p99"],
            "tick_max": s["tick_ms_max"], "overruns": stats.overruns, "ticks": stats.ticks,
            "outputs_ms": s["input_to_outputs_ms"], "pixels_ms": pixels,
            "frames": [r.get("frames") for r in rendered]}


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--subscriber":
        subscriber(sys.argv[2], sys.argv[3], float(sys.argv[4]))
        return
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=30.0, help="physics run length, s")
    args = ap.parse_args()
    print(f"pipeline benchmark, {os.cpu_count()} cores, loopback")
    for target in (3000, 10000):
        for n in (1, 3):
            f = stream_figures(target, n)
            print(f"stream, {f['floes']:5d} live floes, {n} subscriber(s): {f['MB_s']:5.1f} MB/s at 60 Hz, "
                  f"delay median {f['median_ms']:5.2f} ms, p99 {f['p99_ms']:6.2f} ms, resyncs {f['resyncs']}")
    with tempfile.TemporaryDirectory() as tmp:
        for renderers in (0, 3):
            r = physics_run(args.seconds, renderers, Path(tmp))
            print(f"physics 30 Hz, {r['renderers']} render processes: tick median {r['tick_median']} ms, "
                  f"p99 {r['tick_p99']} ms, max {r['tick_max']} ms, overruns {r['overruns']}/{r['ticks']}; "
                  f"input->outputs {r['outputs_ms']}; input->pixels {r['pixels_ms']}; frames {r['frames']}")


if __name__ == "__main__":
    main()
