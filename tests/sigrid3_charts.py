"""SIGRID-3 charts written for tests with pyshp, in WGS 84: a polygon per feature with its
egg-code attributes (the two-character fields ice services publish)."""
from __future__ import annotations

from pathlib import Path

import shapefile

from bridge_node.charts.sigrid3 import FIELDS

WGS84_PRJ = ('GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]],'
             'PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]]')


def box_ring(lon0: float, lat0: float, lon1: float, lat1: float) -> list[list[float]]:
    """A closed clockwise ring (the shapefile's outer-ring order) of a lon/lat box."""
    return [[lon0, lat0], [lon0, lat1], [lon1, lat1], [lon1, lat0], [lon0, lat0]]


def write_chart(base: Path, features: list[tuple[list[list[float]], dict]], prj: str | None = WGS84_PRJ,
                fields: tuple[str, ...] = FIELDS) -> Path:
    """Write ``base``.shp/.shx/.dbf (and .prj unless None): one polygon per (ring, attributes),
    attributes missing from a feature left empty. Returns the .shp path."""
    with shapefile.Writer(str(base), shapeType=shapefile.POLYGON) as w:
        for name in fields:
            w.field(name, "C", size=2)
        for ring, attributes in features:
            w.poly([ring])
            w.record(*[attributes.get(name, "") for name in fields])
    if prj is not None:
        base.with_suffix(".prj").write_text(prj)
    return base.with_suffix(".shp")


# the issue's chart: ice free; 6/10 thin first-year medium floes; 9/10 of which 6/10 thick
# first-year small floes and 3/10 grey-white brash (three boxes west to east at 74 N 20 E)
ISSUE_CHART = [
    (box_ring(20.00, 74.000, 20.03, 74.018), {"POLY_TYPE": "W", "CT": "00"}),
    (box_ring(20.03, 74.000, 20.10, 74.018), {"POLY_TYPE": "I", "CT": "60", "SA": "87", "FA": "05"}),
    (box_ring(20.10, 74.000, 20.13, 74.018), {"POLY_TYPE": "I", "CT": "90", "CA": "60", "SA": "93", "FA": "04",
                                               "CB": "30", "SB": "85", "FB": "02"}),
]
