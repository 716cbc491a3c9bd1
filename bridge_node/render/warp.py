"""Projector warp meshes for curved screens: a channel's image is drawn flat, then through a
grid that says, for each grid node of the projector's output, which point of the flat image
it shows (the geometry correction a projector calibration tool measures).

Grid file: a PFM image (the format of the VESA MPCDI geometry warp file), ``PF`` header,
``cols rows``, a negative scale (little-endian), then rows * cols * 3 float32, rows from the
bottom of the output up. Node (row i, column j) sits at the output's normalized position
(j / (cols - 1), i / (rows - 1)), (0, 0) its bottom-left corner, (1, 1) its top-right. Its
first two values are the normalized position in the flat image it shows, same axes; the
third is ignored. A NaN node shows black (outside the screen). Between nodes the mapping is
linear (two triangles per grid cell).
"""
from __future__ import annotations

from pathlib import Path

import moderngl
import numpy as np

from bridge_node.common.errors import UserError
from bridge_node.common.input_files import read_input
from bridge_node.common.output_files import write_output
from bridge_node.render.passes import glsl

MAX_NODES = 4096  # grid nodes a side, at most
MAX_PFM_BYTES = 64 + MAX_NODES * MAX_NODES * 12  # the header, and three float32 a node


class WarpError(ValueError):
    """A warp grid file that cannot be used; the message names the file and what is wrong."""


def write_pfm(path: Path, grid: np.ndarray) -> None:
    """Write a warp grid (rows, cols, 2 or 3) float, bottom row first, as PFM."""
    rows, cols = grid.shape[:2]
    data = np.zeros((rows, cols, 3), dtype="<f4")
    data[..., : grid.shape[2]] = grid
    write_output(path, f"PF\n{cols} {rows}\n-1.0\n".encode() + data.tobytes(), "warp grid file")


def read_pfm(path: Path, where: str) -> np.ndarray:
    """The warp grid of a PFM file: (rows, cols, 2) float32 source positions, bottom row
    first. ``where`` names the config key for the messages."""
    try:
        raw = read_input(path, "warp grid file", MAX_PFM_BYTES, where)
    except UserError as exc:
        raise WarpError(str(exc)) from None
    head = raw.split(b"\n", 3)
    try:
        kind, (cols, rows), scale = head[0].strip(), map(int, head[1].split()), float(head[2])
    except (IndexError, ValueError):
        raise WarpError(f"{where}: not a PFM file (expected 'PF', 'cols rows', scale lines)") from None
    if kind != b"PF" or not (2 <= cols <= MAX_NODES and 2 <= rows <= MAX_NODES):
        raise WarpError(f"{where}: expected a 3-channel PFM ('PF') of 2 to {MAX_NODES} nodes a side, "
                        f"got {kind.decode(errors='replace')!r} {cols}x{rows}")
    body = head[3] if len(head) > 3 else b""
    if len(body) != rows * cols * 12:
        raise WarpError(f"{where}: {len(body)} bytes of data, {cols}x{rows} nodes need {rows * cols * 12}")
    data = np.frombuffer(body, dtype="<f4" if scale < 0 else ">f4").reshape(rows, cols, 3)
    return data[..., :2].astype("f4")


class WarpMesh:
    """Draws a flat channel image through a warp grid into the bound framebuffer."""

    def __init__(self, ctx: moderngl.Context, grid: np.ndarray) -> None:
        rows, cols = grid.shape[:2]
        y, x = np.meshgrid(np.linspace(-1.0, 1.0, rows), np.linspace(-1.0, 1.0, cols), indexing="ij")
        uv = np.where(np.isfinite(grid), grid, -1.0)  # NaN: outside the flat image, black
        vertices = np.dstack([x, y, uv]).astype("f4").reshape(-1, 4)
        k = np.arange(rows * cols).reshape(rows, cols)
        a, b, c, d = k[:-1, :-1], k[:-1, 1:], k[1:, :-1], k[1:, 1:]
        index = np.stack([a, b, d, a, d, c], axis=-1).astype("i4").ravel()
        self.program = glsl.program(ctx, "warp.vert", "warp.frag")
        self.vao = ctx.vertex_array(self.program, [(ctx.buffer(vertices.tobytes()), "2f 2f", "in_ndc", "in_uv")],
                                    index_buffer=ctx.buffer(index.tobytes()))

    def draw(self, flat: moderngl.Texture) -> None:
        flat.use(0)
        self.program["flat_image"].value = 0
        self.vao.render()
