"""Append-only session record of every link input and output, for replay and post-mortem: a
``Listener`` the hub adds to every link when it is given a record folder.

One folder per session, a file per link kind, in the kind's own format (its module says):
``can.log`` in python-can's candump log format, ``nmea.log`` with one raw sentence per line
(``<unix time> <link> <rx|tx> <sentence>``), ``modbus.csv`` with one row per register
read or write, and ``dis.log`` with one PDU per line (``<unix time> <link> <rx|tx> <hex>``).
``flush()`` is called every tick and writes to the OS at most a second after a line was
added, so a killed node loses at most the last second.

Every complete line ends with a newline, and lines are only appended, so after a power cut
or a full disk only the last line can be torn, and it has no newline: readers
(``record_reader``) skip it and count it. Before appending to an existing file the record
cuts such a torn tail off, so it never glues onto the next line.
"""
from __future__ import annotations

import logging
import time
from pathlib import Path

from bridge_node.links.kind import LINK_KINDS, RecordWriter
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
    """Writers for one session folder (created if missing; existing files are appended to):
    a file per registered link kind (``LinkKind.record``)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        formats = {name: kind.record for name, kind in LINK_KINDS.items()}
        self.torn_tails_cut = sum(cut_torn_tail(self.folder / f.file) for f in formats.values())
        self._writers: dict[str, RecordWriter] = {name: f.writer(self.folder / f.file) for name, f in formats.items()}
        self._last_flush = time.monotonic()
        self._stopped = False
        self.failed: str | None = None  # why recording stopped (a full disk, say); the node goes on

    def on_traffic(self, traffic: Traffic) -> None:
        if self.failed is None:
            try:
                self._writers[traffic.protocol].write(traffic)
            except OSError as exc:
                self._fail(exc)

    def _fail(self, exc: OSError) -> None:
        self.failed = exc.strerror or str(exc)
        log.error("session record in %s stopped: %s", self.folder, self.failed)

    def flush(self, force: bool = False) -> None:
        """Write buffered lines to the OS if ``FLUSH_PERIOD`` has passed (or ``force``)."""
        now = time.monotonic()
        if self.failed is None and (force or now - self._last_flush >= FLUSH_PERIOD):
            try:
                for writer in self._writers.values():
                    writer.flush()
            except OSError as exc:
                self._fail(exc)
            self._last_flush = now

    def stop(self) -> None:
        """Flush and close the files; safe to call twice."""
        if self._stopped:
            return
        self._stopped = True
        self.flush(force=True)
        for writer in self._writers.values():
            try:
                writer.close()
            except OSError as exc:  # the data that did not fit is lost either way; say so once
                if self.failed is None:
                    self._fail(exc)
