"""Benchmark: the class mask against the shaded frame (``icebridge render-snapshot
--classes``), and the masks themselves to look at.

The default exercise with a broken channel of 3000 free floes ahead of the ship (as
bench_render lays it); N channels at WIDTHxHEIGHT looking up it. Interleaved in one process,
so that the machine's load falls on both alike: a shaded frame (every channel drawn and
edge-blended, glFinish) and a class frame (every channel's mask drawn and read back). Prints
both medians, their ratio and the core count, and the share of each class in the centre
channel's mask; writes the centre channel's frame and mask as PNGs to --out.
Run: .venv/bin/python benchmarks/bench_classes.py [--channels 3] [--size 1280x720] [--frames 20] [--out out]
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_render import channels, world_with_floes  # noqa: E402 (the benchmarks folder, not a package)

from bridge_node.render.channels import ChannelSet, create_context  # noqa: E402
from bridge_node.render.classes import class_shares, save_legend  # noqa: E402
from bridge_node.render.renderer import SceneRenderer  # noqa: E402
from bridge_node.render.settings import RenderSettings  # noqa: E402
from bridge_node.render.video import save_png  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--channels", type=int, default=3, choices=(1, 3, 5))
    ap.add_argument("--size", default="1280x720", help="WIDTHxHEIGHT of each channel")
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--out", default="out")
    args = ap.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    ctx = create_context()
    model, data, view = world_with_floes(3000)
    chans = [c.model_copy(update={"output": "png", "pitch_deg": -6.0}) for c in channels(args.channels, width, height)]
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=chans)), chans)
    cs.render(view)  # warm-up: shaders compiled, first upload
    cs.class_images(view)
    times = {"shaded": [], "classes": []}
    for _ in range(args.frames):
        view.ship = dataclasses.replace(view.ship, heading=view.ship.heading + 1e-4)
        t0 = time.perf_counter()
        cs.render(view)
        times["shaded"].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        masks = cs.class_images(view)
        times["classes"].append(time.perf_counter() - t0)
    med = {k: float(np.median(v)) * 1e3 for k, v in times.items()}
    print(f"class mask benchmark on {ctx.info['GL_RENDERER']}: {args.channels} x {width}x{height}, "
          f"{args.frames} interleaved rounds, {os.cpu_count()} CPUs")
    print(f"  shaded frame: median {med['shaded']:7.1f} ms (render + glFinish)")
    print(f"  class frame:  median {med['classes']:7.1f} ms (render + read back)")
    print(f"  class / shaded: {med['classes'] / med['shaded']:.2f}")
    centre = len(chans) // 2
    shares = class_shares(masks[centre])
    print("  centre channel's classes: " + ", ".join(f"{k} {100 * v:.1f} %" for k, v in shares.items() if v > 0))
    out = Path(args.out)
    save_png(cs.images()[centre], out / "bench_classes_frame.png")
    save_png(masks[centre], out / "bench_classes_mask.png")
    save_legend(out / "classes_legend.png")
    print(f"  wrote {out / 'bench_classes_frame.png'}, {out / 'bench_classes_mask.png'}")


if __name__ == "__main__":
    main()
