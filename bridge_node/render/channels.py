"""Channel targets: render each channel at its resolution into a framebuffer, then show it
in its window, write it as a PNG frame, or read it back (tests)."""
from __future__ import annotations

import math
from pathlib import Path

import moderngl
import numpy as np

from bridge_node.render.classes import save_legend
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings
from bridge_node.render.video import save_png
from bridge_node.render.warp import WarpMesh, read_pfm
from bridge_node.render.windows import ChannelWindow, window_context
from bridge_node.stream.world_view import WorldView


def create_context() -> moderngl.Context:
    """A headless OpenGL 3.3 context through EGL (Mesa's llvmpipe works without a GPU)."""
    return moderngl.create_standalone_context(backend="egl")


def context_for(channels: list[ChannelSettings]) -> tuple[moderngl.Context, object | None]:
    """The context to draw these channels in: a hidden glfw window's if any channel is shown
    in a window (the channel windows share it), else headless EGL. Returns it with the
    hidden window (None for EGL)."""
    if any(c.output == "window" for c in channels):
        return window_context()
    return create_context(), None


def msaa_samples(ctx: moderngl.Context, setting: str | int) -> int:
    """Samples per pixel for ``render.msaa_samples``: auto is 1 on Mesa's software
    rasteriser (llvmpipe), 4 on a GPU."""
    if setting != "auto":
        return int(setting)
    return 1 if "llvmpipe" in ctx.info["GL_RENDERER"] else 4


def blend_ramp(channel: ChannelSettings, azimuth: np.ndarray) -> np.ndarray:
    """Light share (linear, 0..1) the channel gives at azimuths (rad from its centre). In
    each blend band the light falls linearly with azimuth, so where two channels overlap
    their light sums to one."""
    half = math.radians(channel.hfov_deg) / 2.0
    ramp = np.ones_like(azimuth)
    if channel.blend_left_deg > 0:
        ramp *= np.clip((azimuth + half) / math.radians(channel.blend_left_deg), 0.0, 1.0)
    if channel.blend_right_deg > 0:
        ramp *= np.clip((half - azimuth) / math.radians(channel.blend_right_deg), 0.0, 1.0)
    return ramp


def column_factors(channel: ChannelSettings) -> np.ndarray:
    """The factor each pixel column's colour is scaled by: the blend ramp at the column's
    azimuth, with the projector's gamma undone (the projector raises it to gamma again)."""
    x = (np.arange(channel.width) + 0.5) / channel.width * 2.0 - 1.0
    azimuth = np.arctan(x * math.tan(math.radians(channel.hfov_deg) / 2.0))
    return (blend_ramp(channel, azimuth) ** (1.0 / channel.gamma)).astype("f4")


