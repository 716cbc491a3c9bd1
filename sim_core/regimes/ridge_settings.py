"""Ridge fields as a config draws them: ``[[ice_field.ridges]]``, a polygon holding parallel
ridges of one direction, spacing, sail, keel and keel rubble (``sim_core.regimes.rubble``)."""
from __future__ import annotations

import math

import shapely
from pydantic import Field, model_validator

from sim_core.params import Params
from sim_core.regimes.rubble import RidgeField
from sim_core.regimes.settings import Pair, check_polygon, local_corners


class RidgeFieldSettings(Params):
    """Parallel first-year ridges over a polygon (``polygon_m`` [east, north] m from the
    field's south-west corner, or ``polygon_deg`` [latitude, longitude]). Their lines run
    ``direction_deg`` (true, deg) and lie ``spacing_m`` apart, one of them through
    ``through_m`` (default: the polygon's centroid). The keel's rubble: angle of internal
    friction, cohesion and porosity (Dolgopolov et al. 1975; the defaults lie within what
    field measurements of first-year keels report)."""

    name: str = Field(min_length=1, max_length=64)
    polygon_m: list[Pair] | None = Field(None, description="[[east, north], ...] m")
    polygon_deg: list[Pair] | None = Field(None, description="[[latitude, longitude], ...] deg")
    direction_deg: float = Field(ge=0.0, lt=360.0, description="direction the ridge lines run, true, deg")
    spacing_m: float = Field(gt=0.0, le=100000.0, description="distance between ridge lines, m")
    through_m: Pair | None = Field(None, description="[east, north] m a ridge line passes through")
    width_m: float = Field(20.0, gt=1.0, le=200.0, description="keel width, m")
    sail_height_m: float = Field(1.5, ge=0.0, le=10.0, description="sail height above the level ice, m")
    keel_depth_m: float = Field(5.0, gt=0.0, le=40.0, description="keel depth below the sea surface, m")
    keel_friction_angle_deg: float = Field(35.0, ge=10.0, le=60.0, description="phi of the keel rubble, deg")
    keel_cohesion_kpa: float = Field(3.0, ge=0.0, le=50.0, description="c of the keel rubble, kPa")
    keel_porosity: float = Field(0.3, ge=0.05, le=0.6, description="e, the share of voids in the keel")

    @model_validator(mode="after")
    def _checked(self) -> "RidgeFieldSettings":
        check_polygon(self.polygon_m, self.polygon_deg)
        if self.width_m > self.spacing_m:
            raise ValueError(f"width_m {self.width_m:g} is wider than spacing_m {self.spacing_m:g}: the keels would "
                             "overlap")
        return self

    def ridges(self, lat0_deg: float, lon0_deg: float) -> RidgeField:
        """The ridge field in the local frame of an origin (degrees)."""
        polygon = shapely.Polygon(local_corners(self.polygon_m, self.polygon_deg, lat0_deg, lon0_deg))
        anchor = tuple(self.through_m) if self.through_m is not None else (polygon.centroid.x, polygon.centroid.y)
        return RidgeField(self.name, polygon, anchor, math.radians(90.0 - self.direction_deg), self.spacing_m,
                          self.width_m, self.sail_height_m, self.keel_depth_m,
                          math.radians(self.keel_friction_angle_deg), self.keel_cohesion_kpa * 1e3, self.keel_porosity)
