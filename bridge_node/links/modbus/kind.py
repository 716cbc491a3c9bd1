"""The Modbus link kind: ``modbus.csv`` in the session record (one row per register read or
write), and its replay through the link's own register decoding."""
from __future__ import annotations

import csv
from collections.abc import Iterator, Sequence
from pathlib import Path

from bridge_node.links.base import Link
from bridge_node.links.kind import LinkKind, RecordFormat, RecordWriter, ReplayFeed, register_kind
from bridge_node.links.messages import ControlInput, Traffic
from bridge_node.links.modbus.link import ModbusLink, register_order
from bridge_node.links.modbus.settings import ModbusLinkSettings
from bridge_node.links.record_reader import MODBUS_COLUMNS, read_modbus_csv


class _ModbusCsvWriter(RecordWriter):
    """``modbus.csv``: a header row when the file is new, then one row per register access."""

    def __init__(self, path: Path) -> None:
        new = not path.exists()
        self._file = open(path, "a", newline="", encoding="utf-8")
        self._csv = csv.writer(self._file)
        if new:
            self._csv.writerow(MODBUS_COLUMNS)

    def write(self, traffic: Traffic) -> None:
        a = traffic.data  # a modbus.link.RegisterAccess
        self._csv.writerow([f"{traffic.unix_time:.3f}", traffic.link, traffic.direction, a.table, a.address, a.raw,
                            a.value])

    def flush(self) -> None:
        self._file.flush()

    def close(self) -> None:
        self._file.close()


class _RecordedModbus(Link):
    """A Modbus link whose register reads come from the record: each read row becomes the
    order its register holds, timed at its read."""

    def __init__(self, settings: ModbusLinkSettings) -> None:
        super().__init__(settings)
        self.pending: list[tuple[float, dict]] = []  # (monotonic time of the read, row)
        self._specs = {(r.table, r.address): r for r in settings.registers}

    def _open_device(self) -> object:
        return self.pending

    def _close_device(self, device) -> None:
        pass

    def _poll_device(self, now: float) -> Iterator[ControlInput]:
        rows, self.pending = self.pending, []
        for when, row in rows:
            spec = self._specs.get((row["table"], int(row["address"])))
            if spec is None:
                continue  # a register this config does not read as an order
            order = register_order(spec, int(row["raw"]), when, self.name)
            if isinstance(order, str):
                self._count_error(order)
            else:
                yield order

    def publish(self, state, now: float) -> None:
        pass


class _ModbusReplay(ReplayFeed):
    """The recorded register reads of one Modbus link, each timed at the tick's clock less the
    time between the read and the tick's poll."""

    def __init__(self, settings: ModbusLinkSettings, siblings: Sequence[ModbusLinkSettings]) -> None:
        self.link = _RecordedModbus(settings)

    def owns(self, record: dict) -> bool:
        return record["link"] == self.link.name

    def feed(self, record: dict, tick_monotonic: float, tick_unix: float) -> None:
        self.link.pending.append((tick_monotonic - (tick_unix - float(record["unix_time"])), record))


MODBUS = register_kind(LinkKind(
    "modbus", ModbusLinkSettings, ModbusLink,
    RecordFormat("modbus.csv", _ModbusCsvWriter, read_modbus_csv, lambda row: row.get("op"),
                 lambda row: float(row["unix_time"]), input_direction="read"),
    _ModbusReplay))
