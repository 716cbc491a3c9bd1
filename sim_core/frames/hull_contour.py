"""The hull's waterline contour in the ship frame (x forward from midship, y to starboard)."""
from __future__ import annotations

import numpy as np

CONTOUR_POINTS = 34  # paper §2.4: the hull described by 34 contour points
BOW_FRACTION = 0.3  # share of the length the parabolic bow takes
STERN_FRACTION = 0.15  # share of the length the parabolic run takes


def waterline_contour(length: float, beam: float, n_points: int = CONTOUR_POINTS,
                      bow_fraction: float = BOW_FRACTION, stern_fraction: float = STERN_FRACTION,
                      transom: float = 0.6) -> np.ndarray:
    """Convex waterline contour (n_points, 2) in the ship frame, m: a parallel midbody, a
    parabolic bow over ``bow_fraction`` of the length ending at the stem, and a parabolic
    run over ``stern_fraction`` ending at a transom of ``transom`` x beam. Points run from
    the stem down the starboard side to the transom corner, the transom centre, then up the
    port side; n_points/2 stations per side (the stem once)."""
    if n_points < 8 or n_points % 2:
        raise ValueError("n_points must be an even number >= 8")
    half = n_points // 2
    x_bow, x_stern = 0.5 * length - bow_fraction * length, -0.5 * length + stern_fraction * length
    x = np.linspace(0.5 * length, -0.5 * length, half)
    y = np.full(half, 0.5 * beam)
    bow = x > x_bow
    y[bow] = 0.5 * beam * (1.0 - ((x[bow] - x_bow) / (0.5 * length - x_bow)) ** 2)
    stern = x < x_stern
    y[stern] = 0.5 * beam * (1.0 - (1.0 - transom) * ((x_stern - x[stern]) / (x_stern + 0.5 * length)) ** 2)
    stbd = np.column_stack([x, y])
    port = np.column_stack([x[1:], -y[1:]])[::-1]
    return np.vstack([stbd, [[-0.5 * length, 0.0]], port])

