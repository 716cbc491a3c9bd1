"""NMEA 0183 link: console orders from a serial line, instrument sentences out on the same
line (paced within its baud budget) and, where the settings say so, copied to UDP (port
10110 on the loopback by default) for chart plotters such as OpenCPN. A link without a
serial port sends on UDP only; one with a port copies to UDP only if ``udp_output``. With
``[links.ais]`` the own ship also goes out as ``!AIVDO`` and the other vessels as ``!AIVDM``.
The serial line is written by a writer thread: the loop never waits for a far end that does
not read."""
from __future__ import annotations

import datetime as dt
import io
import select
import socket
import time
from collections.abc import Iterator

import serial

from bridge_node.common.network import is_loopback_host
from bridge_node.links.base import Link
from bridge_node.links.convoy import ConvoyTarget
from bridge_node.links.device_io import QueuedWriter, RateSchedule
from bridge_node.links.messages import Alarm, ControlInput, Vessel
from bridge_node.links.nmea0183.ais import AisReporter
from bridge_node.links.nmea0183.sentences import (TTM_RATE, SentenceError, parse_order, render_alarm,
                                                  render_outputs, render_targets)
from bridge_node.links.nmea0183.settings import NmeaLinkSettings
from sim_core.ship.outputs import ShipOutputs

MAX_PENDING = 1024  # characters of a line without its end: beyond this it is noise
SEND_QUEUE = 64  # sentences the writer may hold; beyond this a sentence is dropped (send_failed)
ROOM_WAIT_S = 0.1  # the writer looks this often whether the link is closing while the line is full


class _NoPort:
    """The serial port of a UDP-only link: nothing comes in, nothing goes out."""

    in_waiting = 0

    def close(self) -> None:
        pass


class _SerialPort:
    """An open serial port: read on the loop's thread, written by a ``QueuedWriter``, which
    closes the port last. pyserial's write spins while an OS port's buffer is full, so the
    writer waits for room with ``select``; a URL handler's port (``loop://``,
    ``socket://``) has no descriptor and is written blocking, as its own write waits."""

    def __init__(self, port: serial.SerialBase, name: str) -> None:
        self.port = port
        try:
            self._fd: int | None = port.fileno()
        except io.UnsupportedOperation:
            self._fd = None
            port.write_timeout = None
        self.writer = QueuedWriter(self._write, port.close, (serial.SerialException, OSError),
                                   f"nmea-send-{name}", SEND_QUEUE)

    @property
    def in_waiting(self) -> int:
        return self.port.in_waiting

    def read(self, size: int) -> bytes:
        return self.port.read(size)

    def _write(self, data: bytes) -> None:
        """Write all of ``data`` (on the writer's thread), waiting for room; a write cut
        short by closing is let go."""
        while data and not self.writer.closing.is_set():
            if self._fd is None or select.select([], [self._fd], [], ROOM_WAIT_S)[1]:
                data = data[self.port.write(data):]

    def close(self) -> None:
        """Have the writer close the port once its write is through (not waited for)."""
        self.writer.close()


