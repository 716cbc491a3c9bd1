"""Ice regions in a config (issue 26, item 1): ``ice_field.chart`` names a SIGRID-3 chart and
``[[ice_field.regions]]`` draws regions over it, in local metres or in degrees;
``icebridge field CONFIG`` lays out both. A bad region or chart is a config error naming the
file and key (and, for a chart, its feature and field)."""
import json

import pytest
from conftest import run_cli
from sigrid3_charts import ISSUE_CHART, write_chart

from bridge_node.node.config import ConfigError, load_config

CONFIG = """
[ship]
name = "polar_cargo"

[exercise]
origin_latitude_deg = 74.0
origin_longitude_deg = 20.0

[ice_field]
width = 3000.0
height = 1500.0
thickness = 0.5
chart = "issue.shp"

[[ice_field.regions]]     # an old channel filled with brash, drawn over the chart in metres
name = "channel"
polygon_m = [[1000.0, 0.0], [1100.0, 0.0], [1100.0, 1500.0], [1000.0, 1500.0]]
concentration = 10
ice = [{ stage = "grey", floe_size = "brash" }]

[[ice_field.regions]]     # fast ice along the south edge, in degrees
name = "fast ice"
polygon_deg = [[74.0, 20.04], [74.0, 20.06], [74.002, 20.06], [74.002, 20.04]]
concentration = 10
ice = [{ stage = 91, floe_size = 9 }]
"""


def _config(folder, text=CONFIG):
    write_chart(folder / "issue", ISSUE_CHART)
    path = folder / "exercise.toml"
    path.write_text(text)
    return path


def test_the_config_lays_out_its_chart_and_its_regions(tmp_path):
    done = run_cli("field", str(_config(tmp_path)), "--json", "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr
    regions = {r["name"]: r for r in json.loads(done.stdout)["regions"]}
    assert list(regions) == ["issue.shp feature 1", "issue.shp feature 2", "issue.shp feature 3", "channel",
                             "fast ice"]
    channel = regions["channel"]
    assert channel["area_km2"] == pytest.approx(0.15, rel=1e-6)  # 100 m x 1500 m, over the chart
    assert channel["types"][0]["floe_size"] == "brash" and abs(channel["concentration_laid"] - 10) <= 0.5
    assert regions["fast ice"]["level_ice"] and regions["fast ice"]["concentration_laid"] == 10
    assert regions["fast ice"]["area_km2"] == pytest.approx(0.137, rel=0.02)  # ~616 m x 223 m


@pytest.mark.parametrize("old, new, expected", [
    ('stage = "grey"', 'stage = "gray"', ["ice_field.regions.0.ice.0.stage", "'gray' is not a stage"]),
    ("concentration = 10\nice = [{ stage = \"grey\"", "concentration = 5\nice = [{ concentration = 6, stage = \"grey\"",
     ["ice_field.regions.0", "add up to 6/10, more than the total 5/10"]),
    ("[1100.0, 1500.0], [1000.0, 1500.0]", "[1000.0, 1500.0], [1100.0, 1500.0]",
     ["ice_field.regions.0", "invalid polygon: Self-intersection"]),
    ('chart = "issue.shp"', 'chart = "missing.shp"', ["ice_field.chart = 'missing.shp'", "no such file"]),
])
def test_a_bad_region_is_a_config_error(tmp_path, old, new, expected):
    path = _config(tmp_path, CONFIG.replace(old, new, 1))
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    for text in [str(path)] + expected:
        assert text in str(caught.value), str(caught.value)


def test_a_bad_chart_is_named_with_the_config_key(tmp_path):
    path = _config(tmp_path)
    write_chart(tmp_path / "issue", [(ISSUE_CHART[1][0], {"POLY_TYPE": "I", "CT": "60", "SA": "87", "FA": "77"})])
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    message = str(caught.value)
    assert "ice_field.chart = 'issue.shp'" in message and "feature 1: FA = 77" in message
