"""SIGRID-3 ice charts (WMO, JCOMM Technical Report No. 23): the shapefile ice services
publish, read with pyshp, its projection (the ``.prj``) taken by pyproj to WGS 84, and its
polygons put into the exercise's local frame (x east, y north, m).

Attributes read: POLY_TYPE (I or S ice, W water, L land, N no data), CT (total
concentration), and per ice type A, B, C the partial concentration (CA, CB, CC), stage of
development (SA, SB, SC) and floe size (FA, FB, FC). Codes are checked against
``sim_core.regimes.wmo_codes``. Any fault is a ChartError naming the file, the feature
(1-based, as GIS tools number them) and the field.
"""
from __future__ import annotations

import logging
import math
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyproj
import shapefile
import shapely
from shapely.geometry import shape as geo_shape

from bridge_node.common.errors import UserError
from sim_core.frames.geodesy import geodetic_to_local
from sim_core.regimes import wmo_codes
from sim_core.regimes.regime import IceRegime, IceRegion, RegionKind, make_regime

FIELDS = ("POLY_TYPE", "CT", "CA", "SA", "FA", "CB", "SB", "FB", "CC", "SC", "FC")
KINDS: dict[str, RegionKind] = {"I": "ice", "S": "ice", "W": "water", "L": "land", "N": "no_data"}
POLYGON_TYPES = (shapefile.POLYGON, shapefile.POLYGONZ, shapefile.POLYGONM)
MAX_LATITUDE = 89.0  # deg: the local tangent plane's reach (as [exercise] origin_latitude_deg)
# pyshp logs its doubts about a ring's orientation to stderr; the polygon checks below say
# what is wrong with a feature, once, as an error
logging.getLogger("shapefile").setLevel(logging.ERROR)


class ChartError(UserError):
    """A chart that cannot be read or holds a fault; the message names file, feature, field."""


@dataclass(frozen=True)
class ChartFeature:
    """One polygon of a chart: its name, kind, regime, geometry (lon, lat, degrees) and where
    it is (file and feature)."""

    name: str
    kind: RegionKind
    regime: IceRegime
    geometry: shapely.Geometry
    where: str  # the file and feature, for messages


def read_chart(path: str | Path) -> list[ChartFeature]:
    """The features of a SIGRID-3 chart (the ``.shp``; its ``.dbf``, ``.shx`` and ``.prj``
    beside it), in WGS 84 longitude and latitude. ChartError for any fault."""
    path = Path(path)
    if path.is_dir():
        raise ChartError(f"{path}: is a directory; give the chart's .shp file")
    if not path.is_file():
        raise ChartError(f"{path}: no such file")
    if path.stat().st_size == 0:
        raise ChartError(f"{path}: empty file; a SIGRID-3 chart is an ESRI shapefile")
    to_wgs84 = _projection(path)
    try:
        reader = shapefile.Reader(str(path))
    except (shapefile.ShapefileException, OSError, ValueError, UnicodeDecodeError) as exc:
        raise ChartError(f"{path}: not a readable shapefile: {exc}") from None
    with reader:
        if reader.shapeType not in POLYGON_TYPES:
            raise ChartError(f"{path}: holds {reader.shapeTypeName} shapes; an ice chart holds polygons")
        names = [f[0].upper() for f in reader.fields[1:]]
        missing = [f for f in FIELDS if f not in names]
        if missing:
            raise ChartError(f"{path}: no attribute {', '.join(missing)}; a SIGRID-3 chart has {', '.join(FIELDS)}")
        try:
            rows = list(reader.iterShapeRecords())
        except (shapefile.ShapefileException, OSError, ValueError, struct.error) as exc:
            raise ChartError(f"{path}: damaged shapefile: {exc}") from None
    if not rows:
        raise ChartError(f"{path}: the chart holds no features")
    return [_feature(path, n, row.shape, dict(zip(names, row.record)), to_wgs84)
            for n, row in enumerate(rows, start=1)]


def chart_regions(features: list[ChartFeature], lat0_deg: float, lon0_deg: float) -> list[IceRegion]:
    """The chart's features as regions in the local frame of an origin (degrees)."""
    lat0, lon0 = math.radians(lat0_deg), math.radians(lon0_deg)

    def local(lonlat: np.ndarray) -> np.ndarray:
        lon = lon0_deg + (lonlat[:, 0] - lon0_deg + 180.0) % 360.0 - 180.0  # the near side of 180 deg
        north, east = geodetic_to_local(np.radians(lonlat[:, 1]), np.radians(lon), lat0, lon0)
        return np.column_stack([east, north])
    regions = [IceRegion(f.name, shapely.transform(f.geometry, local), f.kind, f.regime) for f in features]
    for feature, region in zip(features, regions):
        if not shapely.is_valid(region.polygon) or region.polygon.is_empty:
            raise ChartError(f"{feature.where}: not a valid polygon in the exercise's local frame "
                             f"({shapely.is_valid_reason(region.polygon)}): does it wind round a pole?")
    return regions


