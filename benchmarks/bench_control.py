"""Benchmark: the instructor's command to its effect, and what the control endpoint costs the
physics loop.

The default exercise runs at 60 Hz with its bow in the ice (no links, no render processes).
A client thread sends 200 commands (visibility changes) to the control endpoint at random
moments, over ZeroMQ on the loopback; a listener notes the end of the tick whose step
applied each one. Command to effect = that tick's end - the moment the command was sent,
in ms and in tick periods (median, p99, max). Then the same loop runs again while a client
floods the endpoint (as fast as it answers): the tick p99 against the quiet run's, a
same-run ratio. Prints the core count beside every figure.

Run: .venv/bin/python benchmarks/bench_control.py [--commands N] [--seconds S]
"""
from __future__ import annotations

import argparse
import json
import os
import random
import threading
import time

import numpy as np
import zmq

from bridge_node.control.endpoint import ControlEndpoint
from bridge_node.control.queue import CommandQueue
from bridge_node.control.settings import ControlSettings
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import load_config
from bridge_node.common.network import free_port
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import build_world, start_world, warm_up

RATE = 60.0


def _exercise():
    cfg = load_config()
    cfg = cfg.model_copy(update={"links": [], "exercise": cfg.exercise.model_copy(update={"start_north": -60.0})})
    model = build_world(cfg, None)
    warm_up(model, cfg)
    return cfg, model


def _sender(address: str, count: int, sent: dict, done: threading.Event) -> None:
    """Send ``count`` commands at random moments (20-80 ms apart), noting when each left."""
    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.connect(address)
    time.sleep(0.5)
    for k in range(count):
        visibility = 1000.0 + k  # each command's value names it
        sent[visibility] = time.monotonic()
        sock.send(json.dumps({"command": {"command": "visibility", "visibility_m": visibility}}).encode())
        sock.recv()
        time.sleep(random.uniform(0.02, 0.08))
    sock.close()
    done.set()


def _flooder(address: str, stop: threading.Event) -> None:
    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.connect(address)
    message = json.dumps({"command": {"command": "freeze", "junk": 1}}).encode()
    while not stop.is_set():
        sock.send(message)
        sock.recv()
    sock.close()


def _run(cfg, model, seconds: float | None, client) -> tuple[dict, list]:
    """The loop with the control endpoint and one client; returns the loop's summary and
    (applied visibility, tick end) pairs."""
    data = start_world(model, cfg)
    queue = CommandQueue(cfg.control.queue, cfg.control.per_tick)
    settings = ControlSettings(endpoint=f"tcp://127.0.0.1:{free_port()}")
    applied, stop = [], threading.Event()

    def note(outcome) -> None:
        for c in outcome.events.commands:
            applied.append((dict(c.changes)["visibility"], time.monotonic()))

    with ControlEndpoint(settings, queue, dict), LinkHub([], cfg.arbitration) as hub:
        thread = threading.Thread(target=client, args=(settings.endpoint, stop), daemon=True)
        thread.start()
        stats = run_realtime(model, data, hub, RATE, seconds, [note], should_stop=stop.is_set, commands=queue)
        stop.set()
        thread.join(10.0)
    return stats.summary(), applied


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--commands", type=int, default=200)
    p.add_argument("--seconds", type=float, default=20.0)
    args = p.parse_args()
    cores = os.cpu_count()
    cfg, model = _exercise()
    sent: dict = {}
    quiet, applied = _run(cfg, model, None, lambda address, stop: _sender(address, args.commands, sent, stop))
    delays = np.array([(t - sent[v]) * 1e3 for v, t in applied])
    period_ms = 1e3 / RATE
    print(f"command to effect, {len(delays)} commands, {cores} cores, {RATE:.0f} Hz (period {period_ms:.1f} ms):")
    for name, value in (("median", np.median(delays)), ("p99", np.percentile(delays, 99)), ("max", delays.max())):
        print(f"  {name:6s} {value:7.1f} ms = {value / period_ms:4.2f} periods")
    flooded, _ = _run(cfg, model, args.seconds, _flooder)
    base, _ = _run(cfg, model, args.seconds, lambda address, stop: stop.wait())
    print(f"tick p99 over {args.seconds:g} s, {cores} cores: quiet {base['tick_ms_p99']} ms, flooded "
          f"{flooded['tick_ms_p99']} ms (ratio {flooded['tick_ms_p99'] / base['tick_ms_p99']:.2f}); overruns "
          f"{base['overruns']} / {flooded['overruns']}")


if __name__ == "__main__":
    main()
