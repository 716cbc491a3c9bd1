"""Instructor commands as they travel (JSON objects), checked field by field, and made into
the world's typed commands (``sim_core.instructor``) at the tick that applies them.

Each command is one JSON object with a ``command`` name and that command's fields, in the
units of the bridge (degrees, knots, metres, UTC):

========================  =========================================================
``freeze``, ``resume``    physics held (the clock stops) / running again
``reposition``            ``latitude_deg`` and ``longitude_deg``, or ``north_m`` and
                          ``east_m`` (from the exercise origin: the field's
                          south-west corner as laid);
                          ``heading_deg``; ``speed_kn`` (default 0)
``visibility``            ``visibility_m``
``clock``                 ``utc`` (ISO 8601), or ``time_of_day`` (HH:MM[:SS], UTC, the
                          exercise's date kept)
``wind``                  ``speed_kn``, ``from_deg``
``current``               ``speed_kn``, ``to_deg``
``steering_failure``      ``pumps_failed``: 0 (repaired), 1 (half the rate), 2 (stuck)
``engine_failure``        ``power_percent``: 100 (repaired) .. 0 (blackout)
``sensor_failure``        ``sensor`` and ``mode``: ``gyro`` ``ok``, ``frozen`` or ``offset``
                          (with ``offset_deg``); ``gnss`` ``ok``, ``lost`` or ``jumping``
                          (``jump_m``, default 200); ``log`` ``ok`` or ``frozen``
``link_fault``            ``link`` (a link's name), ``fault``: ``none`` (cleared),
                          ``disconnect``, ``drop``, ``corrupt``, ``duplicate``, ``delay``
                          (``delay_s``); ``probability`` (default 1)
``save``                  ``name``: the exercise's state now, a save point in the session
                          record's ``saves/NAME.json`` (``icebridge run --fork`` it)
``add_vessel``            ``mmsi``, ``name``, ``length_m``, ``beam_m``, a position (as
                          ``reposition``), ``course_deg``, ``speed_kn``
``move_vessel``           ``mmsi`` and a position
``steer_vessel``          ``mmsi``, ``course_deg``, ``speed_kn``
``remove_vessel``         ``mmsi``
``set_ice``               ``ice`` (one of the exercise's ice names: "open water",
                          "level ice 0.50 m", a floe field's egg code) over
                          ``polygon_m`` ([[east, north], ...], as a region's) or
                          ``polygon_deg`` ([[latitude, longitude], ...]) (``ice_command``)
========================  =========================================================

A command to a vessel the world does not have, or ice of a class it does not have (a
recorded command replayed on another exercise), is applied as nothing (the step does not
publish it).

A bad command is refused whole with a ``CommandError`` that names the field, the value and
what is allowed; nothing of it is applied.
"""
from __future__ import annotations

import dataclasses
import datetime as dt
import json
import math
from typing import Annotated, Literal

from pydantic import Field, TypeAdapter, ValidationError, model_validator

from bridge_node.control.command_base import CommandBase, CommandError, PlacedCommand
from bridge_node.control.ice_command import SetIceCommand
from bridge_node.control.save_point import SAVE_NAME, SaveRequest
from bridge_node.links.nmea0183.ais import SIX_BIT_TEXT
from bridge_node.links.faults import LINK_FAULT_KINDS, LinkFault
from sim_core.frames.units import KNOT
from sim_core.ice.hull_bodies import MAX_HULLS
from sim_core.instructor import (
    AddVessel,
    Command,
    EngineFailure,
    Freeze,
    MoveVessel,
    OtherVessel,
    RemoveVessel,
    Reposition,
    SetClock,
    SetEnvironment,
    SetIce,
    SteerVessel,
    SteeringFailure,
)
from sim_core.regimes.settings import check_polygon
from sim_core.ship.sensors import SENSOR_MODES, SensorFailure
from sim_core.world import WorldData, WorldModel

MAX_COMMAND_BYTES = 4096  # a command's JSON is a few hundred bytes; anything longer is refused unread


