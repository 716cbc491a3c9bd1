"""Local tangent plane <-> latitude/longitude around a configured origin (WGS 84).

The exercise area is a few tens of kilometres at most, so a local tangent plane with the
WGS 84 meridional and prime-vertical radii at the origin is accurate to well under a metre
there. pyproj (which the chart reader uses for a chart's own projection) would give the
same answer here, at far more cost per call and outside ``sim_core``'s no-I/O rule.
"""
from __future__ import annotations

import math

_A = 6378137.0  # WGS 84 semi-major axis, m
_E2 = 6.69437999014e-3  # first eccentricity squared


def radii(lat0: float) -> tuple[float, float]:
    """Meridional and prime-vertical radii of curvature (m) at latitude lat0 (rad)."""
    w = 1.0 - _E2 * math.sin(lat0) ** 2
    return _A * (1.0 - _E2) / w**1.5, _A / math.sqrt(w)


def local_to_geodetic(north: float, east: float, lat0: float, lon0: float) -> tuple[float, float]:
    """Latitude and longitude (rad) of a point north/east metres from the origin (rad)."""
    m, n = radii(lat0)
    return lat0 + north / m, lon0 + east / (n * math.cos(lat0))


def geodetic_to_local(lat: float, lon: float, lat0: float, lon0: float) -> tuple[float, float]:
    """North and east metres of (lat, lon) from the origin; all angles in radians."""
    m, n = radii(lat0)
    return (lat - lat0) * m, (lon - lon0) * n * math.cos(lat0)
