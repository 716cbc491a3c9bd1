"""All configured links together, fanned out like python-can's ``Notifier``: each tick polls
every link, arbitrates the orders, publishes the ship state and any alarm changes on every
link, raises and clears a link-down alarm per link, and flushes the session record."""
from __future__ import annotations

import logging
import math
from collections import Counter
from pathlib import Path

from bridge_node.config import NodeConfig, resolve_path
from bridge_node.links.base import Alarm, ControlInput, Link
from bridge_node.links.can_link import CanLink
from bridge_node.links.link_settings import CanLinkSettings, ModbusLinkSettings, NmeaLinkSettings
from bridge_node.links.modbus_link import ModbusLink
from bridge_node.links.nmea_link import NmeaLink
from bridge_node.links.session_record import SessionRecord
from bridge_node.order_arbiter import Decision, OrderArbiter
from sim_core.ship_outputs import ShipOutputs

log = logging.getLogger("icebridge.links")
LINK_DOWN_ALARM = 200  # + the link's index
ALARM_REPEAT_S = 10.0  # active alarms are announced again this often


def make_link(settings, config_path: str | None, record: SessionRecord | None) -> Link:
    if isinstance(settings, CanLinkSettings):
        return CanLink(settings, resolve_path(config_path, settings.dbc), record)
    if isinstance(settings, NmeaLinkSettings):
        return NmeaLink(settings, record)
    if isinstance(settings, ModbusLinkSettings):
        return ModbusLink(settings, record)
    raise TypeError(f"no link for {type(settings).__name__}")


class LinkHub:
    """The node's links, the arbiter and the alarms."""

    def __init__(self, cfg: NodeConfig, config_path: str | None, record_dir: Path | None = None) -> None:
        self.record = SessionRecord(record_dir) if record_dir else None
        self.links = [make_link(s, config_path, self.record) for s in cfg.links]
        self.arbiter = OrderArbiter(cfg.arbitration, {s.name: s.timeout_s for s in cfg.links})
        self.active_alarms: dict[int, Alarm] = {}
        self.alarm_log: list[tuple[float, Alarm]] = []
        self._last_announce = -math.inf
        self.last_orders: dict[str, ControlInput] = {}  # "source/kind/engine" -> latest order
        self.order_counts: Counter = Counter()

    def open(self) -> None:
        for link in self.links:
            link.open()

    def close(self) -> None:
        for link in self.links:
            link.close()
        if self.record:
            self.record.close()

    def tick(self, state: ShipOutputs, now: float) -> Decision:
        """Poll, arbitrate, publish; returns the orders for the ship."""
        inputs = []
        for link in self.links:
            got = link.poll(now)
            inputs.extend(got)
            for order in got:
                key = f"{order.source}/{order.kind}/{order.engine}"
                self.last_orders[key] = order
                self.order_counts[key] += 1
        self.arbiter.feed(inputs)
        decision = self.arbiter.decide(now)
        changes = list(decision.alarms)
        for i, link in enumerate(self.links):
            number, up = LINK_DOWN_ALARM + i, link.health().connected
            if up == (number in self.active_alarms):
                changes.append(Alarm(number, f"link {link.name} {'up' if up else 'down'}", not up))
        for alarm in changes:
            self._raise(alarm, now)
        if now - self._last_announce >= ALARM_REPEAT_S:
            self._last_announce = now
            changes = list(self.active_alarms.values())
        for link in self.links:
            link.publish(state, now)
            for alarm in changes:
                link.publish_alarm(alarm, now)
        if self.record:
            self.record.flush()
        return decision

    def _raise(self, alarm: Alarm, now: float) -> None:
        self.alarm_log.append((now, alarm))
        if alarm.active:
            self.active_alarms[alarm.number] = alarm
            log.warning("alarm %03d: %s", alarm.number, alarm.text)
        else:
            self.active_alarms.pop(alarm.number, None)
            log.info("alarm %03d cleared: %s", alarm.number, alarm.text)

    def errors(self) -> Counter:
        total = Counter()
        for link in self.links:
            total.update(link.health().errors)
        return total