class FreezeCommand(CommandBase):
    command: Literal["freeze", "resume"]

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return Freeze(self.command == "freeze")


class ShipCommand(CommandBase):
    """A command to one own ship: ``ship`` 0 the first (``[ship]``), k the k-th of ``[[ships]]``."""

    ship: int = Field(0, ge=0, le=MAX_HULLS - 1)


class RepositionCommand(PlacedCommand, ShipCommand):
    command: Literal["reposition"]
    heading_deg: float = Field(ge=0.0, lt=360.0)
    speed_kn: float = Field(0.0, ge=0.0, le=25.0)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return Reposition(*self.north_east(model), math.radians(self.heading_deg), self.speed_kn * KNOT,
                          ship=self.ship)


Mmsi = Annotated[int, Field(ge=100_000_000, le=999_999_999)]


class AddVesselCommand(PlacedCommand):
    command: Literal["add_vessel"]
    mmsi: Mmsi
    name: str = Field("", max_length=20, pattern=SIX_BIT_TEXT)
    length_m: float = Field(ge=1.0, le=1022.0)
    beam_m: float = Field(ge=1.0, le=126.0)
    course_deg: float = Field(ge=0.0, lt=360.0)
    speed_kn: float = Field(0.0, ge=0.0, le=40.0)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        north, east = self.north_east(model)
        return AddVessel(self.mmsi, OtherVessel(self.name, north, east, math.radians(self.course_deg),
                                                self.speed_kn * KNOT, self.length_m, self.beam_m))


class MoveVesselCommand(PlacedCommand):
    command: Literal["move_vessel"]
    mmsi: Mmsi

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return MoveVessel(self.mmsi, *self.north_east(model))


class SteerVesselCommand(CommandBase):
    command: Literal["steer_vessel"]
    mmsi: Mmsi
    course_deg: float = Field(ge=0.0, lt=360.0)
    speed_kn: float = Field(ge=0.0, le=40.0)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return SteerVessel(self.mmsi, math.radians(self.course_deg), self.speed_kn * KNOT)


class RemoveVesselCommand(CommandBase):
    command: Literal["remove_vessel"]
    mmsi: Mmsi

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return RemoveVessel(self.mmsi)


class VisibilityCommand(CommandBase):
    command: Literal["visibility"]
    visibility_m: float = Field(ge=50.0, le=100_000.0)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return SetEnvironment((("visibility", float(self.visibility_m)),))


class ClockCommand(CommandBase):
    command: Literal["clock"]
    utc: dt.datetime | None = Field(None, strict=False)  # from its ISO 8601 text
    time_of_day: dt.time | None = Field(None, strict=False)  # from HH:MM[:SS]

    @model_validator(mode="after")
    def _one_time(self) -> ClockCommand:
        if (self.utc is None) == (self.time_of_day is None):
            raise ValueError("give utc (an ISO 8601 date and time) or time_of_day (HH:MM[:SS]), not both")
        if self.utc is not None and not dt.datetime(1970, 1, 2, tzinfo=dt.timezone.utc) <= \
                (self.utc if self.utc.tzinfo else self.utc.replace(tzinfo=dt.timezone.utc)) < \
                dt.datetime(2200, 1, 1, tzinfo=dt.timezone.utc):
            raise ValueError(f"utc {self.utc.isoformat()} is outside 1970-01-02 to 2200-01-01")
        return self

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        if self.utc is not None:
            utc = self.utc if self.utc.tzinfo else self.utc.replace(tzinfo=dt.timezone.utc)
            return SetClock(utc.timestamp())
        day = dt.datetime.fromtimestamp(data.epoch + data.time, dt.timezone.utc).date()
        t = self.time_of_day.replace(tzinfo=None)
        return SetClock(dt.datetime.combine(day, t, dt.timezone.utc).timestamp())


class WindCommand(CommandBase):
    command: Literal["wind"]
    speed_kn: float = Field(ge=0.0, le=100.0)
    from_deg: float = Field(ge=0.0, lt=360.0)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return SetEnvironment((("wind_speed", self.speed_kn * KNOT), ("wind_from", math.radians(self.from_deg))))


