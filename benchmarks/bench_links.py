"""Benchmark: the links' per-tick cost and input-to-output latency, on loopback.

Three links at once, as a bridge would wire them: CAN (python-can virtual bus), serial NMEA
0183 over a socat pty pair with its UDP mirror, and Modbus TCP to a pymodbus server on
127.0.0.1 (the console simulator of the tests).
1. Per-tick cost of ``LinkHub.tick`` (poll all links, arbitrate, publish outputs), 60 Hz.
2. Latency per link: console sends an order -> the node's tick returns it as an order
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
from links_helpers import node_config, pty_pair  # noqa: E402
from modbus_console import ModbusConsole  # noqa: E402
from test_links_can import STATE, console_frame  # noqa: E402

from bridge_node.link_hub import LinkHub  # noqa: E402
from bridge_node.links.nmea0183 import ROR  # noqa: E402


def main() -> None:
    print(f"links benchmark, {os.cpu_count()} cores, loopback only")
    with tempfile.TemporaryDirectory() as tmp, pty_pair(Path(tmp)) as (node_end, console_end):
        modbus = ModbusConsole("tcp")
        modbus.start()
        cfg = node_config([
            {"type": "can", "name": "can", "channel": "bench"},
            {"type": "nmea0183", "name": "nmea", "port": node_end, "baudrate": 115200, "udp_port": 10119,
             "rates": {"RSA": 20.0}},
            {"type": "modbus", "name": "modbus", "port": modbus.port, "poll_hz": 50,
             "registers": [{"order": "rudder", "address": 0, "scale": 0.1}],
             "writes": [{"value": "rudder_angle", "address": 10, "scale": 0.1}]},
        ], rudder=["can", "nmea", "modbus"], engine=["can"])
        hub = LinkHub(cfg, None)
        hub.open()
        peer = can.Bus(interface="virtual", channel="bench")
        line = serial.Serial(console_end, 115200, timeout=0)
        time.sleep(0.5)
        # 1. per-tick cost at 60 Hz
        costs = []
        for _ in range(600):
            t0 = time.perf_counter()
            hub.tick(STATE, time.monotonic())
            costs.append(time.perf_counter() - t0)
            while peer.recv(timeout=0.0) is not None:
                pass
            line.read(65536)
            time.sleep(1 / 60)
        ms = np.array(costs) * 1e3
        print(f"hub tick (3 links: poll, arbitrate, publish): median {np.median(ms):.3f} ms, "
              f"p99 {np.percentile(ms, 99):.3f} ms")
        # 2. latency: order in -> order out of tick -> output carrying it at the instrument
        results = {}
        for name in ("can", "nmea", "modbus"):
            order_ms, out_ms = [], []
            for k in range(30):
                deg = 5.0 + k % 20
                t0 = time.perf_counter()
                if name == "can":
                    peer.send(console_frame("HelmOrder", RudderOrder=deg, Status=1, Counter=k % 255))
                elif name == "nmea":
                    line.write((str(ROR("RC", "ROR", (f"{deg:.1f}", "A", "", "V", "B"))) + "\r\n").encode())
                else:
                    modbus.set(0, int(deg * 10))
                while True:
                    got = [o for link in hub.links if link.name == name for o in link.poll(time.monotonic())]
                    if got and abs(math.degrees(got[-1].value) - deg) < 1e-6:
                        break
                    time.sleep(0.0002)  # a spinning poll would starve the Modbus thread of the GIL
                t1 = time.perf_counter()
                echo = dataclasses.replace(STATE, rudder_angle=math.radians(deg))
                link = next(lk for lk in hub.links if lk.name == name)
                if name == "can":
                    link._schedule.next_due["rudder"] = 0.0  # due now
                    link.publish(echo, time.monotonic())
                    while True:
                        msg = peer.recv(timeout=1.0)
                        if (msg.arbitration_id >> 8) & 0x3FFFF == 127245:
                            break
                elif name == "nmea":
                    link._schedule.next_due["RSA"] = 0.0
                    link.publish(echo, time.monotonic())
                    buf = b""
                    while f"RSA,{deg:.1f}".encode() not in buf:
                        buf += line.read(4096)
                else:
                    link.publish(echo, time.monotonic())
                    while modbus.get(10) != int(round(deg * 10)):
                        time.sleep(0.0002)
                t2 = time.perf_counter()
                order_ms.append((t1 - t0) * 1e3)
                out_ms.append((t2 - t1) * 1e3)
                time.sleep(0.02)
            results[name] = (np.array(order_ms), np.array(out_ms))
        for name, (o, u) in results.items():
            print(f"{name:6s} latency: console -> order {np.median(o):6.2f} ms (p99 {np.percentile(o, 99):6.2f}), "
                  f"order -> instrument {np.median(u):6.2f} ms (p99 {np.percentile(u, 99):6.2f}), "
                  f"total {np.median(o + u):6.2f} ms")
        line.close()
        peer.shutdown()
        hub.close()
        modbus.stop()


if __name__ == "__main__":
    main()