def _projection(path: Path) -> pyproj.Transformer:
    prj = next((p for p in (path.with_suffix(".prj"), path.with_suffix(".PRJ")) if p.is_file()), None)
    if prj is None:
        raise ChartError(f"{path}: no projection file ({path.with_suffix('.prj').name}) beside it; SIGRID-3 "
                         "charts carry one, and the chart cannot be placed without it")
    try:
        crs = pyproj.CRS.from_wkt(prj.read_text(errors="replace"))
        return pyproj.Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
    except pyproj.exceptions.CRSError as exc:
        raise ChartError(f"{prj}: not a projection pyproj can read: {exc}") from None


def _feature(path: Path, n: int, shape: shapefile.Shape, record: dict, to_wgs84: pyproj.Transformer) -> ChartFeature:
    where = f"{path}: feature {n}"
    kind = KINDS.get(str(record["POLY_TYPE"] or "").strip().upper())
    if kind is None:
        raise ChartError(f"{where}: POLY_TYPE = {record['POLY_TYPE']!r}: one of I or S (ice), W, L, N")
    regime = _regime(where, record) if kind == "ice" else make_regime(0.0, [])
    if shape.shapeType == shapefile.NULL or not shape.points:
        raise ChartError(f"{where}: has no geometry")
    geometry = geo_shape(shape.__geo_interface__)
    if geometry.is_empty or not shapely.is_valid(geometry):
        raise ChartError(f"{where}: invalid polygon: {shapely.is_valid_reason(geometry)}")
    x, y = to_wgs84.transform(*shapely.get_coordinates(geometry).T)
    if not (np.all(np.isfinite(x)) and np.all(np.abs(y) <= 90.0)):
        raise ChartError(f"{where}: coordinates that do not lie on the earth in the chart's projection")
    if np.abs(y).max() > MAX_LATITUDE:
        raise ChartError(f"{where}: reaches latitude {y[np.abs(y).argmax()]:.2f} deg; the exercise's local frame "
                         f"holds to {MAX_LATITUDE:g} deg")
    lonlat = shapely.set_coordinates(geometry, np.column_stack([x, y]))
    return ChartFeature(f"{path.name} feature {n}", kind, regime, lonlat, where)


def _regime(where: str, record: dict) -> IceRegime:
    total = _code(where, record, "CT")
    if total is None or total == 99:
        raise ChartError(f"{where}: CT = {record['CT']!r}: an ice polygon needs its total concentration")
    types = []
    for letter in "ABC":
        stage, size = _code(where, record, "S" + letter), _code(where, record, "F" + letter)
        if stage is None:
            given = [f for f in ("C" + letter, "F" + letter) if _code(where, record, f) is not None]
            if given:
                raise ChartError(f"{where}: S{letter} is empty; {' and '.join(given)} need the stage of their ice")
            continue
        if size is None:
            raise ChartError(f"{where}: F{letter} is empty; S{letter} = {stage:02d} needs a floe size")
        partial = _code(where, record, "C" + letter)
        types.append((None if partial is None else _checked(where, "C" + letter, partial,
                                                             wmo_codes.concentration_tenths),
                      _checked(where, "S" + letter, stage, lambda c: wmo_codes.stage(c).code),
                      _checked(where, "F" + letter, size, lambda c: wmo_codes.floe_size(c).code)))
    tenths = _checked(where, "CT", total, wmo_codes.concentration_tenths)
    if tenths > 0.0 and not types:
        raise ChartError(f"{where}: SA is empty; an ice polygon with CT = {total:02d} needs the stage of its ice")
    try:
        return make_regime(tenths, types)
    except ValueError as exc:
        raise ChartError(f"{where}: CT, CA, CB, CC: {exc}") from None


def _checked(where: str, field: str, code: int, convert):
    try:
        return convert(code)
    except ValueError as exc:
        raise ChartError(f"{where}: {field} = {code:02d}: {exc}") from None


def _code(where: str, record: dict, field: str) -> int | None:
    """A SIGRID-3 code as an integer; None for an empty field or -9 (not given)."""
    value = record[field]
    if isinstance(value, float) and value.is_integer():  # a numeric (N) field with decimals: 60.0
        value = int(value)
    text = value.decode("ascii", "replace") if isinstance(value, bytes) else str(value if value is not None else "")
    text = text.strip()
    if text in ("", "-9"):
        return None
    try:
        return int(text)
    except ValueError:
        raise ChartError(f"{where}: {field} = {text!r}: not a SIGRID-3 code (a two-digit number)") from None
