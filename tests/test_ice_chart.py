"""Ice regimes from a SIGRID-3 chart (issue 26, items 1 and 4): ``icebridge field`` lays out
the chart's regions and its report matches the chart (concentration per region within half
a tenth, floe sizes within the WMO ranges); a bad chart is a clear error naming the file,
the feature and the field, never a traceback."""
import json

import pyproj
import pytest
from conftest import run_cli
from PIL import Image
import shapefile
from sigrid3_charts import ISSUE_CHART, WGS84_PRJ, box_ring, write_chart

from bridge_node.charts.sigrid3 import FIELDS, read_chart


@pytest.fixture(scope="module")
def issue_report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("chart")
    chart = write_chart(folder / "issue", ISSUE_CHART)
    done = run_cli("field", str(chart), "--json", "--out", str(folder))
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_each_region_is_laid_at_its_charted_concentration(issue_report):
    regions = issue_report["regions"]
    assert [r["kind"] for r in regions] == ["water", "ice", "ice"]
    for region in regions:
        assert abs(region["concentration_laid"] - region["concentration_chart"]) <= 0.5, region
    assert regions[0]["concentration_laid"] == 0.0
    assert regions[1]["whole"]  # medium floes: the whole region is laid and measured


def test_the_report_says_where_the_floes_repeat(issue_report):
    """As the world lays them on 100 m tiles: the small floes every 4 tiles, the medium
    floes at 6/10 (227 m apart) every 7, three across."""
    assert [r["repeat_m"] for r in issue_report["regions"]] == [None, 700.0, 400.0]


def test_floe_sizes_lie_in_the_wmo_ranges(issue_report):
    types = {t["floe_size"]: t for r in issue_report["regions"] for t in r["types"]}
    assert set(types) == {"medium_floe", "small_floe", "brash"}
    assert types["medium_floe"]["size_range_m"] == [100.0, 500.0]
    assert types["small_floe"]["size_range_m"] == [20.0, 100.0]
    for t in types.values():
        assert t["floes"] >= 30, t
        assert t["share_within_range"] >= 0.95, t
        low, high = t["size_range_m"]
        assert low <= t["size_p5_p50_p95_m"][1] <= high


def test_ice_types_and_thicknesses_follow_the_stage_codes(issue_report):
    pack = issue_report["regions"][2]["types"]
    assert [(t["concentration"], t["stage"], t["floe_size"]) for t in pack] == [
        (6.0, "thick_first_year", "small_floe"), (3.0, "grey_white", "brash")]
    assert pack[0]["thickness_range_m"] == [1.2, 2.0] and pack[1]["thickness_range_m"] == [0.15, 0.3]


def test_the_top_view_shows_floes_and_water(issue_report):
    with Image.open(issue_report["picture"]) as image:
        grey = image.convert("L")
        histogram = grey.histogram()
    bright = sum(histogram[200:]) / sum(histogram)  # floes (and the page)
    dark = sum(histogram[:80]) / sum(histogram)  # open water
    assert bright > 0.2 and dark > 0.05


def _bad(tmp_path, features, **kw):
    return write_chart(tmp_path / "bad", features, **kw)


PACK = {"POLY_TYPE": "I", "CT": "70", "SA": "87", "FA": "04"}
NORTH_POLAR = pyproj.CRS.from_epsg(3413).to_wkt("WKT1_ESRI")  # NSIDC sea ice polar stereographic north


def _polar_box(x: float, y: float, half: float) -> list[list[float]]:
    """A closed clockwise square ring of half-side ``half`` m about (x, y) m, EPSG:3413."""
    return [[x - half, y - half], [x - half, y + half], [x + half, y + half], [x + half, y - half], [x - half, y - half]]
RING = box_ring(20.0, 74.0, 20.01, 74.005)
BOW_TIE = [[20.0, 74.0], [20.01, 74.005], [20.01, 74.0], [20.0, 74.005], [20.0, 74.0]]


