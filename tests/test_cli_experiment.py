"""``icebridge experiment`` as a user runs it: JSON results, plots, clear errors."""
import json

from conftest import run_cli


def test_transit_json_series_and_plots(tmp_path):
    cfg = tmp_path / "exercise.toml"
    cfg.write_text(
        '[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 400.0\nthickness = 0.3\n'
        f'[paths]\ncache_dir = "{tmp_path / "tiles"}"\n'
    )
    r = run_cli("experiment", "transit", "--config", str(cfg), "--distance", "220", "--dt", "0.1",
                "--json", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    s, series = out["summary"], out["series"]
    assert s["distance_m"] >= 220.0 and s["reverse_replacement"] is True
    assert len(series["distance_m"]) == len(series["live"]) == s["steps"]
    assert max(series["live"]) == s["max_live"] > 0  # the bow reached the ice and broke it
    assert (tmp_path / "transit.png").stat().st_size > 10_000


def test_transit_bad_arguments_are_clear_errors():
    r = run_cli("experiment", "transit", "--distance", "-5")
    assert r.returncode == 2 and "--distance -5.0 m is outside the allowed range" in r.stderr
    assert "Traceback" not in r.stderr


def test_scene_config_error_names_file_and_key(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n[scene]\nreverse_distance = 100.0\n')
    r = run_cli("experiment", "transit", "--config", str(cfg), "--distance", "50")
    assert r.returncode == 2
    assert str(cfg) in r.stderr and "reverse_distance = 100.0 m must be at least" in r.stderr
    assert "Traceback" not in r.stderr


def test_run_renders_channel_frames(tmp_path):
    cfg = tmp_path / "exercise.toml"
    cfg.write_text(
        '[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 400.0\nthickness = 0.3\n'
        '[exercise]\nstart_north = -60.0\n'
        '[[render.channels]]\nname = "bow"\nwidth = 160\nheight = 90\n'
        f'[paths]\ncache_dir = "{tmp_path / "tiles"}"\nsession_dir = "{tmp_path / "sessions"}"\n'
    )
    r = run_cli("run", "--config", str(cfg), "--duration", "3", "--frames-every", "1", "--json", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    frames = sorted((tmp_path / "frames").glob("*_bow.png"))
    assert out["frames_rendered"] == len(frames) >= 2
    assert out["ticks"] > 30 and out["live_floes"] > 0
    assert (tmp_path / "run.png").exists() and list((tmp_path / "sessions").iterdir())
