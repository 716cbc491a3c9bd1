"""The station's event log (instructor commands the world applied, refused orders, alarms
raised and cleared, links going down and up) and its alarms: what the stream and the
control endpoint's status replies show."""
from __future__ import annotations

import datetime as dt
import math
import time
from collections import deque

import numpy as np

from bridge_node.control.save_point import SaveRequest
from bridge_node.links.faults import LinkFault
from bridge_node.station.failures import SENSOR_TEXT, FleetFailures
from sim_core.frames.units import KNOT
from sim_core.instructor import (
    Command,
    EngineFailure,
    Freeze,
    Reposition,
    SetClock,
    SetEnvironment,
    SetIce,
    SteeringFailure,
)
from sim_core.ship.sensors import SensorFailure
from sim_core.world import WorldEvents

LOG_MAX = 500  # events kept (a late browser gets these)
REFUSED_SHOWN_S = 10.0  # s a refused order stays among the alarms
_ENVIRONMENT = {"visibility": ("visibility", 1.0, "m"), "wind_speed": ("wind", 1.0 / KNOT, "kn"),
                "wind_from": ("wind from", 180.0 / math.pi, "deg"), "current_speed": ("current", 1.0 / KNOT, "kn"),
                "current_to": ("current to", 180.0 / math.pi, "deg")}
SENSOR_NAMES = {"gyro": "gyro", "gnss": "GNSS", "log": "speed log"}


def _sensor_text(failure: SensorFailure) -> str:
    if failure.mode == "ok":
        return f"{SENSOR_NAMES.get(failure.sensor, failure.sensor)} repaired"
    text = "sensor failure: " + SENSOR_TEXT.get((failure.sensor, failure.mode), f"{failure.sensor} {failure.mode}")
    if (failure.sensor, failure.mode) == ("gyro", "offset"):
        return f"{text} {math.degrees(failure.amount):+.1f} deg"
    return f"{text} {failure.amount:.0f} m" if (failure.sensor, failure.mode) == ("gnss", "jumping") else text


def _link_fault_text(fault: LinkFault) -> str:
    if fault.kind == "none":
        return f"link {fault.link}: fault cleared"
    if fault.kind == "disconnect":
        return f"link {fault.link}: fault disconnect"
    delay = f", {fault.delay_s:g} s" if fault.kind == "delay" else ""
    return f"link {fault.link}: fault {fault.kind} (probability {fault.probability:g}{delay})"


def describe(command: Command | LinkFault | SaveRequest) -> tuple[str, str]:
    """The kind ("command", "failure") and one line of text of an applied world command, or
    of a node command of a session record (a link fault, a save point); a command to
    another own ship than the first names it (``ship 1: ...``)."""
    kind, text = _describe(command)
    ship = getattr(command, "ship", 0)
    return kind, f"ship {ship}: {text}" if ship else text


def _describe(command: Command | LinkFault | SaveRequest) -> tuple[str, str]:
    if isinstance(command, Freeze):
        return "command", "exercise frozen" if command.frozen else "exercise resumed"
    if isinstance(command, Reposition):
        return "command", (f"ship repositioned to N {command.north:.0f} m, E {command.east:.0f} m, heading "
                           f"{math.degrees(command.heading):.0f} deg, {command.speed / KNOT:.1f} kn")
    if isinstance(command, SetEnvironment):
        parts = [f"{_ENVIRONMENT[k][0]} {v * _ENVIRONMENT[k][1]:.4g} {_ENVIRONMENT[k][2]}"
                 if k in _ENVIRONMENT else f"{k} {v:.4g}" for k, v in command.changes]
        return "command", "set " + ", ".join(parts)
    if isinstance(command, SetClock):
        return "command", "clock set to " + dt.datetime.fromtimestamp(command.utc, dt.timezone.utc).isoformat(
            timespec="seconds")
    if isinstance(command, SteeringFailure):
        text = {2: "steering gear repaired (both pumps)", 1: "steering failure: one pump (half rate)",
                0: "steering failure: both pumps (rudder stuck)"}.get(command.pumps, f"steering pumps {command.pumps}")
        return "failure", text
    if isinstance(command, EngineFailure):
        share = command.power_share
        text = "engine repaired (full power)" if share >= 1.0 else (
            "engine failure: blackout" if share <= 0.0 else f"engine failure: power limited to {share * 100:.0f} %")
        return "failure", text
    if isinstance(command, SensorFailure):
        return "failure", _sensor_text(command)
    if isinstance(command, LinkFault):
        return "failure", _link_fault_text(command)
    if isinstance(command, SaveRequest):
        return "command", f"save point {command.name}"
    if isinstance(command, SetIce):
        (x0, y0), (x1, y1) = np.min(command.polygon, axis=0), np.max(command.polygon, axis=0)
        return "command", f"{command.ice} laid over E {x0:.0f}-{x1:.0f} m, N {y0:.0f}-{y1:.0f} m"
    return "command", type(command).__name__


