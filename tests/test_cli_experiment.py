"""``icebridge experiment`` as a user runs it: JSON results, plots, clear errors."""
import json

import av
import numpy as np
from conftest import exercise_toml, run_cli
from PIL import Image


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


def test_run_streams_to_a_render_process_that_writes_frames_video_and_panorama(tmp_path):
    """The main job, headless: physics in one process, the channels drawn by a render process
    from the state stream, which writes PNG frames, a video and a panorama that show ice."""
    cfg = exercise_toml(tmp_path, '[[render.channels]]\nname = "bow"\nwidth = 160\nheight = 90\npitch_deg = -10.0\n'
                                  '[[render.channels]]\nname = "aft"\nwidth = 160\nheight = 90\nyaw_deg = 180.0\n')
    r = run_cli("run", "--config", str(cfg), "--duration", "4", "--frames-every", "1", "--json", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    frames = sorted((tmp_path / "frames").glob("*_bow.png"))
    assert out["frames_rendered"] == 2 * len(frames) and len(frames) >= 2
    assert out["ticks"] > 30 and out["live_floes"] > 0
    assert out["stream"]["sent"] == out["ticks"] + 1 and out["stream"]["dropped"] == 0
    proc, = out["render_processes"]
    assert proc["exit"] == 0 and proc["restarts"] == 0 and proc["frames"] > 2 and proc["channels"] == ["bow", "aft"]
    panorama = np.asarray(Image.open(out["panorama"][0]))
    assert panorama.shape == (90, 320, 3) and panorama.std() > 10  # a picture, not a flat image
    assert (panorama.mean(axis=-1) > 170).mean() > 0.05  # with bright ice in it
    with av.open(out["video"][0]) as video:
        pictures = [f.to_ndarray(format="rgb24") for f in video.decode(video=0)]
    assert len(pictures) >= 2 and all(p.std() > 10 for p in pictures)
    assert (tmp_path / "run.png").exists() and list((tmp_path / "sessions").iterdir())