class CurrentCommand(CommandBase):
    command: Literal["current"]
    speed_kn: float = Field(ge=0.0, le=10.0)
    to_deg: float = Field(ge=0.0, lt=360.0)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return SetEnvironment((("current_speed", self.speed_kn * KNOT), ("current_to", math.radians(self.to_deg))))


class SteeringFailureCommand(ShipCommand):
    command: Literal["steering_failure"]
    pumps_failed: int = Field(ge=0, le=2)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return SteeringFailure(2 - self.pumps_failed, self.ship)


class EngineFailureCommand(ShipCommand):
    command: Literal["engine_failure"]
    power_percent: float = Field(ge=0.0, le=100.0)

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        return EngineFailure(self.power_percent / 100.0, self.ship)


class SensorFailureCommand(ShipCommand):
    command: Literal["sensor_failure"]
    sensor: Literal["gyro", "gnss", "log"]
    mode: Literal["ok", "frozen", "offset", "lost", "jumping"]
    offset_deg: float | None = Field(None, ge=-180.0, le=180.0)
    jump_m: float | None = Field(None, ge=10.0, le=2000.0)

    @model_validator(mode="after")
    def _mode_of_sensor(self) -> SensorFailureCommand:
        if self.mode not in SENSOR_MODES[self.sensor]:
            raise ValueError(f"mode {self.mode!r} is not one of the {self.sensor}'s: "
                             f"{', '.join(SENSOR_MODES[self.sensor])}")
        offset = (self.sensor, self.mode) == ("gyro", "offset")
        if offset != (self.offset_deg is not None):
            raise ValueError("offset_deg (-180 to 180) goes with sensor gyro and mode offset, and only there")
        if self.jump_m is not None and (self.sensor, self.mode) != ("gnss", "jumping"):
            raise ValueError("jump_m (10 to 2000) goes only with sensor gnss and mode jumping")
        return self

    def to_world(self, model: WorldModel, data: WorldData) -> Command:
        if self.mode == "offset":
            return SensorFailure(self.sensor, self.mode, math.radians(self.offset_deg), self.ship)
        if self.mode == "jumping":
            return SensorFailure(self.sensor, self.mode, 200.0 if self.jump_m is None else self.jump_m, self.ship)
        return SensorFailure(self.sensor, self.mode, ship=self.ship)


class LinkFaultCommand(CommandBase):
    command: Literal["link_fault"]
    link: str = Field(min_length=1, max_length=64)
    fault: Literal[LINK_FAULT_KINDS]
    probability: float = Field(1.0, ge=0.0, le=1.0)
    delay_s: float | None = Field(None, gt=0.0, le=10.0)

    @model_validator(mode="after")
    def _delay_with_delay(self) -> LinkFaultCommand:
        if (self.fault == "delay") != (self.delay_s is not None):
            raise ValueError("delay_s (0 to 10 s) goes with fault delay, and only there")
        return self

    def to_world(self, model: WorldModel, data: WorldData) -> LinkFault:
        """The fault, seeded with the step that applies it (a replay draws the same)."""
        return LinkFault(self.link, self.fault, self.probability, self.delay_s or 0.0, data.seq + 1)


class SaveCommand(CommandBase):
    command: Literal["save"]
    name: str = Field(pattern=SAVE_NAME)

    def to_world(self, model: WorldModel, data: WorldData) -> SaveRequest:
        return SaveRequest(self.name)


NodeCommand = LinkFault | SaveRequest  # applied by the node at a tick, not by the world
NODE_COMMANDS = (LinkFault, SaveRequest)
WireCommand = Annotated[FreezeCommand | RepositionCommand | VisibilityCommand | ClockCommand | WindCommand |
                        CurrentCommand | SteeringFailureCommand | EngineFailureCommand | SensorFailureCommand |
                        AddVesselCommand | MoveVesselCommand | SteerVesselCommand | RemoveVesselCommand |
                        LinkFaultCommand | SaveCommand | SetIceCommand, Field(discriminator="command")]
