"""Append-only session record of every link input and output, for replay and post-mortem.

One folder per session: ``can.log`` in python-can's candump log format (written by
``can.Logger``, read back by ``can.LogReader``), ``nmea.log`` with one raw sentence per line
(``<unix time> <link> <rx|tx> <sentence>``), and ``modbus.csv`` with one row per register
read or write. ``flush()`` is called every tick and writes to the OS at most a second after
a line was added, so a killed node loses at most the last second.
"""
from __future__ import annotations

import csv
import time
from pathlib import Path

import can

FLUSH_PERIOD = 0.5  # s


class SessionRecord:
    """Writers for one session folder (created if missing; existing files are appended to)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self._can = can.Logger(str(self.folder / "can.log"), append=True)
        self._nmea = open(self.folder / "nmea.log", "a", encoding="ascii", errors="replace")
        new_csv = not (self.folder / "modbus.csv").exists()
        self._modbus_file = open(self.folder / "modbus.csv", "a", newline="", encoding="utf-8")
        self._modbus = csv.writer(self._modbus_file)
        if new_csv:
            self._modbus.writerow(["unix_time", "link", "op", "table", "address", "raw", "value"])
        self._last_flush = time.monotonic()

    def can_frame(self, msg: can.Message) -> None:
        """A CAN frame in or out (its timestamp should be wall-clock unix time)."""
        self._can(msg)

    def nmea(self, link: str, direction: str, sentence: str) -> None:
        self._nmea.write(f"{time.time():.3f} {link} {direction} {sentence.strip()}\n")

    def modbus(self, link: str, op: str, table: str, address: int, raw: int, value: float) -> None:
        self._modbus.writerow([f"{time.time():.3f}", link, op, table, address, raw, value])

    def flush(self, force: bool = False) -> None:
        now = time.monotonic()
        if force or now - self._last_flush >= FLUSH_PERIOD:
            self._can.file.flush()
            self._nmea.flush()
            self._modbus_file.flush()
            self._last_flush = now

    def close(self) -> None:
        self.flush(force=True)
        self._can.stop()
        self._nmea.close()
        self._modbus_file.close()
