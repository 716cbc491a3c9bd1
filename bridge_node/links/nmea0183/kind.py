"""The NMEA 0183 link kind: ``nmea.log`` in the session record, and its replay from a
``loop://`` port."""
from __future__ import annotations

from collections.abc import Sequence

from bridge_node.links.kind import LinkKind, RecordFormat, ReplayFeed, TextLineWriter, register_kind
from bridge_node.links.messages import Traffic
from bridge_node.links.nmea0183.link import NmeaLink
from bridge_node.links.nmea0183.settings import NmeaLinkSettings
from bridge_node.links.record_reader import NmeaRecord, read_nmea_log


class _NmeaReplay(ReplayFeed):
    """An NMEA link reading its recorded sentences from a ``loop://`` port."""

    def __init__(self, settings: NmeaLinkSettings, siblings: Sequence[NmeaLinkSettings]) -> None:
        self.link = NmeaLink(settings.model_copy(update={"port": "loop://", "udp_output": False}))

    def owns(self, record: NmeaRecord) -> bool:
        return record.link == self.link.name

    def feed(self, record: NmeaRecord, tick_monotonic: float, tick_unix: float) -> None:
        if self.link.device is not None:
            self.link.device.port.write((record.sentence + "\r\n").encode("ascii", errors="replace"))


def _record_line(t: Traffic) -> str:
    """``<unix time> <link> <rx|tx> <sentence>``, a line of ``nmea.log``."""
    return f"{t.unix_time:.3f} {t.link} {t.direction} {t.data.strip()}"


NMEA0183 = register_kind(LinkKind(
    "nmea0183", NmeaLinkSettings, NmeaLink,
    RecordFormat("nmea.log", lambda path: TextLineWriter(path, _record_line), read_nmea_log,
                 lambda r: r.direction, lambda r: r.unix_time, input_direction="rx"),
    _NmeaReplay))