_WIRE = TypeAdapter(WireCommand)
COMMAND_NAMES = ("freeze", "resume", "reposition", "visibility", "clock", "wind", "current", "steering_failure",
                 "engine_failure", "sensor_failure", "link_fault", "save", "add_vessel", "move_vessel", "steer_vessel",
                 "remove_vessel", "set_ice")


def parse_command(message: dict) -> WireCommand:
    """A command checked whole; CommandError naming the field, value and what is allowed."""
    if not isinstance(message, dict) or message.get("command") not in COMMAND_NAMES:
        name = message.get("command") if isinstance(message, dict) else message
        raise CommandError(f"command {name!r}: unknown; allowed: {', '.join(COMMAND_NAMES)}")
    try:
        return _WIRE.validate_python(message)
    except ValidationError as exc:
        raise CommandError("; ".join(_explain(e) for e in exc.errors())) from None


def _explain(error: dict) -> str:
    """One pydantic error as 'field = value: what is allowed'."""
    where = ".".join(str(p) for p in error["loc"][1:]) or "command"
    value = error.get("input")
    shown = json.dumps(value) if isinstance(value, (int, float, str, bool)) or value is None else type(value).__name__
    text = error["msg"].removeprefix("Value error, ")
    if error["type"] == "missing":
        return f"{where}: missing (required)"
    return f"{where} = {shown}: {text}" if where != "command" else text


# -- the applied commands as records (session record, state stream) -----------------------
_ENVIRONMENT_FIELDS = {"visibility", "wind_speed", "wind_from", "current_speed", "current_to"}
_TYPES = {cls.__name__: cls for cls in (Freeze, Reposition, SetEnvironment, SetClock, SteeringFailure,
                                        EngineFailure, SensorFailure, AddVessel, MoveVessel, SteerVessel, RemoveVessel,
                                        SetIce, LinkFault, SaveRequest)}


def command_record(command: Command | NodeCommand) -> dict:
    """An applied world or node command as a JSON-able dict (SI values, exactly as applied)."""
    return {"type": type(command).__name__, **dataclasses.asdict(command)}


def command_from_record(record: dict) -> Command | NodeCommand:
    """The world or node command a record holds; CommandError for one that is not."""
    try:
        cls = _TYPES[record["type"]]
        fields = {k: v for k, v in record.items() if k != "type"}
        if cls is SetEnvironment:
            fields["changes"] = tuple((str(k), float(v)) for k, v in fields["changes"])
        if cls is AddVessel:
            fields["vessel"] = OtherVessel(**fields["vessel"])
        if cls is SetIce:
            fields["polygon"] = tuple((float(x), float(y)) for x, y in fields["polygon"])
            check_polygon(fields["polygon"], None)  # 3 corners or more, not self-intersecting
            if not isinstance(fields["ice"], str):
                raise ValueError(f"ice {fields['ice']!r} is not a name")
        command = cls(**fields)
        numbers = [v for v in _leaves(dataclasses.asdict(command)) if isinstance(v, float)]
        if not all(math.isfinite(v) for v in numbers) or \
                cls is SetEnvironment and not {k for k, _ in command.changes} <= _ENVIRONMENT_FIELDS or \
                cls is SensorFailure and command.mode not in SENSOR_MODES.get(command.sensor, ()) or \
                cls is LinkFault and (command.kind not in LINK_FAULT_KINDS or not 0.0 <= command.probability <= 1.0):
            raise ValueError("a value that is not finite, a field the environment lacks, or a kind unknown")
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise CommandError(f"not a command record: {record!r:.200} ({exc})") from None
    return command


def _leaves(value: object) -> list:
    """Every value in nested dicts, lists and tuples."""
    if isinstance(value, dict):
        return [leaf for v in value.values() for leaf in _leaves(v)]
    if isinstance(value, (list, tuple)):
        return [leaf for v in value for leaf in _leaves(v)]
    return [value]