class NmeaLink(Link):
    """Serial NMEA 0183 (pyserial; any ``serial_for_url`` port) plus a UDP output mirror."""

    open_errors = (serial.SerialException, OSError, ValueError)
    lost_errors = (serial.SerialException, OSError)
    lost_kind = "port_lost"

    def __init__(self, settings: NmeaLinkSettings) -> None:
        super().__init__(settings)
        self._udp: socket.socket | None = None
        self._pending = b""
        self._schedule = RateSchedule({k: r for k, r in settings.output_rates().items() if k != "TTM"})
        self._targets_schedule = RateSchedule({"TTM": settings.rates.get("TTM", TTM_RATE)})
        self._talkers = settings.talkers
        self._allowed = settings.order_talkers()
        self._ais = AisReporter(settings.ais) if settings.ais is not None else None
        self._budget = settings.baudrate / 10.0  # characters per second, 8N1
        self._tokens = self._budget
        self._last_refill = time.monotonic()
        self._clock_offset = 0.0  # exercise UTC minus the wall clock, s

    def begin_open(self) -> None:
        if self.settings.sends_udp() and self._udp is None:
            self._udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            if is_loopback_host(self.settings.udp_host):  # never open a port off the host
                self._udp.bind(("127.0.0.1", 0))
        super().begin_open()

    def close(self) -> None:
        super().close()
        if self._udp is not None:
            self._udp.close()
            self._udp = None

    def _open_device(self) -> _SerialPort | _NoPort:
        if not self.settings.port:
            return _NoPort()
        port = serial.serial_for_url(self.settings.port, baudrate=self.settings.baudrate, timeout=0, write_timeout=0)
        return _SerialPort(port, self.name)

    def _close_device(self, port: _SerialPort | _NoPort) -> None:
        port.close()

    def _poll_device(self, now: float) -> Iterator[ControlInput]:
        if self.settings.port:  # a write that failed on the writer's thread: the port is lost
            for exc in self.device.writer.failures():
                raise exc
        waiting = self.device.in_waiting
        chunk = self.device.read(waiting) if waiting else b""
        lines = (self._pending + chunk).split(b"\n")
        self._pending = lines.pop()
        if len(self._pending) > MAX_PENDING:
            self._count_error("malformed")
            self._pending = b""
        for raw in lines:
            line = raw.decode("ascii", errors="replace").strip()
            if not line:
                continue
            self._report("rx", line)
            try:
                yield from parse_order(line, now, self.name, self._allowed)
            except SentenceError as exc:
                self._count_error(exc.kind)

    def _write_serial(self, data: bytes) -> bool:
        """Queue one sentence for the writer within the baud budget; False if it was not
        (counted: ``baud_budget_skipped``, or ``send_failed`` while the far end does not read)."""
        if len(data) > self._tokens:
            self._count_error("baud_budget_skipped")
            return False
        if not self.device.writer.put(data):
            self._count_error("send_failed")
            return False
        self._tokens -= len(data)
        return True

    def _send(self, sentences: list[str], now: float) -> None:
        elapsed, self._last_refill = now - self._last_refill, now
        self._tokens = min(self._budget, self._tokens + elapsed * self._budget)
        for s in sentences:
            data = (s + "\r\n").encode("ascii")
            if self._udp is not None:
                try:
                    self._udp.sendto(data, (self.settings.udp_host, self.settings.udp_port))
                except OSError:
                    self._count_error("udp_send_failed")
            if self.settings.port and self.device is not None and not self._write_serial(data):
                continue
            self._report("tx", s)
            self._health.outputs += 1
        if self.settings.port and self.device is not None:
            self.device.writer.flush()  # the sentences of one call reach the writer together

    def _utc(self) -> dt.datetime:
        """The exercise clock (the outputs' UTC, which a replay takes from its log)."""
        return dt.datetime.fromtimestamp(time.time() + self._clock_offset, dt.timezone.utc)

    def publish(self, state: ShipOutputs, now: float) -> None:
        if state.utc > 0.0:
            self._clock_offset = state.utc - time.time()
        utc = self._utc()
        sentences = render_outputs(self._schedule.due(now), state, utc, self._talkers)
        if self._ais is not None:
            sentences += self._ais.own_ship(state, now, utc)
        if sentences:
            self._send(sentences, now)

    def publish_targets(self, targets: list[ConvoyTarget], now: float) -> None:
        if targets and self._targets_schedule.due(now):
            self._send(render_targets(targets, self._utc(), self._talkers.get("TTM", "RA")), now)

    def publish_vessels(self, vessels: list[Vessel], now: float) -> None:
        if self._ais is not None and vessels:
            self._send(self._ais.others(vessels, now, self._utc()), now)

    def publish_alarm(self, alarm: Alarm, now: float) -> None:
        talker = self._talkers.get("ALR", "II")
        self._send([render_alarm(alarm, self._utc(), talker)], now)
