"""The listeners a tick's outcome goes to, in one place: the links (alarm changes raised,
the ship's state out), the state stream (the render processes, the instructor station),
and, in a replay, the links run on the source's clock with the console's orders ignored.
The session record's tick log is ``bridge_node.node.tick_record.TickRecord``."""
from __future__ import annotations

import time

from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.links.base import Vessel
from bridge_node.links.hub import LinkHub
from bridge_node.stream.publisher import StatePublisher
from bridge_node.traffic.picture import TrafficPicture
from sim_core.frames.geodesy import local_to_geodetic


class LinkOutputs(StepListener):
    """Every alarm change of the step raised on the hub (announced with the next state sent),
    and the ship's state out on every link at the tick's clock: as its sensors read it to the
    instruments, as it is to other simulators."""

    def __init__(self, hub: LinkHub) -> None:
        self.hub = hub

    def clock(self, now: float) -> float:
        """The links' clock (monotonic s) at the tick's ``now``."""
        return now

    def on_step(self, outcome: TickOutcome) -> None:
        events = outcome.events
        self.hub.publish(events.readings if outcome.send else None, self.clock(outcome.now), outcome.alarms,
                         truth=events.ship)


class ReplayLinkOutputs(LinkOutputs):
    """A replay's links: they only send. The source's clock is moved to start at this
    process's monotonic clock (the links' own timers, a serial line's budget say, run on
    it), and the links are polled only to keep them up: a live console's orders are
    counted (``console_orders_ignored``) and dropped."""

    def __init__(self, hub: LinkHub) -> None:
        super().__init__(hub)
        self.console_orders_ignored = 0
        self._offset: float | None = None  # monotonic s - source clock s

    def clock(self, now: float) -> float:
        if self._offset is None:
            self._offset = time.monotonic() - now
        return now + self._offset

    def on_step(self, outcome: TickOutcome) -> None:
        if outcome.send:
            now = self.clock(outcome.now)
            for link in self.hub.links:
                self.console_orders_ignored += len(link.poll(now))
        super().on_step(outcome)


class WorldTraffic(StepListener):
    """The world's other vessels (the instructor's) into the traffic picture, placed on the
    field whose corner is at ``origin`` (latitude, longitude rad), before the links send it."""

    def __init__(self, picture: TrafficPicture, origin: tuple[float, float]) -> None:
        self.picture, self.origin = picture, origin

    def on_step(self, outcome: TickOutcome) -> None:
        out = []
        for mmsi, v in outcome.events.vessels:
            lat, lon = local_to_geodetic(v.north, v.east, *self.origin)
            out.append(Vessel(f"instructor:{mmsi}", mmsi, v.name, outcome.now, lat, lon, v.course, v.course,
                              v.speed, 0.0, v.length, v.beam))
        self.picture.world = out


class StreamOutput(StepListener):
    """Every step sent on the state stream with its input time and the traffic picture
    (placed on the field whose corner is at ``origin``, latitude and longitude rad)."""

    def __init__(self, publisher: StatePublisher, traffic: TrafficPicture | None,
                 origin: tuple[float, float]) -> None:
        self.publisher, self.traffic, self.origin = publisher, traffic, origin

    def on_step(self, outcome: TickOutcome) -> None:
        if outcome.send:
            table = self.traffic.table(self.origin) if self.traffic is not None else None
            self.publisher.publish(outcome.events, outcome.input_time, table)
