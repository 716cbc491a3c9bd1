"""The CAN link kind: ``can.log`` in the session record, and its replay on a virtual bus."""
from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path

import can

from bridge_node.links.can.link import CanLink
from bridge_node.links.can.settings import CanLinkSettings
from bridge_node.links.kind import LinkKind, RecordFormat, RecordWriter, ReplayFeed, register_kind
from bridge_node.links.messages import Traffic
from bridge_node.links.record_reader import read_can_log


class _CanLogWriter(RecordWriter):
    """``can.log`` in python-can's candump format, written by ``can.Logger`` (each frame with
    its own timestamp, wall-clock unix time)."""

    def __init__(self, path: Path) -> None:
        self._logger = can.Logger(str(path), append=True)

    def write(self, traffic: Traffic) -> None:
        self._logger(traffic.data)

    def flush(self) -> None:
        self._logger.file.flush()

    def close(self) -> None:
        self._logger.stop()


_replay_channels = itertools.count()


class _CanReplay(ReplayFeed):
    """A CAN link on a virtual bus of its own, sent its recorded frames: those of its recorded
    channel, and (the first CAN link) those of a channel no CAN link of the config has."""

    def __init__(self, settings: CanLinkSettings, siblings: Sequence[CanLinkSettings]) -> None:
        channel = f"icebridge-replay-{next(_replay_channels)}"
        self.link = CanLink(settings.model_copy(update={"interface": "virtual", "channel": channel}))
        self._bus = can.Bus(interface="virtual", channel=channel)
        self._channel = settings.channel
        self._known = {s.channel for s in siblings}
        self._first = siblings[0].name == settings.name

    def owns(self, record: can.Message) -> bool:
        channel = str(record.channel)
        return channel == self._channel or (self._first and channel not in self._known)

    def feed(self, record: can.Message, tick_monotonic: float, tick_unix: float) -> None:
        self._bus.send(record)

    def after_poll(self) -> None:
        while self._bus.recv(0.0) is not None:  # what the link sent (address claims): not needed
            pass

    def close(self) -> None:
        self._bus.shutdown()


CAN = register_kind(LinkKind(
    "can", CanLinkSettings, CanLink,
    RecordFormat("can.log", _CanLogWriter, read_can_log, lambda m: "rx" if m.is_rx else "tx",
                 lambda m: m.timestamp, input_direction="rx"),
    _CanReplay))
