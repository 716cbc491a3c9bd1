import trimesh
from conftest import run_cli


def test_prefracture_builds_then_loads_from_cache(tmp_path):
    args = ("prefracture", "--cache-dir", str(tmp_path / "lib"), "--out", str(tmp_path / "out"))
    first = run_cli(*args)
    assert first.returncode == 0, first.stderr
    assert "built" in first.stdout and "0.50" in first.stdout
    assert len(list((tmp_path / "lib").glob("*.npz"))) == 2  # one class x two variants
    assert (tmp_path / "out" / "prefracture.png").stat().st_size > 10_000
    second = run_cli(*args)
    assert second.returncode == 0 and "cache" in second.stdout and "built" not in second.stdout


def test_prefracture_exports_one_tile(tmp_path):
    out = tmp_path / "tile.glb"
    res = run_cli("prefracture", "--thickness", "1.0", "--seed", "5", "--mode", "prism",
                  "--colliders", "sphere", "--export", str(out))
    assert res.returncode == 0, res.stderr
    scene = trimesh.load(out, file_type="glb")
    assert 855 <= len(scene.geometry) <= 1515
    assert f"({len(scene.geometry)} cells)" in res.stdout
