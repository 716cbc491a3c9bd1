"""Floe fields laid out from ice regimes (issue 26, item 1): the egg code's codes, regimes
that add up, and a layout that reaches each type's concentration with floes of its size,
none overlapping, each inside its region, the same whichever windows it is laid in."""
import numpy as np
import pytest
import shapely

from sim_core.regimes import wmo_codes
from sim_core.regimes.floe_layout import compile_regimes, joined, lay_out
from sim_core.regimes.measure import caliper_diameter, ice_area
from sim_core.regimes.regime import IceRegion, effective_polygons, make_regime, region_at
from sim_core.regimes.survey import survey_region


@pytest.mark.parametrize("code, tenths", [(0, 0.0), (1, 0.0), (10, 1.0), (60, 6.0), (46, 5.0), (79, 8.0), (81, 9.0),
                                          (91, 9.5), (92, 10.0), (98, 0.0)])
def test_concentration_codes(code, tenths):
    assert wmo_codes.concentration_tenths(code) == tenths


@pytest.mark.parametrize("code", [5, 75, 64, 93, 99, 100])
def test_a_code_that_is_not_a_concentration_is_refused(code):
    with pytest.raises(ValueError, match="not a SIGRID-3 concentration code"):
        wmo_codes.concentration_tenths(code)


def test_regimes_add_up():
    assert make_regime(6, [(None, 87, 5)]).types[0].concentration == 6
    assert make_regime(9, [(5, 93, 4), (3, 85, 2)]).types[0].concentration == 6  # the rest to the thickest
    assert make_regime(9.5, [(6, 93, 4), (4, 85, 2)]).total == 9.5  # 9+/10 holds 10 tenths of partials
    assert make_regime(10, [(None, 91, 9)]).level and not make_regime(10, [(None, 91, 6)]).level
    with pytest.raises(ValueError, match="add up to 8/10, more than the total 7/10"):
        make_regime(7, [(5, 93, 4), (3, 85, 2)])
    with pytest.raises(ValueError, match="fast ice is level ice"):
        make_regime(10, [(5, 93, 9), (5, 85, 2)])
    with pytest.raises(ValueError, match="stage of development 99 cannot be laid out"):
        make_regime(5, [(None, 99, 4)])


def test_later_regions_lie_over_earlier_ones():
    free = make_regime(0, [])
    regions = [IceRegion("a", shapely.box(0, 0, 100, 100), "water", free),
               IceRegion("b", shapely.box(50, 0, 150, 100), "water", free)]
    polygons = effective_polygons(regions, shapely.box(0, 0, 120, 100))
    assert polygons[0].area == pytest.approx(5000) and polygons[1].area == pytest.approx(7000)
    assert list(region_at(polygons, np.array([10.0, 60.0, 130.0]), np.array([5.0, 5.0, 5.0]))) == [0, 1, -1]


@pytest.fixture(scope="module")
def pack():
    """7/10 of which 5/10 medium first-year small floes and 2/10 grey-white ice cakes, in an
    L-shaped region beside an ice-free one."""
    regime = make_regime(7, [(5, 91, 4), (2, 85, 3)])
    region = shapely.Polygon([(0, 0), (600, 0), (600, 300), (300, 300), (300, 600), (0, 600)])
    regions = [IceRegion("free", shapely.box(0, 0, 600, 600), "water", make_regime(0, [])),
               IceRegion("pack", region, "ice", regime)]
    return compile_regimes(regions, shapely.box(0, 0, 600, 600), seed=3)


def _laid(model, side):
    return joined([lay_out(model, (x, y, x + side, y + side)) for x in np.arange(-100, 700, side)
                   for y in np.arange(-100, 700, side)])


def test_the_layout_does_not_depend_on_the_windows(pack):
    big = _laid(pack, 400.0)
    assert len(big) > 100
    for side in (100.0, 230.0):  # 230 m windows: some miss the L-shaped region, but not its floes
        np.testing.assert_array_equal(_centroids(big), _centroids(_laid(pack, side)))


def _centroids(layout, shift=(0.0, 0.0)):
    c = shapely.get_coordinates(shapely.centroid(layout.polygon)) + shift
    return np.round(c[np.lexsort(c.T)], 6)


