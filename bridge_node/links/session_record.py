"""Append-only session record of every link input and output, for replay and post-mortem: a
``Listener`` the hub adds to every link when it is given a record folder.

One folder per session: ``can.log`` in python-can's candump log format (written by
``can.Logger``, read back by ``can.LogReader``), ``nmea.log`` with one raw sentence per line
(``<unix time> <link> <rx|tx> <sentence>``), ``modbus.csv`` with one row per register
read or write, and ``dis.log`` with one PDU per line (``<unix time> <link> <rx|tx> <hex>``). ``flush()`` is called every tick and writes to the OS at most a second after
a line was added, so a killed node loses at most the last second.

Every complete line ends with a newline, and lines are only appended, so after a power cut
or a full disk only the last line can be torn, and it has no newline: readers
(``record_reader``) skip it and count it. Before appending to an existing file the record
cuts such a torn tail off, so it never glues onto the next line.
"""
from __future__ import annotations

import csv
import logging
import time
from pathlib import Path

import can

from bridge_node.links.messages import Listener, Traffic

FLUSH_PERIOD = 0.5  # s
log = logging.getLogger("icebridge.record")


def cut_torn_tail(path: Path) -> bool:
    """Truncate a file after its last newline if it ends in a torn line; True if it did."""
    if not path.is_file() or path.stat().st_size == 0:
        return False
    with open(path, "rb+") as f:
        f.seek(-1, 2)
        if f.read(1) == b"\n":
            return False
        f.seek(0)
        data = f.read()
        f.truncate(data.rfind(b"\n") + 1)
    return True


class SessionRecord(Listener):
    """Writers for one session folder (created if missing; existing files are appended to)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.torn_tails_cut = sum(cut_torn_tail(self.folder / name)
                                  for name in ("can.log", "nmea.log", "modbus.csv", "dis.log"))
        self._can = can.Logger(str(self.folder / "can.log"), append=True)
        self._nmea = open(self.folder / "nmea.log", "a", encoding="ascii", errors="replace")
        self._dis = open(self.folder / "dis.log", "a", encoding="ascii")
        new_csv = not (self.folder / "modbus.csv").exists()
        self._modbus_file = open(self.folder / "modbus.csv", "a", newline="", encoding="utf-8")
        self._modbus = csv.writer(self._modbus_file)
        if new_csv:
            self._modbus.writerow(["unix_time", "link", "op", "table", "address", "raw", "value"])
        self._last_flush = time.monotonic()
        self._writers = {"can": self._can_frame, "nmea0183": self._sentence, "modbus": self._register,
                         "dis": self._pdu}
        self._stopped = False
        self.failed: str | None = None  # why recording stopped (a full disk, say); the node goes on

    def on_traffic(self, traffic: Traffic) -> None:
        if self.failed is None:
            try:
                self._writers[traffic.protocol](traffic)
            except OSError as exc:
                self._fail(exc)

    def _fail(self, exc: OSError) -> None:
        self.failed = exc.strerror or str(exc)
        log.error("session record in %s stopped: %s", self.folder, self.failed)

    def _can_frame(self, t: Traffic) -> None:
        self._can(t.data)  # the frame's own timestamp, wall-clock unix time

    def _sentence(self, t: Traffic) -> None:
        self._nmea.write(f"{t.unix_time:.3f} {t.link} {t.direction} {t.data.strip()}\n")

    def _pdu(self, t: Traffic) -> None:
        self._dis.write(f"{t.unix_time:.3f} {t.link} {t.direction} {t.data.hex()}\n")

    def _register(self, t: Traffic) -> None:
        a = t.data  # a modbus_link.RegisterAccess
        self._modbus.writerow([f"{t.unix_time:.3f}", t.link, t.direction, a.table, a.address, a.raw, a.value])

    def flush(self, force: bool = False) -> None:
        """Write buffered lines to the OS if ``FLUSH_PERIOD`` has passed (or ``force``)."""
        now = time.monotonic()
        if self.failed is None and (force or now - self._last_flush >= FLUSH_PERIOD):
            try:
                self._can.file.flush()
                self._nmea.flush()
                self._dis.flush()
                self._modbus_file.flush()
            except OSError as exc:
                self._fail(exc)
            self._last_flush = now

    def stop(self) -> None:
        """Flush and close the files; safe to call twice."""
        if self._stopped:
            return
        self._stopped = True
        self.flush(force=True)
        for close in (self._can.stop, self._nmea.close, self._dis.close, self._modbus_file.close):
            try:
                close()
            except OSError as exc:  # the data that did not fit is lost either way; say so once
                if self.failed is None:
                    self._fail(exc)
