"""The DIS link kind. Its traffic in the session record (``dis.log``: ``<unix time> <link>
<rx|tx> <hex>``, one PDU a line) is read back so that a replay can hear again what the node
heard (``traffic.sources``); it is not fed back to a link, as the entities heard are not
orders. A torn last line and lines that do not parse are counted, never fatal."""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from bridge_node.links.dis.link import DisLink
from bridge_node.links.dis.settings import DisLinkSettings
from bridge_node.links.kind import LinkKind, RecordFormat, TextLineWriter, register_kind
from bridge_node.links.messages import Traffic
from bridge_node.links.record_reader import complete_lines, record_time


@dataclass(frozen=True)
class DisRecord:
    """One line of ``dis.log``: unix time (s), link name, "rx" or "tx", the PDU."""

    unix_time: float
    link: str
    direction: str
    pdu: bytes


def read_dis_log(path: Path) -> tuple[list[DisRecord], Counter]:
    """The PDUs of ``dis.log``, and counts of torn and malformed lines (a unix time that is
    not a finite number in the record's range included)."""
    lines, counts = complete_lines(path)
    out = []
    for line in lines:
        parts = line.split(" ")
        try:
            if len(parts) != 4 or parts[2] not in ("rx", "tx"):
                raise ValueError(line)
            out.append(DisRecord(record_time(parts[0]), parts[1], parts[2], bytes.fromhex(parts[3])))
        except ValueError:
            counts["malformed"] += 1
    return out, counts


def _record_line(t: Traffic) -> str:
    return f"{t.unix_time:.3f} {t.link} {t.direction} {t.data.hex()}"


DIS = register_kind(LinkKind(
    "dis", DisLinkSettings, DisLink,
    RecordFormat("dis.log", lambda path: TextLineWriter(path, _record_line), read_dis_log, lambda r: r.direction,
                 lambda r: r.unix_time, input_direction=None)))
