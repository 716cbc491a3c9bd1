"""The instructor's ``set_ice`` command as it travels: an area of the field and the ice to
lay over it, one of the exercise's ice classes by name (``SceneModel.class_names``: "open
water", "level ice 0.50 m", a floe field's egg code). Made into ``sim_core.instructor.SetIce``.

The area is given as a configured region's is (``sim_core.regimes.settings``), and checked
by the same rules. Only ice the ship has not met changes (see ``SetIce``); brash and ridges
stay where the exercise laid them. The names an exercise offers are those its field was
built with, and open water: a new thickness or egg code would need tile templates built,
which the tick does not wait for.
"""
from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from bridge_node.control.command_base import CommandBase
from sim_core.instructor import SetIce
from sim_core.regimes.settings import Pair, check_polygon, local_corners
from sim_core.world import WorldData, WorldModel

MAX_CORNERS = 64
MAX_NAME = 200  # an egg code of three ice types is named in about 100 characters


class SetIceCommand(CommandBase):
    """``polygon_m``: [[east, north], ...] m from the exercise origin, or ``polygon_deg``:
    [[latitude, longitude], ...]; 3 to 64 corners of a simple polygon, where the field lies
    now. ``ice``: the name of one of the exercise's ice classes."""

    command: Literal["set_ice"]
    polygon_m: list[Pair] | None = Field(None, max_length=MAX_CORNERS)
    polygon_deg: list[Pair] | None = Field(None, max_length=MAX_CORNERS)
    ice: str = Field(min_length=1, max_length=MAX_NAME)

    @model_validator(mode="after")
    def _one_simple_polygon(self) -> SetIceCommand:
        check_polygon(self.polygon_m, self.polygon_deg)
        if self.polygon_m is not None and not all(abs(v) <= 1.0e6 for corner in self.polygon_m for v in corner):
            raise ValueError("polygon_m: a corner farther than 1000 km from the exercise origin")
        return self

    def to_world(self, model: WorldModel, data: WorldData) -> SetIce:
        """The world's command (the control endpoint refuses a name the exercise lacks; the
        world applies such a command as nothing)."""
        lat0, lon0 = (math.degrees(a) for a in model.origin)
        corners = local_corners(self.polygon_m, self.polygon_deg, lat0, lon0)
        return SetIce(tuple((float(x), float(y)) for x, y in corners), self.ice)
