"""The listeners a tick's outcome goes to, in one place: the links (alarm changes raised,
the ship's state out), the state stream (the render processes, the instructor station),
and, in a replay, the links run on the source's clock with the console's orders ignored.
The session record's tick log is ``bridge_node.exercise.tick_record.TickRecord``; its save
points are written by ``SaveWriter``."""
from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path

from bridge_node.control.save_point import SAVES_FOLDER, SavePoint, state_of
from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.links.messages import Vessel
from bridge_node.links.hub import LinkHub
from bridge_node.common.errors import UserError
from bridge_node.common.output_files import write_output
from bridge_node.stream.publisher import StatePublisher
from bridge_node.links.traffic_picture import TrafficPicture
from sim_core.frames.geodesy import local_to_geodetic
from sim_core.world import WorldEvents


log = logging.getLogger(__name__)


class SaveWriter(StepListener):
    """Writes the save points asked for (``SaveRequest``) into the session record's
    ``saves/`` folder, on a thread of their own (the tick never waits for the disk)."""

    def __init__(self, record: Path) -> None:
        self.record = Path(record)
        self._writers: list[threading.Thread] = []

    def on_step(self, outcome: TickOutcome) -> None:
        events = outcome.events
        for request in outcome.saves:
            point = SavePoint(str(self.record.resolve()), events.seq, events.time, state_of(events))
            path = self.record / SAVES_FOLDER / f"{request.name}.json"
            writer = threading.Thread(target=self._write, args=(path, point.as_json()), name="icebridge-save")
            writer.start()
            self._writers.append(writer)

    @staticmethod
    def _write(path: Path, text: str) -> None:
        try:
            path.parent.mkdir(exist_ok=True)
            write_output(path, text, "save point")
            log.info("save point %s written", path)
        except (OSError, UserError) as exc:
            log.error("save point %s not written: %s", path, exc)

    def stop(self) -> None:
        for writer in self._writers:
            writer.join()


class LinkOutputs(StepListener):
    """Every alarm change of the step raised on the hub (announced with the next state sent),
    and the ship's state out on every link at the tick's clock: as its sensors read it to the
    instruments, as it is to other simulators. ``ship`` k > 0: the k-th other own ship's
    state on its own hub; its alarms are its hub's own."""

    def __init__(self, hub: LinkHub, ship: int = 0) -> None:
        self.hub, self.ship = hub, ship

    def clock(self, now: float) -> float:
        """The links' clock (monotonic s) at the tick's ``now``."""
        return now

    def on_step(self, outcome: TickOutcome) -> None:
        events = outcome.events
        if self.ship:
            report = events.others[self.ship - 1]
            state, truth, alarms = report.readings, report.outputs, ()
        else:
            state, truth, alarms = events.readings, events.ship, outcome.alarms
        self.hub.publish(state if outcome.send else None, self.clock(outcome.now), alarms, truth=truth)


class ReplayLinkOutputs(LinkOutputs):
    """A replay's links: they only send. The source's clock is moved to start at this
    process's monotonic clock (the links' own timers, a serial line's budget say, run on
    it), and the links are polled only to keep them up: a live console's orders are
    counted (``console_orders_ignored``) and dropped."""

    def __init__(self, hub: LinkHub, ship: int = 0) -> None:
        super().__init__(hub, ship)
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
    (placed on the field whose corner is at ``origin``, latitude and longitude rad). A
    step carries only the floes that changed since they were last published, so after a
    step the publisher could not take (``StatePublisher.dropped``) the whole state goes
    instead of the next one (``resync``: ``sim_core.world.snapshot``): else the publisher's
    view, which late joiners start from, would miss that step's changes for good."""

    def __init__(self, publisher: StatePublisher, traffic: TrafficPicture | None,
                 origin: tuple[float, float], resync: Callable[[], WorldEvents]) -> None:
        self.publisher, self.traffic, self.origin, self.resync = publisher, traffic, origin, resync
        self._behind = False

    def on_step(self, outcome: TickOutcome) -> None:
        if outcome.send:
            table = self.traffic.table(self.origin) if self.traffic is not None else None
            dropped = self.publisher.dropped
            self.publisher.publish(self.resync() if self._behind else outcome.events, outcome.input_time, table)
            self._behind = self.publisher.dropped > dropped
