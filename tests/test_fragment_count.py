import math

import numpy as np
import pytest

from sim_core.fracture.fragment_count import seed_count_range
from sim_core.fracture.tile_template import FractureSettings, build_tile, plan_areas
from sim_core.material import IceMaterial, characteristic_length


def test_paper_data_points_exact():
    assert seed_count_range(1.0) == (855, 1515)
    assert seed_count_range(0.5) == (1165, 2065)


def test_range_scales_with_tile_area():
    lo, hi = seed_count_range(1.0, tile_side=200.0)
    assert (lo, hi) == (4 * 855, 4 * 1515)


@pytest.mark.parametrize("h", [0.2, 0.5, 1.0, 1.5])
def test_built_tiles_have_counts_in_range(h):
    lo, hi = seed_count_range(h)
    for seed in range(3):
        n = build_tile(h, seed).n_cells
        assert lo <= n <= hi


def test_thicker_ice_gives_fewer_larger_cells():
    hs = [0.2, 0.5, 1.0, 1.5]
    ranges = [seed_count_range(h) for h in hs]
    assert all(a[0] > b[0] and a[1] > b[1] for a, b in zip(ranges, ranges[1:]))
    mean_count, mean_area = [], []
    for h in hs:
        tiles = [build_tile(h, seed) for seed in range(6)]
        mean_count.append(np.mean([t.n_cells for t in tiles]))
        mean_area.append(np.mean([plan_areas(t.geometry).mean() for t in tiles]))
    assert all(a > b for a, b in zip(mean_count, mean_count[1:]))
    assert all(a < b for a, b in zip(mean_area, mean_area[1:]))


@pytest.mark.parametrize("h", [0.0, -0.1, 1.6, 2.0, float("nan")])
def test_thickness_outside_range_is_an_error(h):
    with pytest.raises(ValueError, match="outside the allowed range"):
        seed_count_range(h)


def test_physical_model_calibrated_at_one_metre_and_follows_plate_scaling():
    assert seed_count_range(1.0, model="physical") == (855, 1515)
    mat = IceMaterial()
    lo05, _ = seed_count_range(0.5, model="physical")
    expected = 855 * (characteristic_length(1.0, mat) / characteristic_length(0.5, mat)) ** 2
    assert lo05 == math.floor(expected)
    assert expected == pytest.approx(855 * 0.5**-1.5)
    tile = build_tile(1.0, 1, FractureSettings(count_model="physical"))
    assert 855 <= tile.n_cells <= 1515


def test_characteristic_length_matches_hand_value():
    mat = IceMaterial(water_density=1025.0, gravity=9.81)
    d = 3e9 * 1.0 / (12 * (1 - 0.33**2))
    assert characteristic_length(1.0, mat) == pytest.approx((d / (1025 * 9.81)) ** 0.25, rel=1e-12)
    # by hand: D = 3e9 / (12 * 0.8911) = 2.806e8 N m; (D / 10055)^(1/4) = 27904^(1/4) = 12.92 m
    assert characteristic_length(1.0, mat) == pytest.approx(12.924, abs=1e-3)
