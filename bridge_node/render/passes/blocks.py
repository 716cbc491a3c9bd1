"""The uniform buffers the scene's programs share (``blocks.glsl``).

``Scene`` holds what is the same for every channel of a frame (sun, sky, visibility, the
clock, the searchlights): written once per frame, in ``SceneRenderer.update``. ``View``
holds the channel's camera and whether it draws the class mask: written once per channel.
Every program reads both through the same binding points, so a channel's draw sets no
per-program copies of them. The numpy layouts below mirror std140 as ``blocks.glsl``
declares it (a vec3 takes 16 bytes unless a float follows it; array elements are vec4s);
``check_size`` compares them with the size the driver reports for each program.
"""
from __future__ import annotations

import moderngl
import numpy as np

SCENE_BINDING, VIEW_BINDING, TILE_BINDING = 0, 1, 2


def scene_dtype(light_slots: int) -> np.dtype:
    """std140 layout of the ``Scene`` block with this many searchlight slots."""
    n = light_slots
    return np.dtype({"names": ["sun", "visibility", "direct", "relief_reach", "ambient", "time", "zenith_colour",
                               "horizon_colour", "water_colour", "light_pos", "light_axis", "light_beam"],
                     "formats": ["3f4", "f4", "3f4", "f4", "3f4", "f4", "3f4", "3f4", "3f4", (np.float32, (n, 4)),
                                 (np.float32, (n, 4)), (np.float32, (n, 4))],
                     "offsets": [0, 12, 16, 28, 32, 44, 48, 64, 80, 96, 96 + 16 * n, 96 + 32 * n],
                     "itemsize": 96 + 48 * n})


VIEW = np.dtype({"names": ["view_proj", "eye", "classes"], "formats": [("f4", (4, 4)), "3f4", "i4"],
                 "offsets": [0, 64, 76], "itemsize": 80})


def vec4_bytes(layout: np.dtype) -> int:
    """A layout's size rounded up to whole vec4s (16 bytes), as drivers may lay its block out."""
    return -(-layout.itemsize // 16) * 16


def check_size(program: moderngl.Program, name: str, layout: np.dtype) -> None:
    """Refuse a program whose block differs in size from its layout here (or from that
    rounded up to a vec4, as drivers may report it)."""
    if program[name].size not in (layout.itemsize, vec4_bytes(layout)):
        raise RuntimeError(f"uniform block {name}: the driver lays out {program[name].size} bytes, "
                           f"the renderer {layout.itemsize}")


class SharedBlocks:
    """The ``Scene`` and ``View`` buffers, bound to their binding points for every program."""

    def __init__(self, ctx: moderngl.Context, light_slots: int) -> None:
        self.scene = np.zeros((), scene_dtype(light_slots))
        self.view = np.zeros((), VIEW)
        # whole vec4s: a driver may lay a block out rounded up so (``check_size``), and a
        # buffer bound smaller than its block leaves the draw undefined
        self.scene_buffer = ctx.buffer(reserve=vec4_bytes(self.scene.dtype))
        self.view_buffer = ctx.buffer(reserve=vec4_bytes(VIEW))

    def attach(self, *programs: moderngl.Program) -> None:
        """Point the programs' blocks at the shared binding points."""
        for prog in programs:
            for name, binding, layout in (("Scene", SCENE_BINDING, self.scene.dtype), ("View", VIEW_BINDING, VIEW)):
                if name in prog:
                    check_size(prog, name, layout)
                    prog[name].binding = binding

    def write_scene(self, **values) -> None:
        """Write the frame's ``Scene`` block (every field named)."""
        for name, value in values.items():
            self.scene[name] = value
        self.scene_buffer.write(self.scene.tobytes())

    def write_view(self, view_proj: np.ndarray, eye: np.ndarray, classes: bool) -> None:
        """Write the channel's ``View`` block (view_proj row-major, as numpy holds it) and
        bind both blocks."""
        self.view["view_proj"] = view_proj.T  # GLSL matrices are column-major
        self.view["eye"], self.view["classes"] = eye, int(classes)
        self.view_buffer.write(self.view.tobytes())
        self.scene_buffer.bind_to_uniform_block(SCENE_BINDING)
        self.view_buffer.bind_to_uniform_block(VIEW_BINDING)
