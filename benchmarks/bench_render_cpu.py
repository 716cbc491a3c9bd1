"""Benchmark: the CPU side of drawing one channel (issue 28, item 4).

A GPU does a channel's pixels and vertices itself; what the CPU pays per channel per frame
is the Python that sequences the passes and the GL calls it makes. On llvmpipe the GL
draw calls also do the vertex and pixel work on the calling thread, so this times each
channel's ``SceneRenderer.draw`` and takes out the time spent inside the draw calls
(``VertexArray.render``): what remains is the CPU time a GPU machine's driver thread
would also see, but for the driver's own submission cost. It counts per channel the draw
calls, the uniform writes (``Uniform.value`` and ``Uniform.write``) and the uniform buffer
writes and bindings, by wrapping those moderngl methods. llvmpipe defers some of a draw's
work to later GL calls, so that figure still holds some of it; ``--stub-draws`` replaces
the draw calls with no-ops (nothing is drawn), leaving the Python and the other GL calls
alone: the closest this machine comes to the CPU time per channel on a GPU.

Setup: the default exercise with 10 000 live broken floes (as ``bench_render``), 5 channels
at 320x180 (small, so that pixel work does not dominate the wall time), 40 frames after a
warm-up frame. The floes' draw calls grow with the tiles in view, so the counts are per
channel and also per tile drawn. Prints the core count beside each time.
Run: .venv/bin/python benchmarks/bench_render_cpu.py [--frames N] [--floes N] [--stub-draws]
                                                      [--compare-rev REV]
--compare-rev REV measures the render code of git revision REV too, in the same process, their
frames interleaved, and prints the ratio of the medians.
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib
import os
import time
from collections import Counter

import moderngl
import numpy as np

import bridge_node.render.channels as channels_module
import bridge_node.render.renderer as renderer_module
import bridge_node.render.settings as settings_module
from bench_render import channels, fresh_view, render_package, world_with_floes
from bridge_node.render.channels import ChannelSet, create_context

COUNTED = (("render", moderngl.VertexArray, "render"), ("uniform write", moderngl.Uniform, "write"),
           ("buffer write", moderngl.Buffer, "write"), ("block binding", moderngl.Buffer, "bind_to_uniform_block"))


class Calls:
    """Counts of the wrapped moderngl calls, and the wall time spent inside draw calls."""

    def __init__(self) -> None:
        self.count: Counter = Counter()
        self.render_s = 0.0
        self.stub_draws = False

    def install(self) -> None:
        for name, cls, attr in COUNTED:
            setattr(cls, attr, self._wrapped(name, getattr(cls, attr)))
        value = moderngl.Uniform.value
        calls = self

        def set_value(uniform, v):
            calls.count["uniform write"] += 1
            value.fset(uniform, v)
        moderngl.Uniform.value = property(value.fget, set_value)

    def _wrapped(self, name: str, method):
        calls = self

        def counted(*args, **kwargs):
            calls.count[name] += 1
            if name != "render":
                return method(*args, **kwargs)
            if calls.stub_draws:
                return None
            t0 = time.perf_counter()
            try:
                return method(*args, **kwargs)
            finally:
                calls.render_s += time.perf_counter() - t0
        return counted


@dataclasses.dataclass
class Side:
    """One renderer measured: its channels, its own view of the world, and per channel the
    CPU time (s), the draw calls and the other calls counted."""

    name: str
    renderer: object
    channels: ChannelSet
    view: object
    cpu: list = dataclasses.field(default_factory=list)
    draws: list = dataclasses.field(default_factory=list)
    count: Counter = dataclasses.field(default_factory=Counter)


def side(name: str, ctx, model, data, package=None) -> Side:
    """A renderer of the working tree's render code, or of ``package``'s (``render_package``)."""
    rend, sets, chan = ((importlib.import_module(f"{package.__name__}.{m}") for m in ("renderer", "settings", "channels"))
                        if package else (renderer_module, settings_module, channels_module))
    chans = [sets.ChannelSettings(**c.model_dump()) for c in channels(5, 320, 180)]
    renderer = rend.SceneRenderer(ctx, model, sets.RenderSettings(channels=chans))
    s = Side(name, renderer, chan.ChannelSet(renderer, chans), fresh_view(model, data))
    s.channels.render(s.view)  # warm-up: compile, first upload
    return s


def frame(s: Side, calls: Calls) -> None:
    """Draw every channel of one frame, timing each draw less its draw calls."""
    s.view.ship = dataclasses.replace(s.view.ship, heading=s.view.ship.heading + 1e-4)  # the view moves a little
    before = calls.count.copy()
    s.renderer.update(s.view)
    for target in s.channels.targets:
        s.renderer.ctx.finish()
        target.draw_fbo.use()
        calls.render_s, draws = 0.0, calls.count["render"]
        t0 = time.perf_counter()
        s.renderer.draw(s.view, target.channel, target.blend)
        s.cpu.append(time.perf_counter() - t0 - calls.render_s)
        s.draws.append(calls.count["render"] - draws)
    s.renderer.ctx.finish()
    s.count += calls.count - before


def report(s: Side, cores: int) -> float:
    """Print one side's figures; returns its median CPU time per channel (ms)."""
    ms = np.array(s.cpu) * 1e3
    n = len(s.cpu)
    print(f"{s.name}: CPU per channel median {np.median(ms):.3f} ms, p99 {np.percentile(ms, 99):.3f} ms "
          f"({cores} cores); per channel: " + ", ".join(f"{name} {s.count[name] / n:.1f}" for name, _, _ in COUNTED)
          + f"; draw calls {min(s.draws)}-{max(s.draws)}")
    return float(np.median(ms))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--floes", type=int, default=10_000)
    ap.add_argument("--stub-draws", action="store_true", help="draw calls as no-ops: the CPU side alone")
    ap.add_argument("--compare-rev", metavar="REV", help="also the render code of git revision REV, frames interleaved")
    args = ap.parse_args()
    model, data, _ = world_with_floes(args.floes)
    ctx = create_context()
    sides = [side("working tree", ctx, model, data)]
    if args.compare_rev:
        sides.insert(0, side(args.compare_rev, ctx, model, data, render_package(args.compare_rev)))
    calls = Calls()
    calls.install()
    calls.stub_draws = args.stub_draws
    for k in range(args.frames):
        for s in (sides if k % 2 == 0 else sides[::-1]):
            frame(s, calls)
    cores = os.cpu_count()
    what = "the draw calls as no-ops" if args.stub_draws else "time outside the draw calls"
    print(f"{args.floes} floes, 5 channels at 320x180, {args.frames} frames, {what}, {ctx.info['GL_RENDERER']}")
    medians = [report(s, cores) for s in sides]
    if len(medians) == 2:
        print(f"working tree / {args.compare_rev}: {medians[1] / medians[0]:.2f} ({cores} cores, frames interleaved)")


if __name__ == "__main__":
    main()
