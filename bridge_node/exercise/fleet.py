"""Several own ships, each on its own bridge (issue 31): one tick steps them all in one ice
world, and each ship has its own links and arbitration (a ``LinkHub``), its own outputs and
alarms, and the other ships in its traffic picture.

``FleetOrders`` is the tick's order source: it polls every ship's hub, each of which
arbitrates its own links alone, so a console commands only its own ship and a bridge that
loses its link fails safe alone. The first ship's outputs go out as a single ship's do
(``LinkOutputs``); ``OtherShipOutputs`` sends each other ship's state and alarm changes on
its own hub's links, and ``FleetTraffic`` puts the other own ships into each ship's traffic
picture, where its AIS and DIS links send them and the state stream carries them.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from bridge_node.exercise.collision_alarms import CollisionAlarms
from bridge_node.exercise.order_refusals import OrderRefusals
from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.links.arbiter import Decision
from bridge_node.links.faults import LinkFault
from bridge_node.links.hub import LinkHub
from bridge_node.links.messages import Vessel
from sim_core.ship.outputs import ShipOutputs
from sim_core.world import WorldModel


@dataclass(frozen=True)
class Bridge:
    """One own ship's bridge: its links (opened by the caller), and how the other ships'
    traffic pictures show the ship (MMSI, name)."""

    hub: LinkHub
    mmsi: int
    name: str


class FleetOrders:
    """The order source of an exercise of several own ships: each ship's hub polled and
    arbitrated alone; the first ship's decision, with the others' in ``others``."""

    def __init__(self, bridges: Sequence[Bridge]) -> None:
        self.hubs = [b.hub for b in bridges]

    def poll(self, now: float) -> Decision:
        first, *others = (hub.poll(now) for hub in self.hubs)
        first.others = tuple(others)
        return first

    def fault_link(self, fault: LinkFault, now: float) -> None:
        for hub in self.hubs:  # link names are unique over the fleet: the one that has it
            hub.fault_link(fault, now)


def ship_outputs(outcome: TickOutcome, k: int) -> ShipOutputs:
    """The k-th ship's state as it is, from a tick's events (0: the first ship)."""
    events = outcome.events
    return events.ship if k == 0 else events.others[k - 1].outputs


class OtherShipOutputs(StepListener):
    """The k-th ship's (k >= 1) alarm changes (its links' and arbiter's, and its refused
    orders') raised on its own hub, and its state out on its links."""

    def __init__(self, hub: LinkHub, k: int) -> None:
        self.hub, self.k = hub, k
        self.refusals = OrderRefusals()
        self.phase_name = f"ship {k} outputs"

    def on_step(self, outcome: TickOutcome) -> None:
        report = outcome.events.others[self.k - 1]
        alarms = (*outcome.others[self.k - 1].alarms, *self.refusals.note(report.rejected, outcome.now))
        self.hub.publish(report.readings if outcome.send else None, outcome.now, alarms, truth=report.outputs)


class FleetTraffic(StepListener):
    """The other own ships into the k-th ship's traffic picture, as the last step left them,
    before its links send it."""

    def __init__(self, model: WorldModel, bridges: Sequence[Bridge], k: int) -> None:
        self.picture = bridges[k].hub.traffic
        self.k = k
        self.others = [(j, b, model.ships[j].particulars) for j, b in enumerate(bridges) if j != k]

    def on_step(self, outcome: TickOutcome) -> None:
        self.picture.fleet = [_vessel(ship_outputs(outcome, j), b, p.length, p.beam, outcome.now)
                              for j, b, p in self.others]


def _vessel(s: ShipOutputs, bridge: Bridge, length: float, beam: float, now: float) -> Vessel:
    return Vessel(f"ship:{bridge.mmsi}", bridge.mmsi, bridge.name, now, s.latitude, s.longitude, s.heading,
                  s.course_over_ground, s.speed_over_ground, s.rate_of_turn, length, beam)


def fleet_listeners(model: WorldModel, hub: LinkHub | None, bridges: Sequence[Bridge],
                    outputs: Callable[[LinkHub, int], StepListener] = OtherShipOutputs) -> list[StepListener]:
    """The collision alarms, every ship's traffic picture of the others, then the other
    ships' ``outputs`` (a listener of the k-th ship's hub, k >= 1; a replay's only send),
    before the first ship's, which the caller adds. Without ``bridges`` (one own ship):
    the collision alarms on ``hub`` (with the instructor's vessels), none without a hub."""
    if not bridges:
        return [CollisionAlarms([hub], [""])] if hub is not None else []
    return [CollisionAlarms([b.hub for b in bridges], [b.name for b in bridges]),
            *(FleetTraffic(model, bridges, k) for k in range(len(bridges))),
            *(outputs(b.hub, k) for k, b in enumerate(bridges) if k > 0)]
