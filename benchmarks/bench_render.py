"""Benchmark: frames per second of the projector channels.

1, 3 and 5 channels at 1280x720 and 1920x1080 with 3000 and 10000 live floes, offscreen on
EGL (here Mesa llvmpipe on the CPU; on a GPU machine, the GPU). A frame = upload of what
changed (poses of the live tiles) + every channel drawn and edge-blended + glFinish; no
readback (a projector shows the framebuffer). Baseline in the same process: the same
frames without the level of detail (every floe's side faces drawn at any distance).
Targets: llvmpipe, 3 channels at 1280x720 with 3000 floes >= 15 FPS; GPU, 5 channels at
1920x1080 with 10000 floes >= 60 FPS.
Run: .venv/bin/python benchmarks/bench_render.py [--frames N]
     .venv/bin/python benchmarks/bench_render.py --compare [--frames N]
     .venv/bin/python benchmarks/bench_render.py --case 3:1280x720:3000 [--frames N]
     .venv/bin/python benchmarks/bench_render.py --compare-rev HEAD [--frames N]
--case measures one setup only (channels:WIDTHxHEIGHT:floes), without the baseline.
--compare-rev REV measures the llvmpipe target's case with the render code (bridge_node/render)
of git revision REV against the working tree's, interleaved likewise.
--compare-reflections measures the llvmpipe target's case without the floes' reflections
in the sea (render.reflection_distance_m = 0) against the defaults, interleaved likewise.
--compare measures only the llvmpipe target's case (3 channels at 1280x720, 3000 floes):
the look as it was before the cheaper shading (4x MSAA, every relief octave at any
distance, bilinear noise fetches) against the defaults (MSAA auto: 1 on llvmpipe, relief
octaves within their reach, nearest-texel noise fetches when minified), their
frames interleaved in one process so that the machine's load falls on both alike.
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib
import os
import subprocess
import sys
import tempfile
import time
import types
from pathlib import Path

import moderngl
import numpy as np

import bridge_node.render.channels as channels_module
import bridge_node.render.renderer as renderer_module
import bridge_node.render.settings as settings_module
from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, create_context
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.world_view import WorldView
from sim_core.frames.ship_frame import ship_to_world
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.tiles import break_cells
from sim_core.scene.scene import update_scene
from sim_core.scene.switches import apply_swaps
from sim_core.world import snapshot


def world_with_floes(target: int):
    """The default exercise with a broken channel of ``target`` free floes north of the
    ship, which looks up it from its start (no reverse replacement: all of it stays live)."""
    cfg = load_config()
    cfg = cfg.model_copy(update={"scene": cfg.scene.model_copy(update={"reverse_replacement": False})})
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    east, north = data.ship.eta[1], 0.0
    st = data.ice.state
    while st.count(FloeStatus.FREE) < target:
        pts = ship_to_world(model.contour, north, east, 0.0)
        apply_swaps(model, data, update_scene(model.scene, data.scene, pts, np.array([east, north])))
        rows = np.nonzero((st.status == FloeStatus.INTACT) & (np.abs(st.home[:, 0] - east) < 18.0)
                          & (st.home[:, 1] < north + 50.0))[0]
        break_cells(data.ice, rows[: target - st.count(FloeStatus.FREE)], BreakCause.HULL)
        north += 50.0
    data.ship.eta[0] = -80.0
    return model, data, fresh_view(model, data)


def fresh_view(model, data) -> WorldView:
    """A view of the world's state for one renderer: a view hands its changes (the broken
    floes whose triangles a renderer appends) out once."""
    view = WorldView()
    view.apply(snapshot(model, data))
    return view


def channels(n: int, width: int, height: int) -> list[ChannelSettings]:
    yaws = {1: [0.0], 3: [-55.0, 0.0, 55.0], 5: [-110.0, -55.0, 0.0, 55.0, 110.0]}[n]
    return [ChannelSettings(name=f"ch{k}", yaw_deg=y, width=width, height=height, output="none",
                            blend_left_deg=5.0 if k > 0 else 0.0, blend_right_deg=5.0 if k < n - 1 else 0.0)
            for k, y in enumerate(yaws)]


def fps(cs: ChannelSet, view: WorldView, frames: int) -> tuple[float, float]:
    cs.render(view)  # warm-up: compile shaders, first upload
    times = []
    for _ in range(frames):
        view.ship = dataclasses.replace(view.ship, heading=view.ship.heading + 1e-4)  # the view moves a little
        t0 = time.perf_counter()
        cs.render(view)
        times.append(time.perf_counter() - t0)
    ms = np.array(times) * 1e3
    return 1e3 / float(np.median(ms)), float(np.percentile(ms, 99))


BEFORE = {"msaa_samples": 4, "relief_reach_m": 1.0e7}  # the look before its cheaper shading
NO_REFLECTIONS = {"reflection_distance_m": 0.0}  # the look before the floes' reflections


def render_package(rev: str) -> types.ModuleType:
    """bridge_node.render as it was at git revision `rev`, imported under another name."""
    name = "render_" + "".join(c if c.isalnum() else "_" for c in rev)
    folder = Path(tempfile.mkdtemp(prefix="bench_render_"))
    repo = Path(__file__).resolve().parents[1]
    for path in subprocess.run(["git", "ls-tree", "-r", "--name-only", rev, "bridge_node/render/"], cwd=repo,
                               check=True, capture_output=True, text=True).stdout.split():
        source = subprocess.run(["git", "show", f"{rev}:{path}"], cwd=repo, check=True, capture_output=True,
                                text=True).stdout
        target = folder / name / Path(path).relative_to("bridge_node/render")  # (the passes' GLSL beside them)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(source.replace("bridge_node.render", name) if path.endswith(".py") else source)
    sys.path.insert(0, str(folder))
    return importlib.import_module(name)


def channel_set(ctx, model, look: dict, package: types.ModuleType | None = None):
    """The llvmpipe target's 3 channels at 1280x720 with the `look` settings, drawn by the
    working tree's render code or by that of `package` (see render_package)."""
    names = ("channels", "renderer", "settings")
    chan, rend, sets = ((importlib.import_module(f"{package.__name__}.{m}") for m in names) if package
                        else (channels_module, renderer_module, settings_module))
    chans = [sets.ChannelSettings(**c.model_dump()) for c in channels(3, 1280, 720)]
    return chan.ChannelSet(rend.SceneRenderer(ctx, model, sets.RenderSettings(channels=chans, **look)), chans)


