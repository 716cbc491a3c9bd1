"""The base of every instructor command as it travels (``bridge_node.control.commands``):
a JSON object checked field by field (pydantic: strict, nothing extra, no NaN), the refusal
that names the field, and positions given as latitude and longitude or north and east."""
from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field, model_validator

from sim_core.frames.geodesy import geodetic_to_local
from sim_core.world import WorldModel


class CommandError(ValueError):
    """A command refused: the message names the field, the value and what is allowed."""


class CommandBase(BaseModel):
    """A command's JSON object, checked whole."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False)


def local_position(model: WorldModel, latitude_deg: float, longitude_deg: float) -> tuple[float, float]:
    """A geographic position as (north, east) m from the exercise origin."""
    return geodetic_to_local(math.radians(latitude_deg), math.radians(longitude_deg), *model.origin)


class PlacedCommand(CommandBase):
    """A command with a position: latitude and longitude (deg), or north and east (m from
    the exercise origin: the field's south-west corner as laid; a drifting field moves on)."""

    latitude_deg: float | None = Field(None, ge=-89.0, le=89.0)
    longitude_deg: float | None = Field(None, ge=-180.0, le=180.0)
    north_m: float | None = Field(None, ge=-1.0e5, le=1.0e6)
    east_m: float | None = Field(None, ge=-1.0e5, le=1.0e6)

    @model_validator(mode="after")
    def _one_position(self) -> PlacedCommand:
        geographic = (self.latitude_deg is not None, self.longitude_deg is not None)
        local = (self.north_m is not None, self.east_m is not None)
        if not (all(geographic) and not any(local) or all(local) and not any(geographic)):
            raise ValueError("give latitude_deg and longitude_deg, or north_m and east_m")
        return self

    def north_east(self, model: WorldModel) -> tuple[float, float]:
        """The position in the field's frame, m."""
        if self.north_m is not None:
            return self.north_m, self.east_m
        return local_position(model, self.latitude_deg, self.longitude_deg)
