"""NMEA 0183 link: console orders from a serial line, instrument sentences out on the same
line (paced within its baud budget) and mirrored on UDP (port 10110, loopback by default)
for chart plotters such as OpenCPN."""
from __future__ import annotations

import datetime as dt
import socket
import time

import serial

from bridge_node.links.base import Alarm, ControlInput, DeviceLink, RateSchedule
from bridge_node.links.link_settings import NmeaLinkSettings
from bridge_node.links.nmea0183 import SentenceError, parse_order, render_alarm, render_outputs
from bridge_node.links.session_record import SessionRecord
from sim_core.ship_outputs import ShipOutputs

MAX_PENDING = 1024  # characters of a line without its end: beyond this it is noise


class NmeaLink(DeviceLink):
    """Serial NMEA 0183 (pyserial; any ``serial_for_url`` port) plus a UDP output mirror."""

    device_errors = (serial.SerialException, OSError, ValueError)

    def __init__(self, settings: NmeaLinkSettings, record: SessionRecord | None = None) -> None:
        super().__init__(settings.name)
        self.settings = settings
        self.record = record
        self._udp: socket.socket | None = None
        self._pending = b""
        self._schedule = RateSchedule(settings.output_rates())
        self._talkers = settings.talkers
        self._allowed = frozenset(settings.allowed_talkers)
        self._budget = settings.baudrate / 10.0  # characters per second, 8N1
        self._tokens = self._budget
        self._last_refill = time.monotonic()

    def open(self) -> None:
        if self.settings.udp_port:
            self._udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        if self.settings.port:
            self._connect(time.monotonic())
        else:
            self._health.connected = True  # UDP output only

    def _open_device(self) -> serial.SerialBase:
        return serial.serial_for_url(self.settings.port, baudrate=self.settings.baudrate, timeout=0, write_timeout=0)

    def _close_device(self, port: serial.SerialBase) -> None:
        port.close()

    def poll(self, now: float) -> list[ControlInput]:
        if not self.settings.port:
            return []
        if self.device is None:
            self._reconnect_if_due(now)
            return []
        try:
            waiting = self.device.in_waiting
            chunk = self.device.read(waiting) if waiting else b""
        except (serial.SerialException, OSError):
            self._lost(now, "port_lost")
            return []
        lines = (self._pending + chunk).split(b"\n")
        self._pending = lines.pop()
        if len(self._pending) > MAX_PENDING:
            self._count_error("malformed")
            self._pending = b""
        out = []
        for raw in lines:
            line = raw.decode("ascii", errors="replace").strip()
            if not line:
                continue
            if self.record:
                self.record.nmea(self.name, "rx", line)
            try:
                out.extend(parse_order(line, now, self.name, self._allowed))
            except SentenceError as exc:
                self._count_error(exc.kind)
        return self._received(out, now)

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
            if self.device is not None:
                if len(data) > self._tokens:
                    self._count_error("baud_budget_skipped")
                    continue
                try:
                    self.device.write(data)
                except serial.SerialTimeoutException:
                    self._count_error("write_blocked")
                    continue
                except (serial.SerialException, OSError):
                    self._lost(now, "port_lost")
                    continue
                self._tokens -= len(data)
            if self.record:
                self.record.nmea(self.name, "tx", s)
            self._health.outputs += 1

    def publish(self, state: ShipOutputs, now: float) -> None:
        due = self._schedule.due(now)
        if due:
            self._send(render_outputs(due, state, dt.datetime.now(dt.timezone.utc), self._talkers), now)

    def publish_alarm(self, alarm: Alarm, now: float) -> None:
        talker = self._talkers.get("ALR", "II")
        self._send([render_alarm(alarm, dt.datetime.now(dt.timezone.utc), talker)], now)

    def close(self) -> None:
        super().close()
        if self._udp is not None:
            self._udp.close()
            self._udp = None
