"""Offscreen channel targets: render each channel at its resolution, apply its edge-blend
ramps in a second pass, and read the image back (for PNG frames or tests)."""
from __future__ import annotations

import math
from pathlib import Path

import moderngl
import numpy as np

from bridge_node.render import shaders
from bridge_node.render.render_settings import ChannelSettings
from bridge_node.render.scene_renderer import SceneRenderer
from sim_core.world import WorldData


def create_context() -> moderngl.Context:
    """A headless OpenGL 3.3 context through EGL (Mesa's llvmpipe works without a GPU)."""
    return moderngl.create_standalone_context(backend="egl")


def blend_ramp(channel: ChannelSettings, azimuth: np.ndarray) -> np.ndarray:
    """Light share (linear, 0..1) the channel gives at azimuths (rad from its centre): the
    same ramp the blend shader applies, for checks."""
    half = math.radians(channel.hfov_deg) / 2.0
    ramp = np.ones_like(azimuth)
    if channel.blend_left_deg > 0:
        ramp *= np.clip((azimuth + half) / math.radians(channel.blend_left_deg), 0.0, 1.0)
    if channel.blend_right_deg > 0:
        ramp *= np.clip((half - azimuth) / math.radians(channel.blend_right_deg), 0.0, 1.0)
    return ramp


class ChannelTarget:
    """Framebuffers of one channel."""

    def __init__(self, ctx: moderngl.Context, channel: ChannelSettings, blend: moderngl.Program,
                 quad: moderngl.Buffer) -> None:
        size = (channel.width, channel.height)
        self.channel = channel
        self.colour = ctx.texture(size, 3)
        self.scene_fbo = ctx.framebuffer([self.colour], ctx.depth_renderbuffer(size))
        self.out_fbo = ctx.framebuffer([ctx.renderbuffer(size, 3)])
        self.blend = blend
        self.blend_vao = ctx.vertex_array(blend, [(quad, "2f", "in_ndc")])

    def render(self, renderer: SceneRenderer, data: WorldData) -> None:
        c = self.channel
        self.scene_fbo.use()
        renderer.draw(data, c)
        self.out_fbo.use()
        self.colour.use(0)
        half = math.radians(c.hfov_deg) / 2
        for name, value in (("scene", 0), ("tan_half_hfov", math.tan(half)), ("half_hfov", half),
                            ("blend_left", math.radians(c.blend_left_deg)),
                            ("blend_right", math.radians(c.blend_right_deg)), ("gamma", c.gamma)):
            self.blend[name].value = value
        self.blend_vao.render()

    def image(self, blended: bool = True) -> np.ndarray:
        """The last frame as (height, width, 3) uint8, top row first."""
        fbo = self.out_fbo if blended else self.scene_fbo
        raw = fbo.read(components=3, alignment=1)
        return np.frombuffer(raw, dtype=np.uint8).reshape(self.channel.height, self.channel.width, 3)[::-1]


class ChannelSet:
    """All channels of a projection system over one scene renderer."""

    def __init__(self, renderer: SceneRenderer, channels: list[ChannelSettings]) -> None:
        ctx = renderer.ctx
        self.renderer = renderer
        blend = ctx.program(vertex_shader=shaders.BLEND_VS, fragment_shader=shaders.BLEND_FS)
        self.targets = [ChannelTarget(ctx, c, blend, renderer.quad) for c in channels]

    def render(self, data: WorldData) -> None:
        self.renderer.update(data)
        for t in self.targets:
            t.render(self.renderer, data)
        self.renderer.ctx.finish()

    def save_png(self, folder: Path, stem: str = "") -> list[Path]:
        from PIL import Image

        folder.mkdir(parents=True, exist_ok=True)
        paths = []
        for t in self.targets:
            if t.channel.output != "png":
                continue
            path = folder / f"{stem}{t.channel.name}.png"
            Image.fromarray(t.image()).save(path)
            paths.append(path)
        return paths
