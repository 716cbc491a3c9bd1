"""The navigation lights' pass (``nav_lights.vert``, ``nav_lights.frag``): points of a few
pixels, shown only where the eye is inside a light's sector, added to the image as
strongly as the daylight leaves them visible, fogged by the visibility."""
from __future__ import annotations

import moderngl
import numpy as np

from bridge_node.render.camera import set_matrix
from bridge_node.render.passes import glsl


class NavLightPass:
    """Every ship's navigation lights (``ship_mesh.nav_lights``: position, colour, sector)."""

    def __init__(self, ctx: moderngl.Context, defines: dict, points: np.ndarray) -> None:
        self.ctx = ctx
        self.program = glsl.program(ctx, "nav_lights.vert", "nav_lights.frag", **defines)
        self.vao = ctx.vertex_array(self.program, [(ctx.buffer(points.tobytes()), "3f 3f 2f", "in_pos", "in_colour",
                                                    "in_sector")])
        self._to_world = self.program["ship_to_world"]
        self._point_px, self._strength = self.program["point_px"], self.program["strength"]

    def draw(self, matrices: list[np.ndarray], height: int, strength: float) -> None:
        """The lights of the ships placed by the matrices (ship frame to world), for a
        channel ``height`` pixels high, at ``strength`` (1 at night)."""
        if strength < 0.01:
            return
        ctx = self.ctx
        ctx.enable(moderngl.PROGRAM_POINT_SIZE | moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        ctx.depth_mask = False
        self._point_px.value = max(3.0, 6.0 * height / 720)
        self._strength.value = strength
        for m in matrices:
            set_matrix(self._to_world, m)
            self.vao.render(moderngl.POINTS)
        ctx.depth_mask = True
        ctx.disable(moderngl.PROGRAM_POINT_SIZE | moderngl.BLEND)
