"""Modbus link (pymodbus 3.x): the node polls the console's I/O registers as a TCP client or
RTU master, and optionally writes indicator values (rudder angle, RPM) back.

A Modbus request blocks until the reply or the timeout, so the polling runs in its own
thread and hands orders to the real-time loop through a queue; ``poll`` never blocks. A
failed request drops the connection, and the thread reconnects with back-off (capped at
1 s), so a console that comes back is in use again within about a second.
"""
from __future__ import annotations

import logging
import math
import queue
import threading
import time

from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.exceptions import ModbusException

from bridge_node.links.base import LEVER, RUDDER, TELEGRAPH, ControlInput, Link
from bridge_node.links.link_settings import ModbusLinkSettings, RegisterSpec, WriteSpec
from bridge_node.links.nmea0183 import ETL_POSITIONS, RUDDER_ORDER_LIMIT_DEG
from bridge_node.links.reconnect import Backoff
from bridge_node.links.session_record import SessionRecord
from sim_core.manoeuvring_trials import KNOT
from sim_core.ship_outputs import ShipOutputs

# the link counts and reports its own errors; pymodbus would also print every refused
# connection and, at some levels, every frame
logging.getLogger("pymodbus").setLevel(logging.CRITICAL)


def register_value(raw: int, kind: str) -> int:
    """A 16-bit register as a signed (int16) or unsigned (uint16) integer."""
    return raw - 0x10000 if kind == "int16" and raw >= 0x8000 else raw


def raw_register(value: float, kind: str) -> int:
    """An integer for a 16-bit register, saturated to the type's range."""
    lo, hi = (-0x8000, 0x7FFF) if kind == "int16" else (0, 0xFFFF)
    v = int(round(min(max(value, lo), hi)))
    return v & 0xFFFF


def register_order(spec: RegisterSpec, raw: int, now: float, source: str) -> ControlInput | str:
    """The order a register holds, or the error kind if it is not a valid order."""
    value = register_value(raw, spec.type) * spec.scale
    if not math.isfinite(value):
        return "bad_field"
    if spec.order == "rudder":
        if abs(value) > RUDDER_ORDER_LIMIT_DEG:
            return "out_of_range"
        return ControlInput(now, source, RUDDER, math.radians(value), spec.engine)
    if spec.order == "lever":
        if abs(value) > 100.0:
            return "out_of_range"
        return ControlInput(now, source, LEVER, float(value), spec.engine)
    code = f"{int(round(value)):02d}"
    if code not in ETL_POSITIONS:
        return "out_of_range"
    return ControlInput(now, source, TELEGRAPH, ETL_POSITIONS[code], spec.engine)


def indicator_value(spec: WriteSpec, s: ShipOutputs) -> float:
    """Engineering value of an indicator: rudder angle deg, shaft rpm, heading deg, speed kn."""
    return {"rudder_angle": math.degrees(s.rudder_angle), "shaft_rpm": s.shaft_rps * 60.0,
            "heading": math.degrees(s.heading), "speed": s.speed_longitudinal / KNOT}[spec.value]


class ModbusLink(Link):
    """Polls the configured registers in a worker thread."""

    def __init__(self, settings: ModbusLinkSettings, record: SessionRecord | None = None) -> None:
        super().__init__(settings.name)
        self.settings = settings
        self.record = record
        self._inputs: queue.SimpleQueue = queue.SimpleQueue()
        self._indicators: dict[int, int] = {}  # address -> raw, latest values to write
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._client = None

    def _new_client(self):
        s = self.settings
        if s.transport == "tcp":
            return ModbusTcpClient(s.host, port=s.port, timeout=s.request_timeout_s, retries=0,
                                   reconnect_delay=0.0)
        return ModbusSerialClient(s.serial_port, baudrate=s.baudrate, timeout=s.request_timeout_s, retries=0,
                                  reconnect_delay=0.0)

    def open(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=f"modbus-{self.name}", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        period = 1.0 / self.settings.poll_hz
        backoff = Backoff(first=0.1, cap=1.0)
        next_poll = time.monotonic()
        answered_before = False
        while not self._stop.is_set():
            now = time.monotonic()
            if self._client is None:
                if backoff.ready(now):
                    client = self._new_client()
                    if client.connect():
                        self._client = client
                    else:
                        client.close()
                        self._count_error("connect_failed")
                        backoff.failed(now)
                self._stop.wait(0.02)
                continue
            try:
                orders = self._poll_once()
                self._write_indicators()
            except (ModbusException, OSError, ValueError) as exc:
                self._count_error("request_failed" if not isinstance(exc, ValueError) else "bad_reply")
                self._client.close()
                self._client = None
                self._health.connected = False
                backoff.failed(time.monotonic())
                continue
            if not self._health.connected:  # connected means the console answers, not a port is open
                self._health.connected = True
                self._health.reconnects += answered_before
                answered_before = True
                backoff.succeeded()
            for order in orders:
                self._inputs.put(order)
            next_poll = max(next_poll + period, time.monotonic())
            self._stop.wait(max(0.0, next_poll - time.monotonic()))
        if self._client is not None:
            self._client.close()
            self._client = None

    def _read(self, table: str, start: int, count: int) -> list[int]:
        c, dev = self._client, self.settings.device_id
        reply = (c.read_holding_registers(start, count=count, device_id=dev) if table == "holding"
                 else c.read_input_registers(start, count=count, device_id=dev))
        if reply.isError():
            raise ModbusException(f"exception reply {reply}")
        if len(reply.registers) != count:
            raise ValueError("short reply")
        return reply.registers

    def _poll_once(self) -> list[ControlInput]:
        """Read every configured register once; the orders they hold."""
        now = time.monotonic()
        out = []
        for table in ("holding", "input"):
            specs = [r for r in self.settings.registers if r.table == table]
            if not specs:
                continue
            start = min(r.address for r in specs)
            regs = self._read(table, start, max(r.address for r in specs) - start + 1)
            for spec in specs:
                raw = regs[spec.address - start]
                order = register_order(spec, raw, now, self.name)
                if isinstance(order, str):
                    self._count_error(order)
                else:
                    out.append(order)
                if self.record:
                    self.record.modbus(self.name, "read", table, spec.address, raw,
                                       register_value(raw, spec.type) * spec.scale)
        return out

    def _write_indicators(self) -> None:
        with self._lock:
            pending, self._indicators = self._indicators, {}
        for address, raw in pending.items():
            reply = self._client.write_register(address, raw, device_id=self.settings.device_id)
            if reply.isError():
                raise ModbusException(f"exception reply {reply}")
            self._health.outputs += 1
            if self.record:
                self.record.modbus(self.name, "write", "holding", address, raw, float("nan"))

    def poll(self, now: float) -> list[ControlInput]:
        out = []
        while True:
            try:
                out.append(self._inputs.get_nowait())
            except queue.Empty:
                break
        if out:
            self._health.inputs += len(out)
            self._health.last_input = out[-1].time
        return out

    def publish(self, state: ShipOutputs, now: float) -> None:
        if not self.settings.writes:
            return
        values = {w.address: raw_register(indicator_value(w, state) / w.scale, w.type) for w in self.settings.writes}
        with self._lock:
            self._indicators.update(values)

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        self._health.connected = False
