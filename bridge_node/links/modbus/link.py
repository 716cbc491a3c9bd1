"""Modbus link (pymodbus 3.x): the node polls the console's I/O registers as a TCP client or
RTU master, and optionally writes indicator values (rudder angle, RPM) back.

A Modbus request blocks until the reply or the timeout, so the polling runs in a worker
thread (the link's device). The worker shares nothing mutable with the loop but two
hand-overs: everything it learns (orders, errors, register traffic, console up or down)
goes to the loop through a queue, which ``poll`` drains on the loop's thread, so health and
errors change only there; the indicator values to write come the other way under a lock.
A failed request (a malformed reply among them) drops the connection, and the worker
reconnects with back-off (capped at 1 s), so a console that comes back is in use again
within about a second; the orders of a good poll are kept even if an indicator write after
it fails. A worker that
dies is restarted by ``Link.poll`` like any lost device.
"""
from __future__ import annotations

import logging
import math
import queue
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.exceptions import ModbusException

from bridge_node.links.base import Link
from bridge_node.links.device_io import Backoff
from bridge_node.links.messages import ETL_POSITIONS, RUDDER_ORDER_LIMIT_DEG, ControlInput, searchlight_order
from bridge_node.links.modbus.settings import ModbusLinkSettings, RegisterSpec, WriteSpec
from sim_core.frames.units import KNOT
from sim_core.ship.orders import OrderKind
from sim_core.ship.outputs import ShipOutputs

# the link counts and reports its own errors; pymodbus would also print every refused
# connection and, at some levels, every frame
logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
ORDER, ERROR, UP, DOWN, TRAFFIC = "order", "error", "up", "down", "traffic"  # worker -> loop events


@dataclass(frozen=True)
class RegisterAccess:
    """One register read or written: table, address, raw 16-bit value, and the engineering
    value (reads; nan for writes)."""

    table: str
    address: int
    raw: int
    value: float


class WorkerDied(RuntimeError):
    """The polling thread of an open link has ended."""


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
        return ControlInput(now, source, OrderKind.RUDDER, math.radians(value), spec.engine)
    if spec.order == "lever":
        if abs(value) > 100.0:
            return "out_of_range"
        return ControlInput(now, source, OrderKind.LEVER, float(value), spec.engine)
    if spec.order.startswith("searchlight_"):  # one field of the light's order; the others as they were
        if spec.order == "searchlight_on" and value not in (0.0, 1.0):
            return "out_of_range"
        on = bool(value) if spec.order == "searchlight_on" else None
        angles = [value if spec.order == f"searchlight_{k}" else None for k in ("bearing", "elevation")]
        order = searchlight_order(spec.light, on, *angles)
        return order if isinstance(order, str) else ControlInput(now, source, OrderKind.SEARCHLIGHT, order)
    code = f"{int(round(value)):02d}"
    if code not in ETL_POSITIONS:
        return "out_of_range"
    return ControlInput(now, source, OrderKind.TELEGRAPH, ETL_POSITIONS[code], spec.engine)


def indicator_value(spec: WriteSpec, s: ShipOutputs) -> float:
    """Engineering value of an indicator: rudder angle deg, shaft rpm, heading deg, speed kn."""
    return {"rudder_angle": math.degrees(s.rudder_angle), "shaft_rpm": s.shaft_rps * 60.0,
            "heading": math.degrees(s.heading), "speed": s.speed_longitudinal / KNOT}[spec.value]


