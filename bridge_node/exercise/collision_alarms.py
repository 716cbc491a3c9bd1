"""The collision alarm of several own ships (issue 31): where two hulls touch
(``WorldEvents.collisions``, ``sim_core.ship.collision``), each ship's bridge gets an alarm
naming the other ship, with the impact's closing speed and the energy it put into the
hulls' structure (an NMEA alarm text: no commas, at most 52 characters). The alarm clears
once the ships have been apart for ``CLEAR_S``, so that ships lying alongside, or bumping
along one another, raise it once.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.links.messages import Alarm
from sim_core.frames.units import KNOT
from sim_core.ship.collision import ShipContact

if TYPE_CHECKING:
    from bridge_node.exercise.fleet import Bridge

COLLISION_ALARM = 310  # + the other ship's index: the own ship touching that ship
CLEAR_S = 5.0  # s apart before the alarm clears


class CollisionAlarms(StepListener):
    """Raises on both ships' hubs the alarm of a pair of own ships that touch, and clears it
    when they have been apart for ``CLEAR_S``; ``log`` keeps every collision's first
    contact: (the tick's clock s, the ships' indices, the contact)."""

    def __init__(self, bridges: Sequence[Bridge]) -> None:
        self.bridges = list(bridges)
        self.touching: dict[tuple[int, int], float] = {}  # pair -> when it last touched (the tick's clock, s)
        self.log: list[tuple[float, tuple[int, int], ShipContact]] = []
        self.phase_name = "collision alarms"

    def on_step(self, outcome: TickOutcome) -> None:
        now = outcome.now
        for contact in outcome.events.collisions:
            if contact.ships not in self.touching:
                self.log.append((now, contact.ships, contact))
                impact = f" {contact.closing_speed / KNOT:.1f} kn {contact.energy * 1e-6:.0f} MJ"
                self._raise(contact.ships, now, True, "collision with ", impact)
            self.touching[contact.ships] = now
        for pair, last in list(self.touching.items()):
            if now - last >= CLEAR_S:
                del self.touching[pair]
                self._raise(pair, now, False, "clear of ", "")

    def _raise(self, pair: tuple[int, int], now: float, active: bool, before: str, after: str) -> None:
        """The alarm of ``pair`` on each of its ships' hubs, the other ship's name between
        ``before`` and ``after`` in its text."""
        a, b = pair
        for own, other in ((a, b), (b, a)):
            text = f"{before}{self.bridges[other].name}{after}"
            self.bridges[own].hub.raise_alarm(Alarm(COLLISION_ALARM + other, text, active), now)