def _fault(health: dict | None) -> str | None:
    fault = None if health is None else health.get("fault")
    return None if fault == "none" else fault


def link_changes(before: dict | None, now: dict) -> list[tuple[str, str]]:
    """The events (kind, text) between two status replies' health of one link: down (with
    its last error) or up, and its fault put on or cleared. ``before`` None: the link is
    first seen, and only a link down (not being opened) or with a fault is news."""
    name, up = now.get("name"), bool(now.get("connected"))
    events = []
    if (not up and not now.get("opening")) if before is None else bool(before.get("connected")) != up:
        error = now.get("last_error")
        events.append(("cleared", f"link {name} up") if up else
                      ("alarm", f"link {name} down" + (f": {error}" if error else "")))
    if _fault(now) != _fault(before):
        events.append(("failure", f"link {name}: fault {_fault(now)}" if _fault(now) else f"link {name}: fault cleared"))
    return events


class EventLog:
    """Events with increasing ids (the last ``LOG_MAX``), and the alarms now active."""

    def __init__(self) -> None:
        self._events: deque[dict] = deque(maxlen=LOG_MAX)
        self._next = 1
        self.failures = FleetFailures()
        self._status: dict | None = None  # the last status reply taken
        self.links: dict[str, dict] = {}  # name -> health, as the last status reply gave it
        self._node_alarms: list[str] = []
        self._refused: tuple[float, str] | None = None  # (monotonic, text) of the last refused order
        self._alarms: set[str] = set()

    def add(self, kind: str, text: str, sim_time: float | None = None, utc: float | None = None) -> None:
        """Log one event (``kind``: command, failure, order, alarm, cleared, station)."""
        self._events.append({"id": self._next, "kind": kind, "text": text, "time": sim_time,
                             "utc": None if utc is None else dt.datetime.fromtimestamp(utc, dt.timezone.utc)
                             .strftime("%H:%M:%S"), "wall": time.time()})
        self._next += 1

    def joined(self, seq: int, sim_time: float, utc: float) -> None:
        """The station joined a node's stream (anew: the node may have restarted): logged, and
        the node's next status reply is taken for its failures."""
        self.failures.rejoined()
        self.add("station", f"joined the state stream at step {seq}", sim_time, utc)

    def since(self, last_id: int) -> tuple[dict, ...]:
        """Events after ``last_id`` (the oldest kept if it was dropped)."""
        return tuple(e for e in self._events if e["id"] > last_id)

    def on_events(self, events: WorldEvents) -> None:
        """Log a step's applied commands and refused orders."""
        for command in events.commands:
            kind, text = describe(command)
            self.add(kind, text, events.time, events.ship.utc)
            self.failures.note(command, events.seq)
        for rejection in events.rejected:
            text = f"{rejection.order} order {'refused' if rejection.refused else 'limited'}: {rejection.text}"
            if self._refused is None or self._refused[1] != text or time.monotonic() - self._refused[0] > 5.0:
                self.add("order", text, events.time, events.ship.utc)
            self._refused = (time.monotonic(), text)

    def on_status(self, status: dict | None, sim_time: float | None = None, utc: float | None = None) -> None:
        """Take a status reply of the node (each once): its ships' failures (``FleetFailures``),
        its alarms, and its links' health, logging a link that went down or up or
        whose fault changed. A node without some of these fields keeps what was known."""
        if status is None or status is self._status:
            return
        self._status = status
        self.failures.take(status)
        self._node_alarms = [f"node alarm {a.get('number')}: {a.get('text')}" for a in status.get("alarms", [])]
        links = {str(h.get("name")): h for h in status.get("links", [])}
        for name, health in links.items():
            for kind, text in link_changes(self.links.get(name), health):
                self.add(kind, text, sim_time, utc)
        self.links = links

    def alarms(self, stream_age_s: float | None, control_error: str | None, sim_time: float | None = None,
               utc: float | None = None) -> list[str]:
        """The active alarms; a change is logged (raised / cleared) at the given exercise time."""
        active = []
        if stream_age_s is None:
            active.append("no state from the node yet")
        elif stream_age_s > 2.0:
            active.append("state stream silent")
        if control_error:
            active.append(f"control endpoint: {control_error}")
        active += self.failures.alarms()
        if self._refused is not None and time.monotonic() - self._refused[0] < REFUSED_SHOWN_S:
            active.append(f"order refused or limited: {self._refused[1]}")
        active += self._node_alarms
        now = set(active)
        for text in sorted(now - self._alarms):
            self.add("alarm", text, sim_time, utc)
        for text in sorted(self._alarms - now):
            self.add("cleared", text, sim_time, utc)
        self._alarms = now
        return active
