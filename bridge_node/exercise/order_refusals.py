"""Orders the ship clamped or refused (``WorldEvents.rejected``): logged, counted for the
run summary, and raised as an alarm when one order channel is refused repeatedly.

A console that sends a bad order once may have glitched; one that keeps sending orders the
ship refuses (an unknown telegraph code, a NaN rudder) has a fault the officer must know
about, because the ship keeps its previous order. Clamped orders (beyond the rudder or lever
limit) are counted but raise no alarm: the ship obeys them as far as it can. Refused
searchlight orders (an aim outside the mount's range, a light the ship lacks) are counted and
logged, with no alarm: the light holds its last aim, and the officer sees where it points.
"""
from __future__ import annotations

import logging
from collections import Counter, deque

from bridge_node.links.messages import Alarm
from sim_core.ship.model import OrderRejection

log = logging.getLogger("icebridge.orders")
REFUSED_ALARM = {"rudder": 121, "telegraph": 122, "lever": 122}  # alarm number per order channel
REFUSED_TEXT = {121: "rudder orders refused repeatedly", 122: "engine orders refused repeatedly"}
REFUSALS_FOR_ALARM = 3  # refusals of one channel within the window raise its alarm
WINDOW_S = 10.0  # s; the alarm clears after a window without a refusal


class OrderRefusals:
    """Counts by order and outcome, and the refused-order alarms."""

    def __init__(self) -> None:
        self.counts: Counter = Counter()  # "rudder clamped", "telegraph refused", ...
        self._recent: dict[int, deque] = {n: deque() for n in set(REFUSED_ALARM.values())}
        self._raised: set[int] = set()
        self._logged: set[str] = set()

    def note(self, rejections: tuple[OrderRejection, ...], now: float) -> list[Alarm]:
        """Record one step's rejections at ``now`` (monotonic s); returns alarm changes."""
        for r in rejections:
            self.counts[f"{r.order} {'refused' if r.refused else 'clamped'}"] += 1
            if r.text not in self._logged:  # each distinct reason once; the counts keep the rest
                self._logged.add(r.text)
                log.warning("order %s: %s", "refused" if r.refused else "clamped", r.text)
            if r.refused and r.order in REFUSED_ALARM:
                self._recent[REFUSED_ALARM[r.order]].append((now, r.text))
        changes = []
        for number, recent in self._recent.items():
            while recent and now - recent[0][0] > WINDOW_S:
                recent.popleft()
            if len(recent) >= REFUSALS_FOR_ALARM and number not in self._raised:
                self._raised.add(number)
                changes.append(Alarm(number, REFUSED_TEXT[number], True))  # the reasons are logged above
            elif not recent and number in self._raised:
                self._raised.discard(number)
                changes.append(Alarm(number, "refused orders stopped", False))
        return changes
