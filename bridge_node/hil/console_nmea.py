"""The software console's NMEA 0183 end: ROR, ETL, PRC and the searchlight's sentence out
on a serial line, the node's sentences (RSA, RPM, HDT, ROT) and ALR alarms read back."""
from __future__ import annotations

import math
import random

import serial

from bridge_node.hil.console_links import ETL_CODES, AlarmReading, ConsoleLink, Order, Reading
from bridge_node.hil.settings import NmeaConsoleSettings
from bridge_node.links.nmea0183.sentences import ETL, PRC, ROR, SEARCHLIGHT_SENTENCE, checksum
from sim_core.ship.orders import OrderKind


NMEA_READINGS = {"RSA": (0, "rudder_angle", math.radians(1.0)), "RPM": (2, "shaft_speed", 1.0 / 60.0),
                 "HDT": (0, "heading", math.radians(1.0)), "ROT": (0, "rate_of_turn", math.radians(1.0) / 60.0)}
MAX_LINE = 1024  # characters of a line without its end: beyond this it is noise


class NmeaConsole(ConsoleLink):
    """The console on a serial NMEA 0183 line (pyserial: a port or a pty)."""

    kind = "nmea0183"
    corruptions = ("checksum", "range")
    framing = "checksum"
    garbage_kind = "random bytes"

    def __init__(self, settings: NmeaConsoleSettings) -> None:
        super().__init__(settings)
        self._pending = b""

    def _open(self) -> serial.SerialBase:
        return serial.serial_for_url(self.settings.port, baudrate=self.settings.baudrate, timeout=0, write_timeout=1.0)

    def _close(self, port: serial.SerialBase) -> None:
        port.close()

    def _encode(self, order: Order, corrupt: str | None) -> list[bytes]:
        value = order.wire_value(corrupt)
        talker = self.settings.talker
        if order.kind == OrderKind.RUDDER:
            sentence = str(ROR(talker, "ROR", (f"{math.degrees(value):.1f}", "A", "", "V", "B")))
        elif order.kind == OrderKind.SEARCHLIGHT:
            body = (f"{SEARCHLIGHT_SENTENCE},{value.index},{'A' if value.on else 'V'},"
                    f"{math.degrees(value.bearing):.1f},{math.degrees(value.elevation):.1f}")
            sentence = f"${body}*{checksum(body):02X}"
        elif order.kind == OrderKind.TELEGRAPH:
            code = value if corrupt == "range" else ETL_CODES[value]
            sentence = str(ETL(talker, "ETL", ("", "O", code, "", "B", "0")))
        else:
            sentence = str(PRC(talker, "PRC", (f"{value:.1f}", "A", "", "V", "", "V", "B", "0")))
        if corrupt == "checksum":
            body, given = sentence.rsplit("*", 1)
            sentence = f"{body}*{int(given, 16) ^ 0x55:02X}"
        return [(sentence + "\r\n").encode("ascii")]

    def _write(self, data: bytes) -> None:
        self.device.write(data)

    def _garbage(self, rng: random.Random, count: int) -> list[bytes]:
        return [bytes(rng.randrange(256) for _ in range(count))]

    def _read(self, now: float) -> list[Reading | AlarmReading]:
        waiting = self.device.in_waiting
        lines = (self._pending + (self.device.read(waiting) if waiting else b"")).split(b"\n")
        self._pending = lines.pop()[-MAX_LINE:]
        out = []
        for raw in lines:
            line = raw.decode("ascii", errors="replace").strip()
            if not line.startswith("$") or "*" not in line:
                continue
            body, given = line[1:].rsplit("*", 1)
            try:
                if checksum(body) != int(given, 16):
                    continue
            except ValueError:
                continue
            fields = body.split(",")
            kind = fields[0][2:]
            try:
                if kind == "ALR":
                    out.append(AlarmReading(now, self.role, int(fields[2]), fields[3] == "A", fields[5]))
                elif kind in NMEA_READINGS:
                    index, quantity, factor = NMEA_READINGS[kind]
                    out.append(Reading(now, self.role, quantity, float(fields[1 + index]) * factor))
            except (ValueError, IndexError):
                continue
        return out