def test_laid_for_tiles_a_layout_repeats_in_a_square_of_whole_tiles():
    """7/10 pack of small floes and ice cakes on 100 m tiles repeats every 4 tiles: each
    layer's grid divides 400 m, and a window 400 m east or north lays the same floes."""
    regime = make_regime(7, [(4, 87, 4), (3, 85, 3)])
    region = IceRegion("pack", shapely.box(-5000, -5000, 5000, 5000), "ice", regime)
    model = compile_regimes([region], shapely.box(-5000, -5000, 5000, 5000), seed=3, tile_side=100.0)
    assert model.repeat == (4,)
    assert [round(layer.spacing * layer.period, 9) for layer in model.layers[0]] == [400.0, 400.0]
    first = lay_out(model, (100.0, 200.0, 500.0, 600.0))
    assert len(first) > 100
    for dx, dy in ((400.0, 0.0), (0.0, -400.0), (-800.0, 1200.0)):
        moved = lay_out(model, (100.0 + dx, 200.0 + dy, 500.0 + dx, 600.0 + dy))
        np.testing.assert_allclose(_centroids(first, (dx, dy)), _centroids(moved), atol=1e-6)
    aperiodic = compile_regimes([region], shapely.box(-5000, -5000, 5000, 5000), seed=3)
    assert aperiodic.repeat == (0,) and all(layer.period == 0 for layer in aperiodic.layers[0])
    huge = IceRegion("big floes", region.polygon, "ice", make_regime(8, [(None, 87, 6)]))  # 500-2000 m
    assert compile_regimes([huge], huge.polygon, seed=3, tile_side=100.0).repeat == (0,)  # too large to repeat


@pytest.mark.parametrize("tile_side", [None, 100.0])
@pytest.mark.parametrize("total, types, short, repeat", [
    (8, [(5, 91, 5), (3, 87, 4)], False, 8),  # medium floes (248 m apart: three in 8 tiles), small floes
    (9, [(6, 93, 4), (3, 85, 2)], False, 4),  # small floes, brash in their leads
    (10, [(2, 93, 4), (3, 91, 3), (5, 85, 3)], True, 4),  # ice cakes of two kinds cannot fill what small floes leave
])
def test_later_types_fill_the_leads_or_the_survey_says_why_not(total, types, short, repeat, tile_side):
    """Laid freely or for the world's tiles (repeating where the floes allow), alike."""
    region = IceRegion("r", shapely.box(0, 0, 1500, 1500), "ice", make_regime(total, types))
    model = compile_regimes([region], shapely.box(0, 0, 1500, 1500), seed=0, tile_side=tile_side)
    assert model.repeat[0] == (repeat if tile_side else 0)
    survey = survey_region(model, 0)
    assert all(t.within_range >= 0.95 for t in survey.types)
    assert (abs(survey.concentration - total) > 0.5) == short and bool(survey.note) == short, survey.concentration


def test_floes_reach_the_concentration_inside_their_region_without_overlap(pack):
    layout = _laid(pack, 200.0)
    region = pack.polygons[1]
    assert np.all(shapely.within(layout.polygon, shapely.buffer(region, 1e-6)))
    assert np.all(layout.region == 1)
    tree = shapely.STRtree(layout.polygon)
    a, b = tree.query(layout.polygon, predicate="overlaps")
    assert not np.any(a != b)
    assert ice_area(layout, 1, region) / region.area * 10 == pytest.approx(7.0, abs=0.5)
    for k, (low, high) in enumerate([(20.0, 100.0), (2.0, 20.0)]):
        rows = (layout.ice_type == k) & ~layout.clipped
        size = caliper_diameter(layout.polygon[rows])
        assert rows.sum() > 20 and np.mean((size >= low) & (size <= high)) >= 0.95
        area = shapely.area(layout.polygon[layout.ice_type == k]).sum()
        assert area / region.area * 10 == pytest.approx([5.0, 2.0][k], abs=0.5)
    np.testing.assert_allclose(np.unique(layout.thickness), [0.225, 0.95])
