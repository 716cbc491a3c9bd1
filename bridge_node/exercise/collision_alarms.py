"""The collision alarm (issue 31): where two own ships' hulls touch, or an own ship and a
vessel the instructor steers (``WorldEvents.collisions``, ``sim_core.ship.collision``), each
own ship's bridge gets an alarm naming the other, with the impact's closing speed and the
energy it put into the hulls' structure (an NMEA alarm text: no commas, at most 52
characters). The alarm clears once they have been apart for ``CLEAR_S``, so that ships
lying alongside, or bumping along one another, raise it once.
"""
from __future__ import annotations

from collections.abc import Sequence

from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.links.hub import LinkHub
from bridge_node.links.messages import Alarm
from sim_core.frames.units import KNOT
from sim_core.ship.collision import ShipContact

COLLISION_ALARM = 310  # + the other own ship's index: the own ship touching that ship
VESSEL_COLLISION_ALARM = 330  # the own ship touching a vessel the instructor steers
CLEAR_S = 5.0  # s apart before the alarm clears


class CollisionAlarms(StepListener):
    """Raises on the own ships' hubs (by ship index; ``names`` as the other ships' traffic
    pictures show them) the alarm of a collision, and clears it when the bodies have been
    apart for ``CLEAR_S``; ``log`` keeps every collision's first contact: (the tick's clock
    s, the contact)."""

    def __init__(self, hubs: Sequence[LinkHub], names: Sequence[str]) -> None:
        self.hubs, self.names = list(hubs), list(names)
        self.touching: dict[tuple, tuple[float, str]] = {}  # bodies -> when they last touched (s), vessel's name
        self.log: list[tuple[float, ShipContact]] = []
        self.phase_name = "collision alarms"

    def on_step(self, outcome: TickOutcome) -> None:
        now = outcome.now
        vessels = dict(outcome.events.vessels)
        for contact in outcome.events.collisions:
            key = (contact.ships, contact.vessel)
            vessel = None if contact.vessel is None else vessels.get(contact.vessel)
            name = "" if vessel is None else vessel.name or f"MMSI {contact.vessel}"
            if key not in self.touching:
                self.log.append((now, contact))
                impact = f" {contact.closing_speed / KNOT:.1f} kn {contact.energy * 1e-6:.0f} MJ"
                self._raise(key, name, now, True, "collision with ", impact)
            self.touching[key] = (now, self.touching.get(key, (now, name))[1])
        for key, (last, name) in list(self.touching.items()):
            if now - last >= CLEAR_S:
                del self.touching[key]
                self._raise(key, name, now, False, "clear of ", "")

    def _raise(self, key: tuple, vessel: str, now: float, active: bool, before: str, after: str) -> None:
        """The alarm of a collision on each own ship's hub in it, the other body's name
        between ``before`` and ``after`` in its text."""
        ships, mmsi = key
        if mmsi is not None:
            (own,) = ships
            self.hubs[own].raise_alarm(Alarm(VESSEL_COLLISION_ALARM, f"{before}{vessel}{after}", active), now)
            return
        a, b = ships
        for own, other in ((a, b), (b, a)):
            text = f"{before}{self.names[other]}{after}"
            self.hubs[own].raise_alarm(Alarm(COLLISION_ALARM + other, text, active), now)
