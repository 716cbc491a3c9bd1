"""The ships' pass (``ship.vert``, ``ship.frag``): lit meshes placed by a matrix each, the
own ship and the other vessels in view, and the ridges' sails (``ridge_sails``), which are
drawn with the same program in the world frame."""
from __future__ import annotations

import moderngl
import numpy as np

from bridge_node.render.camera import set_matrix
from bridge_node.render.classes import CLASS_INDEX
from bridge_node.render.passes import glsl
from bridge_node.render.ridge_sails import SailMeshes


class ShipPass:
    """The ship mesh (``ship_triangles``: position, normal, colour per vertex) drawn by matrix."""

    def __init__(self, ctx: moderngl.Context, defines: dict, samplers: dict[str, int], hull: np.ndarray) -> None:
        self.program = glsl.program(ctx, "ship.vert", "ship.frag", **defines)
        glsl.set_present(self.program, **samplers)
        self.vao = ctx.vertex_array(self.program, [(ctx.buffer(hull.tobytes()), "3f 3f 3f", "in_pos", "in_normal",
                                                    "in_colour")])
        self._class, self._to_world = self.program["ship_class"], self.program["ship_to_world"]

    def draw(self, matrices: list[np.ndarray]) -> None:
        """The own ship (the first matrix: ship frame to world) and the other vessels."""
        for k, m in enumerate(matrices):
            self._class.value = CLASS_INDEX["own_ship" if k == 0 else "other_vessel"]
            set_matrix(self._to_world, m)
            self.vao.render()

    def draw_sails(self, sails: SailMeshes, eye: np.ndarray) -> None:
        """The ridges' sails near the eye (built as the ship comes near), as level ice."""
        sails.update(eye)
        self._class.value = CLASS_INDEX["level_ice"]
        set_matrix(self._to_world, np.eye(4))
        sails.render()
