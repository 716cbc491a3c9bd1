"""How many Voronoi seeds (fragments) a tile of level ice gets, as a function of thickness.

Two models:

``paper``
    The reference paper's linear law through its two data points derived from Lubbad &
    Løset's wedge example: h = 1.0 m -> 855..1515 pieces, h = 0.5 m -> 1165..2065 pieces per
    100 m x 100 m. The printed equation (1) is garbled (read literally it gives 855 at
    h = 0.5 m), so the interpolation that honours the data is used:
    n_min = floor(1475 - 620 h), n_max = floor(2615 - 1100 h).

``physical``
    Fragment size proportional to the characteristic length l_c of the floating plate
    (l_c ~ h^(3/4)), so the count per area goes as l_c^-2 ~ h^(-3/2). Calibrated to the same
    h = 1.0 m point (855..1515). Against ``paper`` it gives 2.1x the pieces at 0.5 m, 7x at
    0.2 m, 19x at 0.1 m and 0.85x at 1.5 m: the paper's line is far flatter than plate
    theory (table in docs/design/prefracture.md).
"""
from __future__ import annotations

import math

from sim_core.material import IceMaterial, characteristic_length

REFERENCE_AREA = 100.0 * 100.0  # m2: the paper's counts are per 100 m x 100 m
MAX_THICKNESS = 1.5  # m: the paper's law is calibrated up to here
COUNT_MODELS = ("paper", "physical")
_CALIBRATION_H = 1.0  # m
_CALIBRATION_RANGE = (855, 1515)


def check_thickness(h: float) -> None:
    """Raise ValueError unless 0 < h <= 1.5 m (the range the count laws are calibrated for)."""
    if not (isinstance(h, (int, float)) and math.isfinite(h) and 0.0 < h <= MAX_THICKNESS):
        raise ValueError(f"ice thickness {h!r} m is outside the allowed range (0, {MAX_THICKNESS}] m")


def seed_count_range(
    h: float, tile_side: float = 100.0, model: str = "paper", mat: IceMaterial | None = None
) -> tuple[int, int]:
    """Return (n_min, n_max) fragments for a square tile of side tile_side (m), thickness h (m)."""
    check_thickness(h)
    scale = tile_side * tile_side / REFERENCE_AREA
    if model == "paper":
        lo, hi = math.floor(1475.0 - 620.0 * h), math.floor(2615.0 - 1100.0 * h)
    elif model == "physical":
        mat = mat or IceMaterial()
        ratio = (characteristic_length(_CALIBRATION_H, mat) / characteristic_length(h, mat)) ** 2
        lo, hi = math.floor(_CALIBRATION_RANGE[0] * ratio), math.floor(_CALIBRATION_RANGE[1] * ratio)
    else:
        raise ValueError(f"unknown count model {model!r}; allowed: {', '.join(COUNT_MODELS)}")
    if scale == 1.0:
        return lo, hi
    return max(1, math.floor(lo * scale)), max(1, math.floor(hi * scale))
