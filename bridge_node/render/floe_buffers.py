"""The renderer's floe geometry on the GPU: the pose textures' texels made from poses, the
triangles of a tile's broken floes (``FloeBuffer``: a live tile's own copy of its floes'
vertices; ``FloeCopies``: a frozen tile's indices into its template's), and the small
helpers they and the passes share (a growing buffer, entries written along texture lines,
a polygon clipped to a half-space, the horizon's split of a channel)."""
from __future__ import annotations


import moderngl
import numpy as np

from bridge_node.render.camera import Camera
from bridge_node.render.meshes import TemplateMesh
from bridge_node.render.passes.glsl import POSE_WIDTH


def pose_textures(pose: np.ndarray) -> np.ndarray:
    """The pose textures' texels (2, n, 4) of poses (n, 6): x, y, heave (m), yaw, roll, pitch
    (rad): the unit quaternion (x, y, z, w) of Rz(yaw) Ry(pitch) Rx(roll), floe to world;
    the place (x, y, heave, 0)."""
    x, y, z, yaw, roll, pitch = pose.T
    cy, sy, cp, sp, cr, sr = (f(a / 2) for a in (yaw, pitch, roll) for f in (np.cos, np.sin))
    quaternion = [cy * cp * sr - sy * sp * cr, cy * sp * cr + sy * cp * sr, sy * cp * cr - cy * sp * sr,
                  cy * cp * cr + sy * sp * sr]
    return np.array([np.column_stack(quaternion), np.column_stack([x, y, z, np.zeros_like(x)])])


