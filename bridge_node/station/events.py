"""The station's event log (instructor commands the world applied, refused orders, alarms
raised and cleared) and its alarms: what the stream and the control endpoint show."""
from __future__ import annotations

import datetime as dt
import math
import time
from collections import deque

from sim_core.frames.units import KNOT
from sim_core.instructor import (
    Command,
    EngineFailure,
    Freeze,
    Reposition,
    SetClock,
    SetEnvironment,
    SteeringFailure,
)
from sim_core.world import WorldEvents

LOG_MAX = 500  # events kept (a late browser gets these)
REFUSED_SHOWN_S = 10.0  # s a refused order stays among the alarms
_ENVIRONMENT = {"visibility": ("visibility", 1.0, "m"), "wind_speed": ("wind", 1.0 / KNOT, "kn"),
                "wind_from": ("wind from", 180.0 / math.pi, "deg"), "current_speed": ("current", 1.0 / KNOT, "kn"),
                "current_to": ("current to", 180.0 / math.pi, "deg")}


def describe(command: Command) -> tuple[str, str]:
    """The kind ("command", "failure") and one line of text of an applied world command."""
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
    return "command", type(command).__name__


class EventLog:
    """Events with increasing ids (the last ``LOG_MAX``), and the alarms now active."""

    def __init__(self) -> None:
        self._events: deque[dict] = deque(maxlen=LOG_MAX)
        self._next = 1
        self.steering = 2  # pumps working, as the last command seen set them
        self.power = 1.0
        self._refused: tuple[float, str] | None = None  # (monotonic, text) of the last refused order
        self._alarms: set[str] = set()

    def add(self, kind: str, text: str, sim_time: float | None = None, utc: float | None = None) -> None:
        """Log one event (``kind``: command, failure, order, alarm, cleared, station)."""
        self._events.append({"id": self._next, "kind": kind, "text": text, "time": sim_time,
                             "utc": None if utc is None else dt.datetime.fromtimestamp(utc, dt.timezone.utc)
                             .strftime("%H:%M:%S"), "wall": time.time()})
        self._next += 1

    def since(self, last_id: int) -> tuple[dict, ...]:
        """Events after ``last_id`` (the oldest kept if it was dropped)."""
        return tuple(e for e in self._events if e["id"] > last_id)

    def on_events(self, events: WorldEvents) -> None:
        """Log a step's applied commands and refused orders."""
        for command in events.commands:
            kind, text = describe(command)
            self.add(kind, text, events.time, events.ship.utc)
            if isinstance(command, SteeringFailure):
                self.steering = command.pumps
            elif isinstance(command, EngineFailure):
                self.power = command.power_share
        for rejection in events.rejected:
            text = f"{rejection.order} order {'refused' if rejection.refused else 'limited'}: {rejection.text}"
            if self._refused is None or self._refused[1] != text or time.monotonic() - self._refused[0] > 5.0:
                self.add("order", text, events.time, events.ship.utc)
            self._refused = (time.monotonic(), text)

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
        if self.steering < 2:
            active.append("steering gear: " + ("rudder stuck (both pumps failed)" if self.steering == 0
                                               else "one pump failed (half rate)"))
        if self.power < 1.0:
            active.append("engine: blackout" if self.power <= 0.0 else f"engine: {self.power * 100:.0f} % power")
        if self._refused is not None and time.monotonic() - self._refused[0] < REFUSED_SHOWN_S:
            active.append(f"order refused or limited: {self._refused[1]}")
        now = set(active)
        for text in sorted(now - self._alarms):
            self.add("alarm", text, sim_time, utc)
        for text in sorted(self._alarms - now):
            self.add("cleared", text, sim_time, utc)
        self._alarms = now
        return active
