"""A user's config mistake gives one clear message naming file, key, value and the allowed
range, a non-zero exit, and no traceback."""
import pytest
from conftest import run_cli

from bridge_node.node.config import DEFAULT_CONFIG, ConfigError, load_config


def write_config(tmp_path, replace: dict[str, str]):
    text = DEFAULT_CONFIG.read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return path


CASES = [
    ({"thickness = 0.5 ": "thickness = -0.3 "}, ["ice_field.thickness", "-0.3", "greater than 0"]),
    ({"thickness = 0.5 ": "thickness = 2.0 "}, ["ice_field.thickness", "2.0", "less than or equal to 1.5"]),
    ({"thickness = 0.5 ": "# thickness removed "}, ["ice_field.thickness", "required key is missing"]),
    ({"tile_side = 100.0": 'tile_side = "big"'}, ["fracture.tile_side", "'big'", "valid number"]),
    ({'cells = "prism"': 'cells = "cubes"'}, ["fracture.cells", "'cubes'", "'prism' or 'voronoi3d'"]),
    ({"mesh_share = 0.3": "mesh_shares = 0.3"}, ["fracture.mesh_shares", "unknown key"]),
    ({'thickness_profile = "uniform"': 'thickness_profile = "gradient"'},
     ["ice_field", "thickness_end is required"]),
    ({"[paths]": "[paths"}, ["not valid TOML"]),
]


@pytest.mark.parametrize("replace,expected", CASES)
def test_bad_config_message(tmp_path, replace, expected):
    path = write_config(tmp_path, replace)
    with pytest.raises(ConfigError) as err:
        load_config(path)
    msg = str(err.value)
    assert str(path) in msg
    for part in expected:
        assert part in msg, (part, msg)


@pytest.mark.parametrize("replace,expected", CASES[:4])
def test_cli_exits_nonzero_without_traceback(tmp_path, replace, expected):
    path = write_config(tmp_path, replace)
    res = run_cli("prefracture", "--config", str(path), "--cache-dir", str(tmp_path / "c"))
    assert res.returncode == 2
    assert "Traceback" not in res.stderr + res.stdout
    assert str(path) in res.stderr and expected[0] in res.stderr


def test_missing_config_file_and_bad_thickness_argument(tmp_path):
    res = run_cli("prefracture", "--config", str(tmp_path / "nope.toml"))
    assert res.returncode == 2 and "config file not found" in res.stderr and "Traceback" not in res.stderr
    res = run_cli("prefracture", "--thickness", "2.0")
    assert res.returncode == 2 and "--thickness" in res.stderr and "(0, 1.5]" in res.stderr
    assert "Traceback" not in res.stderr


def test_default_config_loads():
    cfg = load_config()
    assert cfg.ice_field.thickness == 0.5 and cfg.fracture.tile_side == 100.0
