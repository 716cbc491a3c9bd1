"""Benchmark: ``icebridge replay --max`` of a 10 km track through 0.5 m ice.

A ship logged at 8 kn for 10 km (a CSV track, a fix every 2 s, a slow S-bend) on a
1 km x 10.4 km field of 0.5 m ice in 100 m tiles, replayed as a user would run it (the CLI
in its own process), without and with the render processes. Prints the replay speed in
logged (simulated) seconds per wall second, over the replay loop and over the whole
command, with the world step and the machine's core count.
Run: .venv/bin/python benchmarks/bench_replay.py [--steps 0.5,0.2] [--no-render]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from conftest import REPO, free_port  # noqa: E402
from replay_logs import KNOT, csv_text, voyage  # noqa: E402


def ten_km_track(folder: Path) -> Path:
    fixes = voyage(duration=10_000.0 / (8.0 * KNOT), every=2.0, speed_kn=8.0, turn_after=600.0, rate_deg_s=0.02)
    path = folder / "ten_km.csv"
    path.write_text(csv_text(fixes))
    return path


def config(folder: Path, step: float) -> Path:
    path = folder / f"bench_{step:g}.toml"
    path.write_text(f'[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 1000.0\nheight = 10400.0\nthickness = 0.5\n'
                    f'[replay]\nstep_s = {step}\n'
                    f'[stream]\npublish = "tcp://127.0.0.1:{free_port()}"\nsnapshot = "tcp://127.0.0.1:{free_port()}"\n'
                    f'[[links]]\nname = "instruments"\ntype = "nmea0183"\nudp_port = {free_port()}\n')
    return path


def replay(track: Path, cfg: Path, render: str, out: Path) -> dict:
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "bridge_node", "replay", str(track), "--config", str(cfg), "--max",
                           "--render", render, "--json", "--out", str(out)], capture_output=True, text=True, cwd=REPO)
    if done.returncode:
        raise SystemExit(done.stderr)
    return json.loads(done.stdout) | {"command_wall_s": time.monotonic() - t0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", default="0.5", help="world steps to compare, s (default: the config's 0.5)")
    parser.add_argument("--no-render", action="store_true", help="skip the runs with render processes")
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        track = ten_km_track(folder)
        for step in (float(s) for s in args.steps.split(",")):
            for render in ("none",) if args.no_render else ("none", "local"):
                s = replay(track, config(folder, step), render, folder / f"out_{step:g}_{render}")
                frames = sum(r.get("frames", 0) for r in s["render_processes"])
                print(f"step {step:g} s, render {render:5}: {s['distance_m'] / 1000:.2f} km in {s['duration_s']:.0f} s "
                      f"logged; replay loop {s['wall_s']:.1f} s wall = {s['speed_x']:.1f} x real time; whole command "
                      f"{s['command_wall_s']:.1f} s = {s['duration_s'] / s['command_wall_s']:.1f} x; cells broken "
                      f"{s['cells_broken']['by_hull']} by the hull, {s['cells_broken']['by_contact']} by contact"
                      + (f"; {frames} frames rendered" if render == "local" else ""), flush=True)


if __name__ == "__main__":
    main()