class _Worker:
    """The polling thread: owns the Modbus client, reconnects it with back-off, and puts
    ``(event, payload)`` pairs on ``events`` for the loop."""

    def __init__(self, settings: ModbusLinkSettings, name: str) -> None:
        self.settings, self.name = settings, name
        self.events: queue.SimpleQueue = queue.SimpleQueue()
        self._indicators: dict[int, int] = {}  # address -> raw, latest values to write
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._client = None
        self.thread = threading.Thread(target=self._run, name=f"modbus-{name}", daemon=True)

    def set_indicators(self, values: dict[int, int]) -> None:
        with self._lock:
            self._indicators.update(values)

    def drain(self) -> Iterator[tuple[str, object]]:
        while True:
            try:
                yield self.events.get_nowait()
            except queue.Empty:
                return

    def stop(self) -> None:
        self._stop.set()
        if self.thread.is_alive():
            self.thread.join(timeout=2.0)

    def _new_client(self):
        s = self.settings
        if s.transport == "tcp":
            return ModbusTcpClient(s.host, port=s.port, timeout=s.request_timeout_s, retries=0,
                                   reconnect_delay=0.0)
        return ModbusSerialClient(s.serial_port, baudrate=s.baudrate, timeout=s.request_timeout_s, retries=0,
                                  reconnect_delay=0.0)

    def _connect(self) -> bool:
        client = self._new_client()
        if client.connect():
            self._client = client
            return True
        client.close()
        self.events.put((DOWN, "connect_failed"))
        return False

    def _run(self) -> None:
        period = 1.0 / self.settings.poll_hz
        backoff = Backoff()
        next_poll = time.monotonic()
        answering = False  # connected means the console answers, not that a port is open
        while not self._stop.is_set():
            if self._client is None:
                if backoff.ready(time.monotonic()) and not self._connect():
                    backoff.failed(time.monotonic())
                self._stop.wait(0.02)
                continue
            try:  # the orders of a good poll reach the loop even if a write after it fails
                events = self._poll_once()
                if not answering:  # up before the first orders, as the loop sees it
                    answering = True
                    events.insert(0, (UP, None))
                    backoff.succeeded()
                self._put(events)
                self._put(self._write_indicators())
            except (ModbusException, OSError, ValueError) as exc:
                self.events.put((DOWN, "bad_reply" if isinstance(exc, ValueError) else "request_failed"))
                self._client.close()
                self._client = None
                answering = False
                backoff.failed(time.monotonic())
                continue
            next_poll = max(next_poll + period, time.monotonic())
            self._stop.wait(max(0.0, next_poll - time.monotonic()))
        if self._client is not None:
            self._client.close()
            self._client = None

    def _put(self, events: list[tuple[str, object]]) -> None:
        for event in events:
            self.events.put(event)

    def _read(self, table: str, start: int, count: int) -> list[int]:
        c, dev = self._client, self.settings.device_id
        reply = (c.read_holding_registers(start, count=count, device_id=dev) if table == "holding"
                 else c.read_input_registers(start, count=count, device_id=dev))
        if reply.isError():
            raise ModbusException(f"exception reply {reply}")
        if len(reply.registers) != count:
            raise ValueError("short reply")
        return reply.registers

    def _poll_once(self) -> list[tuple[str, object]]:
        """Read every configured register once: events for the orders they hold and the reads."""
        now, events = time.monotonic(), []
        for table in ("holding", "input"):
            specs = [r for r in self.settings.registers if r.table == table]
            if not specs:
                continue
            start = min(r.address for r in specs)
            regs = self._read(table, start, max(r.address for r in specs) - start + 1)
            for spec in specs:
                raw = regs[spec.address - start]
                order = register_order(spec, raw, now, self.name)
                events.append((ERROR, order) if isinstance(order, str) else (ORDER, order))
                access = RegisterAccess(table, spec.address, raw, register_value(raw, spec.type) * spec.scale)
                events.append((TRAFFIC, ("read", access, time.time())))
        return events

    def _write_indicators(self) -> list[tuple[str, object]]:
        """Write the latest indicator values: events for the writes."""
        with self._lock:
            pending, self._indicators = self._indicators, {}
        events = []
        for address, raw in pending.items():
            reply = self._client.write_register(address, raw, device_id=self.settings.device_id)
            if reply.isError():
                raise ModbusException(f"exception reply {reply}")
            events.append((TRAFFIC, ("write", RegisterAccess("holding", address, raw, math.nan), time.time())))
        return events


class ModbusLink(Link):
    """Polls the configured registers in a worker thread (the link's device)."""

    lost_errors = (WorkerDied,)
    lost_kind = "worker_died"
    up_when_open = False  # up once the console answers

    def __init__(self, settings: ModbusLinkSettings) -> None:
        super().__init__(settings)
        self._answered_before = False

    def _open_device(self) -> _Worker:
        worker = _Worker(self.settings, self.name)
        worker.thread.start()
        return worker

    def _close_device(self, worker: _Worker) -> None:
        worker.stop()

    def _poll_device(self, now: float) -> Iterator[ControlInput]:
        """Drain the worker's events: orders yielded, the rest applied to health and listeners."""
        alive = self.device.thread.is_alive()  # read first: events put before it ended are drained below
        for event, payload in self.device.drain():
            if event == ORDER:
                yield payload
            elif event == TRAFFIC:
                direction, access, unix_time = payload
                self._report(direction, access, unix_time)
                if direction == "write":
                    self._health.outputs += 1
            elif event == UP:
                self._health.connected = True
                self._health.reconnects += self._answered_before
                self._answered_before = True
            else:  # ERROR, or DOWN: a connect or request failed
                self._count_error(payload)
                if event == DOWN:
                    self._health.connected = False
                    self._failed = True
        if not alive:
            raise WorkerDied(f"modbus link {self.name}: polling thread ended")

    def publish(self, state: ShipOutputs, now: float) -> None:
        if self.settings.writes and self.device is not None:
            self.device.set_indicators({w.address: raw_register(indicator_value(w, state) / w.scale, w.type)
                                        for w in self.settings.writes})