def compare(ctx, frames: int, before: dict, bilinear_before: bool, rev: str | None = None) -> None:
    """Frame times of the look with the `before` settings (and bilinear noise fetches if
    asked; with the render code of git revision `rev` if given) and of the defaults with the
    working tree's code, interleaved."""
    model, data, _ = world_with_floes(3000)
    looks = {"before": before, "after": {}}
    old = render_package(rev) if rev is not None else None
    sets = []
    for name, look in looks.items():
        view = fresh_view(model, data)
        cs = channel_set(ctx, model, look, old if name == "before" else None)
        if bilinear_before and name == "before":
            cs.renderer.noise.filter = moderngl.LINEAR_MIPMAP_NEAREST, moderngl.LINEAR
        cs.render(view)  # warm-up
        sets.append((name, cs, view))
    times = {name: [] for name in looks}
    for _ in range(frames):
        for name, cs, view in sets:
            view.ship = dataclasses.replace(view.ship, heading=view.ship.heading + 1e-4)
            t0 = time.perf_counter()
            cs.render(view)
            times[name].append(time.perf_counter() - t0)
    med = {name: float(np.median(t)) * 1e3 for name, t in times.items()}
    for name in looks:
        print(f"  {name}: {1e3 / med[name]:5.1f} FPS (median frame {med[name]:6.1f} ms)")
    print(f"  after / before frame time: {med['after'] / med['before']:.2f} "
          f"(FPS x{med['before'] / med['after']:.2f}); {os.cpu_count()} CPUs, {frames} interleaved rounds")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--compare", action="store_true", help="before/after the cheaper shading, llvmpipe target only")
    ap.add_argument("--compare-reflections", action="store_true",
                    help="without/with the floes' reflections, llvmpipe target only")
    ap.add_argument("--compare-rev", metavar="REV",
                    help="the render code of git revision REV against the working tree's, llvmpipe target only")
    ap.add_argument("--case", help="one setup only, CHANNELS:WIDTHxHEIGHT:FLOES (e.g. 3:1280x720:3000)")
    args = ap.parse_args()
    ctx = create_context()
    print(f"render benchmark on {ctx.info['GL_RENDERER']} ({ctx.info['GL_VERSION']})")
    if args.compare or args.compare_reflections:
        compare(ctx, args.frames, BEFORE if args.compare else NO_REFLECTIONS, args.compare)
        return
    if args.compare_rev:
        compare(ctx, args.frames, {}, False, args.compare_rev)
        return
    if args.case:
        n, size, floes = args.case.split(":")
        width, height = (int(v) for v in size.split("x"))
        model, _, view = world_with_floes(int(floes))
        chans = channels(int(n), width, height)
        f, p99 = fps(ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=chans)), chans), view, args.frames)
        print(f"  {n} channel(s) {width}x{height}, {floes} floes: {f:6.1f} FPS (p99 frame {p99:6.1f} ms); "
              f"{os.cpu_count()} CPUs, median of {args.frames} frames")
        return
    for target in (3000, 10000):
        model, data, _ = world_with_floes(target)
        print(f"{data.ice.state.count(FloeStatus.FREE)} live floes, {data.ice.state.n} cells placed")
        for width, height in ((1280, 720), (1920, 1080)):
            for n in (1, 3, 5):
                chans = channels(n, width, height)
                cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=chans)), chans)
                f, p99 = fps(cs, fresh_view(model, data), args.frames)
                line = f"  {n} channel(s) {width}x{height}: {f:6.1f} FPS (p99 frame {p99:6.1f} ms)"
                if n == 3 and width == 1280:
                    flat = RenderSettings(channels=chans, lod_distance_m=1.0e6)
                    base, _ = fps(ChannelSet(SceneRenderer(ctx, model, flat), chans), fresh_view(model, data), args.frames)
                    line += f"; baseline without level of detail {base:6.1f} FPS ({f / base:4.2f}x)"
                print(line)
    print(f"(median of {args.frames} frames per setup)")


if __name__ == "__main__":
    main()