def clip_polygon(poly: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The part of a convex polygon (n, k) where the linear function f (values at its
    vertices) is <= 0, as a triangle fan's triangles (3 m, k). (Plain floats: a channel
    clips a quad twice a frame, where numpy's per-call cost would be most of the time.)"""
    pts, values, out = poly.tolist(), f.tolist(), []
    for k, (a, fa) in enumerate(zip(pts, values)):
        b, fb = pts[(k + 1) % len(pts)], values[(k + 1) % len(pts)]
        if fa <= 0:
            out.append(a)
        if (fa <= 0) != (fb <= 0):
            s = fa / (fa - fb)
            out.append([p + (q - p) * s for p, q in zip(a, b)])
    if len(out) < 3:
        return np.zeros((0, poly.shape[1]))
    return np.array([v for k in range(1, len(out) - 1) for v in (out[0], out[k], out[k + 1])])


def horizon_split(cam: Camera, tx: float, ty: float, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The screen split along the horizon for the environment pass (below, over the band
    of pixels the horizon's anti-aliasing spans) and the sky pass (above): triangles of
    (NDC x, y, view ray x, y, z), the rays linear in the screen; tx, ty: tangents of half
    the fields of view. The split lies where the ray's z is one pixel's change of it (on
    both axes) above 0: past the half pixel that the environment pass blends."""
    corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    rays = -cam.view[2, :3] + corners[:, :1] * tx * cam.view[0, :3] + corners[:, 1:] * ty * cam.view[1, :3]
    band = 2.0 * (abs(tx * cam.view[0, 2]) / width + abs(ty * cam.view[1, 2]) / height)
    quad, f = np.hstack([corners, rays]), rays[:, 2] - band
    return clip_polygon(quad, f), clip_polygon(quad, -f)


def write_entries(tex: moderngl.Texture, lines: int, first: int, values: np.ndarray) -> None:
    """Write values (n, ...) to a texture's frozen entries first .. first + n - 1, which run
    along its lines from the last line down (``entry_texel`` in ``passes/entries.glsl``)."""
    end = first + len(values)
    for line in range(first // POSE_WIDTH, (end - 1) // POSE_WIDTH + 1):
        a, b = max(first, line * POSE_WIDTH), min(end, (line + 1) * POSE_WIDTH)
        tex.write(np.ascontiguousarray(values[a - first:b - first]).tobytes(),
                  viewport=(a % POSE_WIDTH, lines - 1 - line, b - a, 1))


def grown_buffer(ctx: moderngl.Context, buf: moderngl.Buffer | None, used: int, size: int,
           least: int = 1 << 16) -> moderngl.Buffer:
    """`buf` if it holds `size` bytes, else a buffer of at least twice its size (and `least`
    bytes) holding its first `used` bytes (`buf` released)."""
    if buf is not None and size <= buf.size:
        return buf
    new = ctx.buffer(reserve=max(size, 2 * (buf.size if buf else 0), least))
    if buf is not None:
        ctx.copy_buffer(new, buf, used)
        buf.release()
    return new


class FloeBuffer:
    """Triangles of one tile's broken floes (tops or sides): indices into the vertices its
    template shares with every tile laid with it (``meshes.TemplateMesh``), appended to as
    cells break; the storage doubles when full, from ``least`` bytes (0: a buffer that is
    written once, a frozen tile's, holds just what it is given). Only indices are kept per
    floe."""

    def __init__(self, ctx: moderngl.Context, program: moderngl.Program, vbo: moderngl.Buffer | None,
                 index_type: np.dtype, least: int = 1 << 16) -> None:
        self.ctx, self.program, self.vbo, self.index_type = ctx, program, vbo, np.dtype(index_type)
        self.least = least
        self.ibo = self.vao = None
        self._bound: tuple = (None, None)  # the (vertex, index) buffers of the vertex array
        self.indices = 0

    def append(self, index: np.ndarray) -> None:
        """Append triangles, as their corners' indices into the vertices."""
        size = self.index_type.itemsize
        self.ibo = grown_buffer(self.ctx, self.ibo, self.indices * size, (self.indices + len(index)) * size, self.least)
        if self._bound != (self.vbo, self.ibo):
            if self.vao is not None:
                self.vao.release()
            self.vao = self.ctx.vertex_array(self.program, [(self.vbo, "3f 3f i", "in_pos", "in_normal", "in_cell")],
                                             self.ibo, index_element_size=size)
            self._bound = self.vbo, self.ibo
        self.ibo.write(index.astype(self.index_type).tobytes(), offset=self.indices * size)
        self.indices += len(index)

    def render(self) -> None:
        if self.indices:
            self.vao.render(vertices=self.indices)

    def release(self) -> None:
        """Free the index storage (the template's vertices stay, shared)."""
        for obj in (self.vao, self.ibo):
            if obj is not None:
                obj.release()
        self.ibo = self.vao = None
        self._bound = (None, None)
        self.indices = 0

    @property
    def nbytes(self) -> int:
        """Bytes of storage held."""
        return self.ibo.size if self.ibo is not None else 0


class FloeCopies(FloeBuffer):
    """A ``FloeBuffer`` that keeps its own copy of its floes' vertices, for a live tile: on
    llvmpipe, a tile's draw that fetches its vertices from the whole template's took about a
    twentieth of the frame more than one that fetches them from its own few (3 channels at
    1280x720, 3000 floes). Live floes are a few thousand; frozen ones index the template's."""

    def __init__(self, ctx: moderngl.Context, program: moderngl.Program, mesh: TemplateMesh) -> None:
        super().__init__(ctx, program, None, mesh.index.dtype)
        self.template_vertices, self.vertex_count = mesh.vertices, 0

    def append(self, index: np.ndarray) -> None:
        """Append triangles, as their corners' indices into the template's vertices."""
        ids, local = np.unique(index, return_inverse=True)  # the cells' vertices, each once
        stride = self.template_vertices.itemsize
        self.vbo = grown_buffer(self.ctx, self.vbo, self.vertex_count * stride, (self.vertex_count + len(ids)) * stride,
                          self.least)
        self.vbo.write(self.template_vertices[ids].tobytes(), offset=self.vertex_count * stride)
        super().append(local.ravel() + self.vertex_count)
        self.vertex_count += len(ids)

    def release(self) -> None:
        super().release()
        if self.vbo is not None:
            self.vbo.release()
        self.vbo, self.vertex_count = None, 0

    @property
    def nbytes(self) -> int:
        return super().nbytes + (self.vbo.size if self.vbo is not None else 0)