class ChannelTarget:
    """The framebuffer of one channel: drawn multisampled (``samples`` > 1) and resolved,
    then, with a warp grid, drawn through it, into the colour texture that windows show and
    frames are read from."""

    def __init__(self, ctx: moderngl.Context, channel: ChannelSettings, samples: int) -> None:
        size = (channel.width, channel.height)
        self.channel = channel
        self.colour = ctx.texture(size, 3)  # a texture, so that a channel window can show it
        self.warp = self.flat = None
        if channel.warp is not None:
            self.warp = WarpMesh(ctx, read_pfm(Path(channel.warp),
                                               f"render.channels ({channel.name}): warp = {channel.warp!r}"))
            self.flat = ctx.texture(size, 3)
        drawn = self.flat or self.colour
        if samples > 1:
            self.resolved = ctx.framebuffer([drawn])
            self.draw_fbo = ctx.framebuffer([ctx.renderbuffer(size, 3, samples=samples)],
                                            ctx.depth_renderbuffer(size, samples=samples))
        else:
            self.resolved = self.draw_fbo = ctx.framebuffer([drawn], ctx.depth_renderbuffer(size))
        self.fbo = ctx.framebuffer([self.colour]) if self.warp else self.resolved
        self.blend = ctx.texture((channel.width, 1), 1, column_factors(channel).tobytes(), dtype="f4")
        self.blend.filter = moderngl.NEAREST, moderngl.NEAREST
        self.class_fbo: moderngl.Framebuffer | None = None  # made when a class mask is first asked for

    def render(self, renderer: SceneRenderer, view: WorldView) -> None:
        self.draw_fbo.use()
        renderer.draw(view, self.channel, self.blend)
        if self.draw_fbo is not self.resolved:
            renderer.ctx.copy_framebuffer(self.resolved, self.draw_fbo)  # resolve the samples
        if self.warp is not None:
            self.fbo.use()
            renderer.ctx.disable(moderngl.DEPTH_TEST)
            self.warp.draw(self.flat)

    def image(self) -> np.ndarray:
        """The last frame as (height, width, 3) uint8, top row first."""
        return _read(self.fbo, self.channel)

    def class_image(self, renderer: SceneRenderer, view: WorldView) -> np.ndarray:
        """The channel's class mask (``classes``) of the view, drawn flat (before any warp)
        from the same camera: (height, width, 3) uint8, top row first."""
        if self.class_fbo is None:  # one sample per pixel: each pixel one class colour
            size = (self.channel.width, self.channel.height)
            self.class_fbo = renderer.ctx.framebuffer([renderer.ctx.renderbuffer(size, 3)],
                                                      renderer.ctx.depth_renderbuffer(size))
        self.class_fbo.use()
        renderer.draw(view, self.channel, self.blend, classes=True)
        return _read(self.class_fbo, self.channel)


def _read(fbo: moderngl.Framebuffer, channel: ChannelSettings) -> np.ndarray:
    raw = fbo.read(components=3, alignment=1)
    return np.frombuffer(raw, dtype=np.uint8).reshape(channel.height, channel.width, 3)[::-1]


class ChannelSet:
    """All channels of a projection system over one scene renderer."""

    def __init__(self, renderer: SceneRenderer, channels: list[ChannelSettings], hidden_window=None) -> None:
        self.renderer = renderer
        samples = msaa_samples(renderer.ctx, renderer.settings.msaa_samples)
        self.targets = [ChannelTarget(renderer.ctx, c, samples) for c in channels]
        self.windows = [ChannelWindow(renderer.ctx, hidden_window, t.channel, t.colour)
                        for t in self.targets if t.channel.output == "window"]

    def render(self, view: WorldView) -> None:
        """Draw every channel of the view's state, and show the window channels."""
        self.renderer.update(view)
        for t in self.targets:
            t.render(self.renderer, view)
        self.renderer.ctx.finish()
        for w in self.windows:
            w.present()

    def save_png(self, folder: Path, stem: str = "") -> list[Path]:
        """Write the last frame of every PNG-output channel to ``folder/<stem><name>.png``."""
        return [save_png(t.image(), folder / f"{stem}{t.channel.name}.png") for t in self.targets
                if t.channel.output == "png"]

    def class_images(self, view: WorldView) -> list[np.ndarray]:
        """The class mask of every channel of the view's state, in channel order."""
        self.renderer.update(view)
        return [t.class_image(self.renderer, view) for t in self.targets]

    def save_class_pngs(self, view: WorldView, folder: Path, stem: str = "") -> list[Path]:
        """Write the class mask of every PNG-output channel beside its frame, as
        ``folder/<stem><name>_classes.png``, and the legend as ``folder/classes_legend.png``."""
        paths = [save_png(image, folder / f"{stem}{t.channel.name}_classes.png")
                 for t, image in zip(self.targets, self.class_images(view)) if t.channel.output == "png"]
        return paths + [save_legend(folder / "classes_legend.png")]

    def images(self) -> list[np.ndarray]:
        """The last frame of every channel, in channel order."""
        return [t.image() for t in self.targets]
