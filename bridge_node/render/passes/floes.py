"""The broken floes' pass (``floes.vert``, ``floes.frag``): per tile with broken floes in
view, the floes' tops, their side faces within the level-of-detail distance, and within
the reflection distance their side faces once more, mirrored in the water plane.

Each tile's own values (its first row or status entry, its first frozen floe, whether it is
frozen, its snow patches, its ice thickness) live in one slot of a shared uniform buffer
(``tile.glsl``), written when the tile is given rows or frozen: a tile's draw binds its
slot's range, one call where uniform writes took five."""
from __future__ import annotations

import moderngl
import numpy as np

from bridge_node.render.passes import glsl
from bridge_node.render.passes.blocks import TILE_BINDING, check_size

SEEN_DEPTH = 4.0  # m: floes are drawn down to this depth (deeper ice is lost in the sea)
GL_CLIP_DISTANCE0 = 0x3000
TILE = np.dtype({"names": ["first", "first_floe", "frozen", "patch_base", "thickness"],
                 "formats": ["i4", "i4", "i4", "i4", "f4"], "offsets": [0, 4, 8, 12, 16], "itemsize": 20})


class TileSlots:
    """One ``Tile`` block per placement in one uniform buffer, each at the driver's offset
    alignment; the buffer doubles when full. A draw binds its slot's range at the block's
    size as the driver reports it (``block_size``, bytes: std140 may round it up past the
    values' 20 bytes; a smaller range leaves the draw undefined)."""

    def __init__(self, ctx: moderngl.Context, alignment: int, block_size: int) -> None:
        self.ctx, self.block_size = ctx, block_size
        self.stride = -(-block_size // alignment) * alignment
        self.slot: dict[int, int] = {}  # placement -> its slot
        self.values: dict[int, np.ndarray] = {}  # placement -> its block's values
        self._free: list[int] = []
        self.buffer = ctx.buffer(reserve=64 * self.stride)

    def write(self, k: int, **fields) -> None:
        """Set fields of placement k's block (a new placement's others 0)."""
        if k not in self.slot:
            self.slot[k] = self._free.pop() if self._free else len(self.slot)
            self.values[k] = np.zeros((), TILE)
            self._grow()
        block = self.values[k]
        for name, value in fields.items():
            block[name] = value
        self.buffer.write(block.tobytes(), offset=self.slot[k] * self.stride)

    def drop(self, k: int) -> None:
        if k in self.slot:
            self._free.append(self.slot.pop(k))
            del self.values[k]

    def bind(self, k: int) -> None:
        self.buffer.bind_to_uniform_block(TILE_BINDING, offset=self.slot[k] * self.stride, size=self.block_size)

    def _grow(self) -> None:
        needed = (max(self.slot.values()) + 1) * self.stride
        if needed > self.buffer.size:
            old = self.buffer
            self.buffer = self.ctx.buffer(reserve=2 * old.size)
            self.buffer.write(old.read())
            old.release()


class FloePass:
    """The broken floes of the tiles in view: tops, sides, reflections."""

    def __init__(self, ctx: moderngl.Context, defines: dict, samplers: dict[str, int]) -> None:
        self.ctx = ctx
        self.program = glsl.program(ctx, "floes.vert", "floes.frag", SEEN_DEPTH=SEEN_DEPTH, **defines)
        glsl.set_present(self.program, **samplers)
        self.program["Tile"].binding = TILE_BINDING
        check_size(self.program, "Tile", TILE)
        self.tiles = TileSlots(ctx, int(ctx.info["GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT"]), self.program["Tile"].size)
        self._reflected = self.program["reflected"]

    def draw(self, tiles: list[tuple[int, float]], buffers: dict, sides, lod_distance: float) -> None:
        """The tiles' floes ((placement, distance from the eye, m)), their tops from
        ``buffers`` (placement -> (tops, sides)), their side faces (``sides(placement)``)
        within the level-of-detail distance."""
        ctx = self.ctx
        ctx.enable_direct(GL_CLIP_DISTANCE0)
        ctx.enable(moderngl.CULL_FACE)  # (not for the ship: its matrix mirrors, a starboard-handed frame)
        for k, dist in tiles:
            self.tiles.bind(k)
            buffers[k][0].render()
            if dist < lod_distance:
                sides(k).render()
        ctx.disable(moderngl.CULL_FACE)
        ctx.disable_direct(GL_CLIP_DISTANCE0)

    def reflections(self, tiles: list[tuple[int, float]], sides, reach: float) -> None:
        """The floes' reflections in the sea within ``reach`` m: their side faces above the
        water, mirrored in the water plane and blended over the sea by its Fresnel share
        (tops, seen from below the water, are culled). Polygon offset puts a mirrored
        freeboard before the submerged part of the same side, in whose plane it lies."""
        near = [k for k, d in tiles if d < reach]
        if not near:
            return
        ctx = self.ctx
        ctx.enable_direct(GL_CLIP_DISTANCE0)
        ctx.enable(moderngl.CULL_FACE | moderngl.BLEND)
        ctx.front_face = "cw"  # the mirror turns the winding
        ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        ctx.polygon_offset = -1.0, -1.0
        self._reflected.value = True
        for k in near:
            self.tiles.bind(k)
            sides(k).render()
        self._reflected.value = False
        ctx.polygon_offset = 0.0, 0.0
        ctx.front_face = "ccw"
        ctx.disable(moderngl.CULL_FACE | moderngl.BLEND)
        ctx.disable_direct(GL_CLIP_DISTANCE0)
