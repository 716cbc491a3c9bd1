"""Other vessels of the exercise (``[traffic]`` in the node config): AIS logs replayed as
traffic, and vessels scripted with waypoints or a start, course and speed. Positions are
north/east metres from the ice field's south-west corner (the exercise's local frame)."""
from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from bridge_node.links.nmea0183.ais import SIX_BIT_TEXT
from sim_core.params import Params, repeated

Metres = Annotated[float, Field(ge=-1.0e5, le=1.0e6)]
Point = Annotated[list[Metres], Field(min_length=2, max_length=2, description="[north, east] m")]


class ScriptedVessel(Params):
    """One scripted vessel (``[[traffic.vessels]]``): either ``waypoints``, steamed through
    in turn at ``speed_kn`` from the first (stopping at the last, or going round again
    with ``loop``), or a start ``north``/``east`` with ``course_deg`` and ``speed_kn``."""

    mmsi: int = Field(ge=100_000_000, le=999_999_999)
    name: str = Field("", max_length=20, pattern=SIX_BIT_TEXT)
    length: float = Field(gt=0.0, le=1022.0, description="m (AIS: at most 2 x 511)")
    beam: float = Field(gt=0.0, le=126.0, description="m (AIS: at most 2 x 63)")
    speed_kn: float = Field(ge=0.0, le=40.0, description="speed over ground, kn")
    waypoints: list[Point] = Field(default_factory=list, max_length=1000)
    loop: bool = Field(False, description="after the last waypoint, steam back to the first and round again")
    north: Metres | None = None
    east: Metres | None = None
    course_deg: float | None = Field(None, ge=0.0, lt=360.0, description="true course, deg")

    @model_validator(mode="after")
    def _one_way_to_move(self) -> ScriptedVessel:
        straight = (self.north, self.east, self.course_deg)
        if self.waypoints:
            if len(self.waypoints) < 2 or any(v is not None for v in straight):
                raise ValueError(f"vessel {self.mmsi}: give at least 2 waypoints, and then no north, east or "
                                 "course_deg")
        elif any(v is None for v in straight) or self.loop:
            raise ValueError(f"vessel {self.mmsi}: give waypoints, or north, east and course_deg (loop needs "
                             "waypoints)")
        return self


class TrafficSettings(Params):
    """``ais_logs``: NMEA/AIS logs (paths relative to the config file) whose other vessels
    are replayed from the start of the run; ``vessels``: the scripted ones."""

    ais_logs: list[Annotated[str, Field(min_length=1)]] = Field(default_factory=list, max_length=100)
    vessels: list[ScriptedVessel] = Field(default_factory=list, max_length=1000)

    @model_validator(mode="after")
    def _unique(self) -> TrafficSettings:
        doubled = repeated([v.mmsi for v in self.vessels])
        if doubled:
            raise ValueError(f"traffic.vessels: MMSIs must be unique, repeated: {doubled}")
        return self
