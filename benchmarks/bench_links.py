"""Benchmark: the links' per-tick cost and input-to-output latency, on loopback.

Three links at once, as a bridge would wire them: CAN (python-can virtual bus), serial NMEA
0183 over a socat pty pair with its UDP mirror, and Modbus TCP to a pymodbus server on
127.0.0.1 (the console simulator of the tests).
1. Per-tick cost of ``LinkHub.poll`` + ``LinkHub.publish`` (poll all links, arbitrate,
   publish outputs), 60 Hz, without and with the session record.
2. Latency per link: console sends an order -> the link's poll returns it as an order
   -> the node's next output that carries it reaches the instrument side (CAN PGN 127245
   read back on the bus, the NMEA RSA sentence on the pty, the Modbus indicator register).
   The ship state published echoes the order, so the whole path is measured.
Run: .venv/bin/python benchmarks/bench_links.py
"""
from __future__ import annotations

import dataclasses
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import can
import numpy as np
import serial

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from links_helpers import STATE, console_frame, node_config, pty_pair, tick  # noqa: E402
from modbus_console import ModbusConsole  # noqa: E402

from bridge_node.links.hub import LinkHub  # noqa: E402
from bridge_node.links.nmea0183.sentences import ROR  # noqa: E402


def tick_cost(hub: LinkHub, peer: can.BusABC, line: serial.Serial, label: str) -> None:
    """600 ticks at 60 Hz; prints the median and p99 cost of poll + publish, ms."""
    costs = []
    for _ in range(600):
        t0 = time.perf_counter()
        tick(hub, STATE, time.monotonic())
        costs.append(time.perf_counter() - t0)
        while peer.recv(timeout=0.0) is not None:
            pass
        line.read(65536)
        time.sleep(1 / 60)
    ms = np.array(costs) * 1e3
    print(f"hub poll + publish (3 links{label}): median {np.median(ms):.3f} ms, p99 {np.percentile(ms, 99):.3f} ms")


def send_order(name: str, deg: float, k: int, peer, line, modbus) -> None:
    if name == "can":
        peer.send(console_frame("HelmOrder", RudderOrder=deg, Status=1, Counter=k % 255))
    elif name == "nmea":
        line.write((str(ROR("RC", "ROR", (f"{deg:.1f}", "A", "", "V", "B"))) + "\r\n").encode())
    else:
        modbus.set(0, int(deg * 10))


def await_output(name: str, deg: float, link, peer, line, modbus) -> None:
    """Publish a state echoing ``deg`` and wait until the instrument side has it."""
    echo = dataclasses.replace(STATE, rudder_angle=math.radians(deg))
    if name in ("can", "nmea"):
        link._schedule.next_due["rudder" if name == "can" else "RSA"] = 0.0  # due now
    link.publish(echo, time.monotonic())
    if name == "can":
        while (peer.recv(timeout=1.0).arbitration_id >> 8) & 0x3FFFF != 127245:
            pass
    elif name == "nmea":
        buf = b""
        while f"RSA,{deg:.1f}".encode() not in buf:
            buf += line.read(4096)
    else:
        while modbus.get(10) != int(round(deg * 10)):
            time.sleep(0.0002)


def latency(hub: LinkHub, peer, line, modbus) -> None:
    for name in ("can", "nmea", "modbus"):
        link = next(lk for lk in hub.links if lk.name == name)
        order_ms, out_ms = [], []
        for k in range(30):
            deg = 5.0 + k % 20
            t0 = time.perf_counter()
            send_order(name, deg, k, peer, line, modbus)
            while not any(abs(math.degrees(o.value) - deg) < 1e-6 for o in link.poll(time.monotonic())):
                time.sleep(0.0002)  # a spinning poll would starve the Modbus thread of the GIL
            t1 = time.perf_counter()
            await_output(name, deg, link, peer, line, modbus)
            t2 = time.perf_counter()
            order_ms.append((t1 - t0) * 1e3)
            out_ms.append((t2 - t1) * 1e3)
            time.sleep(0.02)
        o, u = np.array(order_ms), np.array(out_ms)
        print(f"{name:6s} latency: console -> order {np.median(o):6.2f} ms (p99 {np.percentile(o, 99):6.2f}), "
              f"order -> instrument {np.median(u):6.2f} ms (p99 {np.percentile(u, 99):6.2f}), "
              f"total {np.median(o + u):6.2f} ms")


def main() -> None:
    print(f"links benchmark, {os.cpu_count()} cores, loopback only")
    with tempfile.TemporaryDirectory() as tmp, pty_pair(Path(tmp)) as (node_end, console_end):
        modbus = ModbusConsole("tcp")
        modbus.start()
        cfg = node_config([
            {"type": "can", "name": "can", "channel": "bench", "allowed_sources": [0x42]},
            {"type": "nmea0183", "name": "nmea", "port": node_end, "baudrate": 115200, "udp_output": True, "udp_port": 10119,
             "rates": {"RSA": 20.0}},
            {"type": "modbus", "name": "modbus", "port": modbus.port, "poll_hz": 50,
             "registers": [{"order": "rudder", "address": 0, "scale": 0.1}],
             "writes": [{"value": "rudder_angle", "address": 10, "scale": 0.1}]},
        ], rudder=["can", "nmea", "modbus"], engine=["can"])
        peer = can.Bus(interface="virtual", channel="bench")
        line = serial.Serial(console_end, 115200, timeout=0)
        for record in (None, Path(tmp) / "record"):
            with LinkHub(cfg.links, cfg.arbitration, record) as hub:
                time.sleep(0.5)
                tick_cost(hub, peer, line, ", recorded" if record else "")
                if record is None:
                    latency(hub, peer, line, modbus)
        line.close()
        peer.shutdown()
        modbus.stop()


if __name__ == "__main__":
    main()
