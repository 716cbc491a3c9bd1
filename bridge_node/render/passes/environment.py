"""The environment pass (``screen.vert``, ``environment.frag``, ``sky.frag``): below the
horizon, sea and level ice per pixel (the unbreakable slab, the intact cells of breakable
tiles from their template's cell raster, a floe field's tiles not simulated, brash and
ridge sails where the field has them); above it, the sky, as a program of its own (on
llvmpipe a branch does not skip work, so within one pass every sky pixel would pay for the
ground). Its constants (the field, the rasters, the texture units, the ridges) are set
once, when it is made."""
from __future__ import annotations

import math

import moderngl
import numpy as np

from bridge_node.render.camera import Camera
from bridge_node.render.floe_buffers import horizon_split
from bridge_node.render.passes import glsl
from bridge_node.render.settings import ChannelSettings


class EnvironmentPass:
    """Sea, level ice and sky, per pixel, for any channel."""

    def __init__(self, ctx: moderngl.Context, defines: dict, constants: dict) -> None:
        self.ground = glsl.program(ctx, "screen.vert", "environment.frag", **defines)
        self.sky = glsl.program(ctx, "screen.vert", "sky.frag", **defines)
        glsl.set_present(self.ground, **constants)
        glsl.set_present(self.sky, **constants)
        self.buffer = ctx.buffer(reserve=2 * 9 * 5 * 4)  # ground, then sky: 3 triangles each at most
        self.ground_vao = ctx.vertex_array(self.ground, [(self.buffer, "2f 3f", "in_ndc", "in_ray")])
        self.sky_vao = ctx.vertex_array(self.sky, [(self.buffer, "2f 3f", "in_ndc", "in_ray")])

    def draw(self, cam: Camera, channel: ChannelSettings) -> None:
        """The ground below the channel's horizon and the sky above it."""
        half = math.radians(channel.hfov_deg) / 2
        ground, above = horizon_split(cam, math.tan(half), math.tan(channel.vfov() / 2), channel.width,
                                      channel.height)
        self.buffer.write(np.vstack([ground, above]).astype("f4").tobytes())
        if len(ground):
            self.ground_vao.render(vertices=len(ground))
        if len(above):
            self.sky_vao.render(vertices=len(above), first=len(ground))