@pytest.mark.parametrize("case, make, expected", [
    ("missing attribute", lambda p: _bad(p, [(RING, PACK)], fields=tuple(f for f in FIELDS if f != "FA")),
     ["no attribute FA"]),
    ("unknown stage", lambda p: _bad(p, [(RING, PACK), (RING, {**PACK, "SA": "77"})]),
     ["feature 2", "SA = 77", "not a SIGRID-3 stage of development code"]),
    ("unknown concentration", lambda p: _bad(p, [(RING, {**PACK, "CT": "75"})]),
     ["feature 1", "CT = 75", "not a SIGRID-3 concentration code"]),
    ("too much ice", lambda p: _bad(p, [(RING, {**PACK, "CT": "50", "CA": "40", "CB": "30", "SB": "85",
                                                "FB": "02"})]),
     ["feature 1", "CT, CA, CB, CC", "add up to 7/10, more than the total 5/10"]),
    ("self-intersecting", lambda p: _bad(p, [(RING, PACK), (BOW_TIE, PACK)]),
     ["feature 2", "invalid polygon", "Self-intersection"]),
    ("no projection", lambda p: _bad(p, [(RING, PACK)], prj=None), ["no projection file (bad.prj)"]),
    ("empty file", lambda p: (p / "empty.shp").write_bytes(b"") or p / "empty.shp", ["empty file"]),
    ("a directory", lambda p: (p / "charts.shp").mkdir() or p / "charts.shp", ["is a directory"]),
    ("bad projection", lambda p: _bad(p, [(RING, PACK)], prj="PROJCS[nonsense"), ["bad.prj", "not a projection"]),
    ("a partial without its stage", lambda p: _bad(p, [(RING, {**PACK, "CT": "90", "CA": "60", "CB": "30",
                                                                "FB": "02"})]),
     ["feature 1", "SB is empty; CB and FB need the stage of their ice"]),
    ("ice without a stage", lambda p: _bad(p, [(RING, {"POLY_TYPE": "I", "CT": "60", "FA": "04"})]),
     ["feature 1", "SA is empty"]),
    ("round the pole", lambda p: _bad(p, [(_polar_box(0.0, 0.0, 400e3), PACK)], prj=NORTH_POLAR),
     ["feature 1", "not a valid polygon in the exercise's local frame", "round a pole"]),
    ("near the pole", lambda p: _bad(p, [(_polar_box(0.0, 100e3, 50e3), PACK)], prj=NORTH_POLAR),
     ["feature 1", "reaches latitude 89.", "holds to 89 deg"]),
])
def test_a_bad_chart_is_a_clear_error(tmp_path, case, make, expected):
    path = make(tmp_path)
    done = run_cli("field", str(path), "--out", str(tmp_path))
    assert done.returncode == 2, (case, done.stdout, done.stderr)
    assert "Traceback" not in done.stderr
    assert str(path.with_suffix("")) in done.stderr, done.stderr  # the .shp, or its .prj
    for text in expected:
        assert text in done.stderr, (case, done.stderr)


def test_a_chart_in_a_polar_projection_across_180_deg(tmp_path):
    """A 2 km square of pack centred on 70 N 180 E, charted in polar stereographic
    coordinates, is 4 km2 in the local frame, not a band round the earth."""
    x, y = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:3413", always_xy=True).transform(180.0, 70.0)
    chart = write_chart(tmp_path / "dateline", [(_polar_box(x, y, 1000.0), PACK)], prj=NORTH_POLAR)
    done = run_cli("field", str(chart), "--json", "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr
    region, = json.loads(done.stdout)["regions"]
    assert region["area_km2"] == pytest.approx(4.0, rel=0.02)


def test_numeric_attribute_fields_are_read_as_codes(tmp_path):
    """Some services store the codes as numeric (N) fields, with decimals."""
    base = tmp_path / "numeric"
    with shapefile.Writer(str(base), shapeType=shapefile.POLYGON) as w:
        w.field("POLY_TYPE", "C", size=1)
        for name in FIELDS[1:]:
            w.field(name, "N", size=5, decimal=1)
        w.poly([RING])
        w.record("I", 60.0, -9.0, 87.0, 4.0, -9.0, -9.0, -9.0, -9.0, -9.0, -9.0)
    base.with_suffix(".prj").write_text(WGS84_PRJ)
    features = read_chart(base.with_suffix(".shp"))
    assert features[0].regime.label() == "6/10 thin_first_year small_floe"
