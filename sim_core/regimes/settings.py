"""Ice regions as a config draws them: ``[[ice_field.regions]]``, a polygon in local metres
or in degrees, a total concentration and its ice types (WMO names or codes)."""
from __future__ import annotations

import math
from typing import Annotated

import shapely
from pydantic import Field, field_validator, model_validator

from sim_core.frames.geodesy import geodetic_to_local
from sim_core.params import Params
from sim_core.regimes import wmo_codes
from sim_core.regimes.regime import IceRegime, IceRegion, make_regime


class IceTypeSettings(Params):
    """One ice type: partial concentration (tenths; a lone type may leave it out and takes
    the total), stage of development and floe size, each a WMO name or SIGRID-3 code."""

    concentration: float | None = Field(None, gt=0.0, le=10.0, description="partial concentration, tenths")
    stage: str | int = Field(description="stage of development: a WMO name (thin_first_year...) or code (87)")
    floe_size: str | int = Field(description="floe size: a WMO name (medium_floe...) or code (5)")

    @field_validator("stage")
    @classmethod
    def _stage(cls, value: str | int) -> int:
        return _code(value, wmo_codes.STAGES, wmo_codes.stage, "stage of development")

    @field_validator("floe_size")
    @classmethod
    def _floe_size(cls, value: str | int) -> int:
        return _code(value, wmo_codes.FLOE_SIZES, wmo_codes.floe_size, "floe size")


def _code(value: str | int, table: dict, lookup, what: str) -> int:
    if isinstance(value, str):
        return wmo_codes.code_by_name(value, table, what)
    return lookup(value).code


Pair = Annotated[list[float], Field(min_length=2, max_length=2)]


def check_polygon(polygon_m: list | None, polygon_deg: list | None) -> None:
    """ValueError unless exactly one of the two is given, with 3 corners or more, valid
    (not self-intersecting), and in degrees within [-89, 89] x [-180, 180]."""
    given = [p for p in (polygon_m, polygon_deg) if p is not None]
    if len(given) != 1:
        raise ValueError("give one polygon: polygon_m or polygon_deg")
    if len(given[0]) < 3:
        raise ValueError(f"a polygon has at least 3 corners, got {len(given[0])}")
    ring = shapely.Polygon(given[0])
    if not ring.is_valid:
        raise ValueError(f"invalid polygon: {shapely.is_valid_reason(ring)}")
    if polygon_deg is not None and any(abs(lat) > 89.0 or abs(lon) > 180.0 for lat, lon in polygon_deg):
        raise ValueError("polygon_deg: latitudes lie in [-89, 89], longitudes in [-180, 180]")


def local_corners(polygon_m: list | None, polygon_deg: list | None, lat0_deg: float,
                  lon0_deg: float) -> list[list[float]]:
    """A checked polygon's corners [east, north] m in the local frame of an origin (degrees)."""
    if polygon_m is not None:
        return polygon_m
    lat0, lon0 = math.radians(lat0_deg), math.radians(lon0_deg)
    return [list(geodetic_to_local(math.radians(lat), math.radians(lon), lat0, lon0)[::-1]) for lat, lon in polygon_deg]


class RegionSettings(Params):
    """A region of the field: its name, one polygon (``polygon_m``: [east, north] m from the
    field's south-west corner, or ``polygon_deg``: [latitude, longitude]), its total
    concentration (tenths) and ice types, thickest first. Later regions lie over earlier ones
    and over the chart."""

    name: str = Field(min_length=1, max_length=64)
    polygon_m: list[Pair] | None = Field(None, description="[[east, north], ...] m")
    polygon_deg: list[Pair] | None = Field(None, description="[[latitude, longitude], ...] deg")
    concentration: float = Field(ge=0.0, le=10.0, description="total concentration, tenths")
    ice: list[IceTypeSettings] = Field(default_factory=list, max_length=3, description="ice types, thickest first")
    brash_thickness: float | None = Field(None, gt=0.0, le=10.0, description=(
        "H_M, m: thickness of its brash (or pancakes) in mid channel; default: the thickest such type's nominal"))

    @model_validator(mode="after")
    def _checked(self) -> "RegionSettings":
        check_polygon(self.polygon_m, self.polygon_deg)
        self.regime()
        return self

    def regime(self) -> IceRegime:
        """The region's regime; ValueError where the concentrations or codes do not fit."""
        return make_regime(self.concentration, [(t.concentration, t.stage, t.floe_size) for t in self.ice])

    def region(self, lat0_deg: float, lon0_deg: float) -> IceRegion:
        """The region in the local frame of an origin (degrees)."""
        corners = local_corners(self.polygon_m, self.polygon_deg, lat0_deg, lon0_deg)
        regime = self.regime()
        return IceRegion(self.name, shapely.Polygon(corners), "ice" if regime.types else "water", regime,
                         self.brash_thickness)

