"""The edge-blend pass (``blend_bands.vert``, ``blend_bands.frag``): the channel's last
pass, over its blend bands only, multiplying what is there by each column's factor."""
from __future__ import annotations

import math

import moderngl
import numpy as np

from bridge_node.render.passes import glsl
from bridge_node.render.settings import ChannelSettings

BLEND_UNIT = 6  # texture unit of the channel's blend ramp


class BlendBandPass:
    """Multiplies the columns of a channel's blend bands by their factors."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.program = glsl.program(ctx, "blend_bands.vert", "blend_bands.frag")
        self.program["blend_ramp"].value = BLEND_UNIT
        self.buffer = ctx.buffer(reserve=2 * 6 * 2 * 4)
        self.vao = ctx.vertex_array(self.program, [(self.buffer, "2f", "in_ndc")])

    def draw(self, channel: ChannelSettings, blend: moderngl.Texture) -> None:
        """The channel's bands (its blend texture: width x 1 float, the factors)."""
        t = math.tan(math.radians(channel.hfov_deg) / 2)
        spans = []
        if channel.blend_left_deg > 0:
            spans.append((-1.0, math.tan(math.radians(channel.blend_left_deg - channel.hfov_deg / 2)) / t))
        if channel.blend_right_deg > 0:
            spans.append((math.tan(math.radians(channel.hfov_deg / 2 - channel.blend_right_deg)) / t, 1.0))
        if not spans:
            return
        quads = np.array([[[a, -1], [b, -1], [b, 1], [a, -1], [b, 1], [a, 1]] for a, b in spans], dtype="f4")
        self.buffer.orphan(quads.nbytes)
        self.buffer.write(quads.tobytes())
        ctx = self.ctx
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ZERO, moderngl.SRC_COLOR
        blend.use(BLEND_UNIT)
        self.vao.render(vertices=6 * len(spans))
        ctx.disable(moderngl.BLEND)
