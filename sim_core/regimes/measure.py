"""Measures of a laid-out floe field: floe size, and concentration per region."""
from __future__ import annotations

import math

import numpy as np
import shapely

from sim_core.regimes.floe_layout import FloeLayout


def caliper_diameter(polygons: np.ndarray) -> np.ndarray:
    """Mean caliper diameter (n,) m of polygons (n,): the perimeter of the convex hull over
    pi (Cauchy's formula; the floe size of Rothrock & Thorndike 1984)."""
    return shapely.length(shapely.convex_hull(polygons)) / math.pi


def ice_area(layout: FloeLayout, region: int, within: shapely.Geometry) -> float:
    """Area (m2) of the region's floes inside a polygon."""
    floes = layout.polygon[layout.region == region]
    if not len(floes):
        return 0.0
    return float(shapely.area(shapely.intersection(floes, within)).sum())
