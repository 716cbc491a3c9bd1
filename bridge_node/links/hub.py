"""All configured links together, fanned out like python-can's ``Notifier``.

Each tick has two phases. ``poll`` polls every link, arbitrates the orders, and returns
them with the alarm changes they bring (the arbiter's, and a link-down alarm per link): an
order source of the exercise's one tick (``bridge_node.exercise.tick``), which gathers every
alarm change of a step. ``publish`` raises the tick's alarm changes, sends the ship state
and the other vessels the links hear of (from DIS) on every link, announces the pending
alarm changes (and every active alarm again each ``ALARM_REPEAT_S``), and flushes the
listeners. With a convoy configured it tracks the convoy's ships in the traffic picture
(``bridge_node.links.convoy``): the links send them, and their distance alarms are raised. The links' raw traffic goes to the hub's
listeners; given a record folder, the hub adds a ``SessionRecord``.
"""
from __future__ import annotations

import logging
import math
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from bridge_node.links.arbiter import Decision, OrderArbiter
from bridge_node.links.convoy import ConvoySettings, ConvoyTarget, ConvoyWatch, convoy_targets
from bridge_node.links.base import OPEN_WAIT_S, Link
from bridge_node.links.messages import Alarm, ControlInput, Listener
from bridge_node.links.faults import LinkFault
from bridge_node.links.registry import make_link
from bridge_node.links.session_record import SessionRecord
from bridge_node.links.settings import ArbitrationSettings, LinkSettingsBase
from bridge_node.links.traffic_picture import TrafficPicture
from sim_core.ship.outputs import ShipOutputs

log = logging.getLogger("icebridge.links")
LINK_DOWN_ALARM = 200  # + the link's index
RECORD_ALARM = 299  # the session record could not be written (a full disk)
ALARM_REPEAT_S = 10.0  # active alarms are announced again this often, s


class LinkHub:
    """The node's links, the arbiter, the alarms and the traffic listeners."""

    def __init__(self, links: Sequence[LinkSettingsBase], arbitration: ArbitrationSettings,
                 record_dir: Path | None = None, traffic: TrafficPicture | None = None,
                 made: Sequence[Link] | None = None, convoy: ConvoySettings | None = None) -> None:
        """The links made from ``links``' settings, or ``made``: links already made (a
        session re-simulation's, which read a record; the settings then give the
        arbitration its sources' timeouts); with ``convoy``, the convoy watch."""
        self.links = list(made) if made is not None else [make_link(s) for s in links]
        self.traffic = traffic or TrafficPicture()
        self.arbiter = OrderArbiter(arbitration, {s.name: s.timeout_s for s in links})
        self.record_dir = record_dir
        self.record: SessionRecord | None = None  # while open with a record folder
        self.listeners: list[Listener] = []
        self.active_alarms: dict[int, Alarm] = {}
        self.alarm_log: list[tuple[float, Alarm]] = []  # (monotonic s, alarm change)
        self.last_orders: dict[str, ControlInput] = {}  # "source/kind/engine" -> latest order
        self.order_counts: Counter = Counter()  # "source/kind/engine" -> orders received
        self._pending: list[Alarm] = []  # alarm changes not yet announced
        self._down: set[int] = set()  # link-down alarms this hub's polls have raised
        self._last_announce = -math.inf
        self.convoy = ConvoyWatch(convoy) if convoy is not None else None
        self.convoy_targets: list[ConvoyTarget] = []  # as last published

    def add_listener(self, listener: Listener) -> None:
        """Give ``listener`` the raw traffic of every link; it is stopped when the hub closes."""
        self.listeners.append(listener)
        for link in self.links:
            link.add_listener(listener)

    def open(self) -> None:
        """Start the session record (with a record folder), then open every link."""
        if self.record_dir is not None and self.record is None:
            self.record = SessionRecord(self.record_dir)
            self.add_listener(self.record)
        for link in self.links:  # all at once: each may take seconds (python-can's slcan sleeps 2 s)
            link.begin_open()
        deadline = time.monotonic() + OPEN_WAIT_S
        for link in self.links:
            link.await_open(max(0.0, deadline - time.monotonic()))

    def close(self) -> None:
        """Close every link, then stop and drop the listeners; safe to call twice."""
        try:
            for link in self.links:
                link.close()
        finally:
            listeners, self.listeners, self.record = self.listeners, [], None
            for listener in listeners:
                for link in self.links:
                    link.remove_listener(listener)
                listener.stop()

    def __enter__(self) -> LinkHub:
        try:
            self.open()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def poll(self, now: float) -> Decision:
        """Phase 1 at ``now`` (monotonic s): poll every link, arbitrate, collect alarm changes;
        returns the orders for the ship."""
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
        for i, link in enumerate(self.links):  # raised only after a real failure, not while a link starts
            number, down = LINK_DOWN_ALARM + i, link.failed
            if down != (number in self._down):
                self._down.symmetric_difference_update({number})
                decision.alarms.append(Alarm(number, link.down_text() if down else f"link {link.name} up", down))
        return decision

    def fault_link(self, fault: LinkFault, now: float) -> None:
        """Put the instructor's ``fault`` on the link it names (none: nothing)."""
        for link in self.links:
            if link.name == fault.link:
                link.set_fault(fault, now)

    def raise_alarm(self, alarm: Alarm, now: float) -> None:
        """Raise (``alarm.active``) or clear an alarm; it is announced at the next ``publish``."""
        self.alarm_log.append((now, alarm))
        self._pending.append(alarm)
        if alarm.active:
            self.active_alarms[alarm.number] = alarm
            log.warning("alarm %03d: %s", alarm.number, alarm.text)
        else:
            self.active_alarms.pop(alarm.number, None)
            log.info("alarm %03d cleared: %s", alarm.number, alarm.text)

    def publish(self, state: ShipOutputs | None, now: float, alarms: Sequence[Alarm] = (),
                truth: ShipOutputs | None = None) -> None:
        """Phase 2 at ``now`` (monotonic s): raise ``alarms`` (the tick's alarm changes), send
        the state (None: nothing but the alarms, as while a replay runs ahead; ``state`` is
        what the sensors read, ``truth`` the ship as it is, for links to other simulators,
        default ``state``) and the alarm changes on every link, and flush the listeners."""
        for alarm in alarms:
            self.raise_alarm(alarm, now)
        if state is None:
            return
        vessels = self.traffic.gather([v for link in self.links for v in link.vessels(now)], now)
        if self.convoy is not None:
            self.convoy_targets = convoy_targets(state, vessels, self.convoy.settings)
            for alarm in self.convoy.changes(self.convoy_targets):
                self.raise_alarm(alarm, now)
        changes, self._pending = self._pending, []
        if now - self._last_announce >= ALARM_REPEAT_S:
            self._last_announce = now
            changes += [a for a in self.active_alarms.values() if a not in changes]
        for link in self.links:
            link.publish_targets(self.convoy_targets, now)
            link.publish(truth if link.simulator_peer and truth is not None else state, now)
            link.publish_vessels(vessels, now)
            for alarm in changes:
                link.publish_alarm(alarm, now)
        for listener in self.listeners:
            listener.flush()
        if self.record is not None and self.record.failed and RECORD_ALARM not in self.active_alarms:
            self.raise_alarm(Alarm(RECORD_ALARM, "session record stopped (see the log)", True), now)

    def errors(self) -> Counter:
        """Error counts by kind, summed over the links."""
        total = Counter()
        for link in self.links:
            total.update(link.health().errors)
        return total
