"""Draw the world state to the projector channels with moderngl.

GPU data mirrors the MuJoCo-style split of the simulation. Static: every template cell's
triangles about its centroid (seen from above the water: no bottom faces), each template's
cell raster (which cell covers each 0.1 m of the tile), the own ship's mesh. Dynamic: two
float textures holding every floe row's pose (x, y, heave, yaw; roll, pitch, status) and a
byte texture of each row's status, a tile table (each placed tile's first floe row,
template and rotation; -1 for the unbreakable slab), and per tile the vertex buffers of its
broken floes (tops and sides apart), to which a cell's template triangles are appended
once, when it breaks; the vertex shader places them by the pose texture. A tile's floes
are drawn only when its box is in the channel's view, their side faces only within the
level-of-detail distance. Level ice (unbreakable tiles and the intact cells
of breakable ones) is drawn per pixel by the environment pass from the cell raster, so it
costs no triangles: on a software rasteriser the vertex work of thousands of intact cells
would dominate the frame. Per frame only the poses of tiles placed or simulated since the
last frame are uploaded; frozen tiles cost nothing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import moderngl
import numpy as np

from bridge_node.render import shaders
from bridge_node.render.render_settings import ChannelSettings, RenderSettings
from sim_core.floe_state import INTACT
from sim_core.world import WorldData, WorldModel

GL_CLIP_DISTANCE0 = 0x3000
FLOE_DRIFT_MARGIN = 30.0  # m: broken floes may drift this far out of their tile
POSE_WIDTH = 2048  # texels per line of the pose textures
MAX_TILES = 4096 * 4096  # tile table of 8 bytes per tile: 134 MB of texture at most
RASTER_SIZE = 1024  # pixels per tile side of the cell rasters (0.1 m for 100 m tiles)
NEAR = 0.5  # m
SKY_HORIZON, SKY_ZENITH = (0.78, 0.84, 0.90), (0.38, 0.55, 0.78)
FOG = (0.70, 0.74, 0.78)
WATER = (0.10, 0.17, 0.22)
ICE_INTACT, ICE_BROKEN, ICE_EDGE = (0.93, 0.95, 0.97), (0.60, 0.68, 0.75), (0.52, 0.68, 0.78)
DECK, HULL = (0.35, 0.38, 0.36), (0.55, 0.12, 0.10)


def _mat(m: np.ndarray) -> bytes:
    """A row-major numpy 4x4 matrix as GLSL's column-major bytes."""
    return np.ascontiguousarray(m.T, dtype="f4").tobytes()


def ship_matrix(north: float, east: float, psi: float) -> np.ndarray:
    """Ship frame (x forward, y starboard, z up) to world (x east, y north, z up)."""
    s, c = math.sin(psi), math.cos(psi)
    return np.array([[s, c, 0, east], [c, -s, 0, north], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)


@dataclass(frozen=True)
class Camera:
    eye: np.ndarray  # world m
    view: np.ndarray
    proj: np.ndarray

    @property
    def view_proj(self) -> np.ndarray:
        return self.proj @ self.view


def channel_camera(channel: ChannelSettings, north: float, east: float, psi: float, far: float) -> Camera:
    """The channel's camera for the ship at (north, east) m with heading psi (rad, from north)."""
    eye = (ship_matrix(north, east, psi) @ np.array([*channel.eye, 1.0]))[:3]
    az, el = psi + math.radians(channel.yaw_deg), math.radians(channel.pitch_deg)
    f = np.array([math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el)])
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = r, u, -f
    view[:3, 3] = -view[:3, :3] @ eye
    tx, ty = math.tan(math.radians(channel.hfov_deg) / 2), math.tan(channel.vfov() / 2)
    proj = np.array([[1 / tx, 0, 0, 0], [0, 1 / ty, 0, 0],
                     [0, 0, (far + NEAR) / (NEAR - far), 2 * far * NEAR / (NEAR - far)], [0, 0, -1, 0]])
    return Camera(eye, view, proj)


def _cell_vertices(model: WorldModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangles of every template cell that can be seen from above the water (bottom faces
    left out), wound counter-clockwise from outside: (position 3f, normal 3f) per vertex,
    each cell's tops first, then its sides. Returns the vertices, each global cell's first
    vertex (G + 1,) and its first side vertex (G,)."""
    ice = model.ice
    tris = ice.tris.copy()
    owner = np.repeat(np.arange(len(ice.mass)), np.diff(ice.tri_start))
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    inward = (n * tris.mean(axis=1)).sum(axis=1) < 0.0  # the centroid is the origin
    n[inward] *= -1.0
    tris[inward] = tris[inward][:, ::-1]
    keep = n[:, 2] > -0.5
    tris, n, owner = tris[keep], n[keep], owner[keep]
    side = n[:, 2] < 0.5
    order = np.lexsort((side, owner))  # by cell, tops before sides
    tris, n, owner, side = tris[order], n[order], owner[order], side[order]
    out = np.zeros((len(tris) * 3, 6), dtype="f4")
    out[:, :3] = tris.reshape(-1, 3)
    out[:, 3:] = np.repeat(n, 3, axis=0)
    cells = len(ice.mass)
    start = np.concatenate([[0], np.cumsum(3 * np.bincount(owner, minlength=cells))])
    side_start = start[:-1] + 3 * np.bincount(owner[~side], minlength=cells)
    return out, start, side_start


def _gather(starts: np.ndarray, stops: np.ndarray) -> np.ndarray:
    """Indices of the concatenated ranges [starts[i], stops[i])."""
    counts = stops - starts
    return np.repeat(starts - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())


class _FloeBuffer:
    """Triangles of one tile's broken floes (tops or sides), appended to as cells break;
    the storage doubles when full."""

    STRIDE = 28  # bytes: position 3f, normal 3f, floe row i4

    def __init__(self, ctx: moderngl.Context, program: moderngl.Program) -> None:
        self.ctx, self.program = ctx, program
        self.vbo = self.vao = None
        self.vertices = 0

    def append(self, verts: np.ndarray, rows: np.ndarray) -> None:
        data = np.zeros(len(verts), dtype=[("v", "f4", 6), ("row", "i4")])
        data["v"], data["row"] = verts, rows
        size = (self.vertices + len(verts)) * self.STRIDE
        if self.vbo is None or size > self.vbo.size:
            old = self.vbo
            self.vbo = self.ctx.buffer(reserve=max(size, 2 * (old.size if old else 0), 1 << 16))
            if old is not None:
                self.ctx.copy_buffer(self.vbo, old, self.vertices * self.STRIDE)
                old.release()
            self.vao = self.ctx.vertex_array(self.program, [(self.vbo, "3f 3f i", "in_pos", "in_normal", "in_row")])
        self.vbo.write(data.tobytes(), offset=self.vertices * self.STRIDE)
        self.vertices += len(verts)

    def render(self) -> None:
        if self.vertices:
            self.vao.render(vertices=self.vertices)


def visible_boxes(view_proj: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Which axis-aligned boxes (n, 3) corners lo..hi, world m, may be seen: False only when
    all eight corners lie outside the same clip plane."""
    corners = np.stack(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij"), -1).reshape(8, 3)
    pts = lo[:, None, :] + corners[None] * (hi - lo)[:, None, :]
    clip = np.concatenate([pts, np.ones(pts.shape[:2] + (1,))], axis=-1) @ view_proj.T
    x, y, z, w = clip[..., 0], clip[..., 1], clip[..., 2], clip[..., 3]
    outside = [x < -w, x > w, y < -w, y > w, z < -w, z > w]
    return ~np.any([o.all(axis=1) for o in outside], axis=0)


def cell_rasters(model: WorldModel, size: int) -> np.ndarray:
    """Per template, which cell covers each pixel of the tile: (templates * size, size)
    uint16, 1 + the cell's index within its template, 0 in the cracks between cells."""
    from PIL import Image, ImageDraw

    ice = model.ice
    out = []
    for k, t in enumerate(ice.templates):
        img = Image.new("I", (size, size), 0)
        draw = ImageDraw.Draw(img)
        scale = size / t.side
        g0 = ice.template_start[k]
        for c in range(t.n_cells):
            g = g0 + c
            ring = ice.outline[ice.outline_start[g]:ice.outline_start[g + 1]] + ice.centroid[g, :2]
            draw.polygon([tuple(p) for p in ring * scale], fill=c + 1)
        out.append(np.asarray(img, dtype=np.int64).astype(np.uint16))
    return np.vstack(out)


def _ship_vertices(contour: np.ndarray, freeboard: float) -> np.ndarray:
    """Hull sides from the waterline contour up to the deck, and the deck, ship frame."""
    tri, nrm = [], []
    centre = contour.mean(axis=0)
    for a, b in zip(contour, np.roll(contour, -1, axis=0)):
        tri.append([[*centre, freeboard], [*a, freeboard], [*b, freeboard]])
        nrm.append([0.0, 0.0, 1.0])
        side = [[*a, 0.0], [*b, 0.0], [*b, freeboard], [*a, 0.0], [*b, freeboard], [*a, freeboard]]
        out = np.array([b[1] - a[1], -(b[0] - a[0])])
        out /= max(np.linalg.norm(out), 1e-12)
        if out @ ((a + b) / 2 - centre) < 0:
            out = -out
        tri += [side[:3], side[3:]]
        nrm += [[*out, 0.0]] * 2
    p = np.array(tri, dtype="f4").reshape(-1, 3)
    n = np.repeat(np.array(nrm, dtype="f4"), 3, axis=0)
    return np.hstack([p, n]).astype("f4")


class SceneRenderer:
    """GPU resources of one world; draws it for any channel."""

    def __init__(self, ctx: moderngl.Context, model: WorldModel, settings: RenderSettings) -> None:
        self.ctx, self.model, self.settings = ctx, model, settings
        scene = model.scene
        self.env = ctx.program(vertex_shader=shaders.ENV_VS, fragment_shader=shaders.ENV_FS)
        self.floe = ctx.program(vertex_shader=shaders.FLOE_VS, fragment_shader=shaders.FLOE_FS)
        self.ship = ctx.program(vertex_shader=shaders.SHIP_VS, fragment_shader=shaders.SHIP_FS)
        self.band = ctx.program(vertex_shader=shaders.BAND_VS, fragment_shader=shaders.BAND_FS)
        self.band_buf = ctx.buffer(reserve=2 * 6 * 2 * 4)
        self.band_vao = ctx.vertex_array(self.band, [(self.band_buf, "2f", "in_ndc")])
        self.env_buf = ctx.buffer(reserve=3 * 5 * 4)
        self.env_vao = ctx.vertex_array(self.env, [(self.env_buf, "2f 3f", "in_ndc", "in_ray")])
        if scene.nx * scene.ny > MAX_TILES:
            raise ValueError(f"the renderer draws fields of up to {MAX_TILES} tiles; this one has {scene.nx * scene.ny}")
        info = np.tile(np.array([-1, 0], "i4"), scene.nx * scene.ny)
        self.tile_info = ctx.texture((scene.nx, scene.ny), 2, info.tobytes(), dtype="i4")
        self.tile_info.filter = moderngl.NEAREST, moderngl.NEAREST
        hull = _ship_vertices(model.contour, settings.freeboard_m)
        self.ship_vao = ctx.vertex_array(self.ship, [(ctx.buffer(hull.tobytes()), "3f 3f", "in_pos", "in_normal")])
        self.cell_verts, self.cell_vert_start, self.cell_side_start = _cell_vertices(model)
        self.raster_size = RASTER_SIZE if len(model.ice.templates) <= 4 else RASTER_SIZE // 2
        raster = cell_rasters(model, self.raster_size)
        self.cell_raster = ctx.texture((self.raster_size, raster.shape[0]), 1, raster.tobytes(), dtype="u2")
        self.cell_raster.filter = moderngl.NEAREST, moderngl.NEAREST
        self.tile_floes: dict[int, tuple[_FloeBuffer, _FloeBuffer]] = {}  # placement -> (tops, sides)
        self._drawn = np.zeros(0, dtype=bool)
        self.pose_a = self.pose_b = self.status = None
        self._pose_lines = 0
        self._placed = 0
        self._uploaded_rows = 0
        self._live_rows: list[int] = []
        h = model.ice.thickness.mean() if len(model.ice.thickness) else 0.0
        mat = model.ice.material
        self.slab_z = float(h * (1.0 - mat.density / mat.water_density))
        az, el = math.radians(settings.sun_azimuth_deg), math.radians(settings.sun_elevation_deg)
        self.sun = (math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el))

    # -- per frame uploads ----------------------------------------------------------------
    def update(self, data: WorldData) -> None:
        """Upload what changed since the last call: tile states, new placements, the
        triangles of newly broken floes, and the poses of the rows of tiles placed or
        simulated since then."""
        tiles = data.ice.tiles
        st = data.ice.state
        self._ensure_pose_capacity(st.n)
        if len(tiles.template) != self._placed:
            self._upload_placements(data)
        # rows of tiles live now or at the last upload (a tile frozen since then gets its final
        # pose): only there can cells have broken or floes have moved
        live = [tiles.row_start[data.scene.placement[int(t)]] for t in data.scene.live if int(t) in data.scene.placement]
        first = min([self._uploaded_rows, *live, *self._live_rows])
        self._append_broken(st, first)
        self._upload_poses(st, first)
        self._live_rows = live
        self._uploaded_rows = st.n

    def _upload_placements(self, data: WorldData) -> None:
        tiles, nx = data.ice.tiles, self.model.scene.nx
        for tile, k in data.scene.placement.items():
            if k >= self._placed:
                info = np.array([tiles.row_start[k], tiles.template[k] | (tiles.quarter_turns[k] << 16)], "i4")
                self.tile_info.write(info.tobytes(), viewport=(tile % nx, tile // nx, 1, 1))
        self._placed = len(tiles.template)

    def _append_broken(self, st, first_row: int) -> None:
        """Append the template triangles of cells broken since the last call (at or after
        first_row) to their tile's buffers (tops and sides apart, for the level of detail)."""
        if len(self._drawn) < st.n:
            self._drawn = np.concatenate([self._drawn, np.zeros(st.n - len(self._drawn), bool)])
        new = first_row + np.nonzero((st.status[first_row:] != INTACT) & ~self._drawn[first_row:st.n])[0]
        self._drawn[new] = True
        for k in np.unique(st.tile[new]):
            rows = new[st.tile[new] == k]
            g = st.gcell[rows]
            if int(k) not in self.tile_floes:
                self.tile_floes[int(k)] = (_FloeBuffer(self.ctx, self.floe), _FloeBuffer(self.ctx, self.floe))
            for buf, a, b in zip(self.tile_floes[int(k)], (self.cell_vert_start[g], self.cell_side_start[g]),
                                 (self.cell_side_start[g], self.cell_vert_start[g + 1])):
                buf.append(self.cell_verts[_gather(a, b)], np.repeat(rows, b - a))

    def _ensure_pose_capacity(self, rows: int) -> None:
        lines = max(1, math.ceil(rows / POSE_WIDTH))
        if lines <= self._pose_lines:
            return
        lines = max(lines, 2 * self._pose_lines)
        for name, components, dtype in (("pose_a", 4, "f4"), ("pose_b", 4, "f4"), ("status", 1, "u1")):
            old = getattr(self, name)
            if old is not None:
                old.release()
            tex = self.ctx.texture((POSE_WIDTH, lines), components, dtype=dtype)
            tex.filter = moderngl.NEAREST, moderngl.NEAREST
            setattr(self, name, tex)
        self._pose_lines = lines
        self._uploaded_rows = 0  # new textures: everything again

    def _upload_poses(self, st, first_row: int) -> None:
        line0 = first_row // POSE_WIDTH
        r0, r1 = line0 * POSE_WIDTH, st.n
        if r1 <= r0:
            return
        lines = math.ceil((r1 - r0) / POSE_WIDTH)
        a = np.zeros((lines * POSE_WIDTH, 4), dtype="f4")
        b = np.zeros_like(a)
        n = r1 - r0
        a[:n, 0:2] = st.xy[r0:r1]
        a[:n, 2] = st.heave[r0:r1]
        a[:n, 3] = st.yaw[r0:r1]
        b[:n, 0] = st.roll[r0:r1]
        b[:n, 1] = st.pitch[r0:r1]
        b[:n, 2] = st.status[r0:r1]
        view = (0, line0, POSE_WIDTH, lines)
        self.pose_a.write(a.tobytes(), viewport=view)
        self.pose_b.write(b.tobytes(), viewport=view)
        status = np.zeros(lines * POSE_WIDTH, dtype=np.uint8)
        status[:n] = st.status[r0:r1]
        self.status.write(status.tobytes(), viewport=view)

    # -- drawing --------------------------------------------------------------------------
    def draw(self, data: WorldData, channel: ChannelSettings, blend: moderngl.Texture) -> Camera:
        """Draw the scene for one channel into the bound framebuffer, its columns scaled by
        the blend texture (width x 1 float: the channel's edge-blend factors)."""
        ctx, s = self.ctx, self.settings
        north, east, psi = (float(v) for v in (data.ship.eta[0], data.ship.eta[1], data.ship.eta[5]))
        cam = channel_camera(channel, north, east, psi, s.far_m)
        vp = cam.view_proj
        half = math.radians(channel.hfov_deg) / 2
        common = {"eye": tuple(cam.eye), "visibility": s.visibility_m, "fog_colour": FOG}
        ctx.clear(*FOG, depth=1.0)
        self.tile_info.use(0)
        self.cell_raster.use(3)
        if self.pose_b is not None:
            self.pose_a.use(4)
            self.pose_b.use(5)
            self.status.use(7)
        # near to far: ship, floes, then the environment behind them, so that the depth test
        # spares the full-screen pass every pixel already covered
        ctx.enable(moderngl.DEPTH_TEST)
        self._set(self.ship, view_proj=vp, ship_to_world=ship_matrix(north, east, psi), sun=self.sun,
                  top_colour=DECK, side_colour=HULL, ambient=0.55, **common)
        self.ship_vao.render()
        if self.tile_floes:
            ctx.enable_direct(GL_CLIP_DISTANCE0)
            ctx.enable(moderngl.CULL_FACE)  # not for the ship: its matrix mirrors (starboard-handed frame)
            self._set(self.floe, view_proj=vp, pose_a=4, pose_b=5, pose_width=POSE_WIDTH, sun=self.sun,
                      top_colour=ICE_BROKEN, side_colour=ICE_EDGE, ambient=0.7, **common)
            self._draw_floes(data, cam)
            ctx.disable(moderngl.CULL_FACE)
            ctx.disable_direct(GL_CLIP_DISTANCE0)
        tx, ty = math.tan(half), math.tan(channel.vfov() / 2)
        corners = np.array([[-1, -1], [3, -1], [-1, 3]], dtype=float)
        rays = -cam.view[2, :3] + corners[:, :1] * tx * cam.view[0, :3] + corners[:, 1:] * ty * cam.view[1, :3]
        self.env_buf.write(np.hstack([corners, rays]).astype("f4").tobytes())
        scene = self.model.scene
        ice = tuple(c * (0.7 + 0.3 * max(self.sun[2], 0.0)) for c in ICE_INTACT)
        self._set(self.env, horizon_colour=SKY_HORIZON, zenith_colour=SKY_ZENITH, water_colour=WATER,
                  ice_colour=ice, slab_z=self.slab_z, far=s.far_m, tile_info=0, cell_raster=3,
                  raster_size=self.raster_size, status=7, pose_width=POSE_WIDTH,
                  field_size=(scene.nx * scene.side, scene.ny * scene.side), tile_side=scene.side, **common)
        self.env_vao.render()
        self._blend_bands(channel, blend)
        return cam

    def _blend_bands(self, channel: ChannelSettings, blend: moderngl.Texture) -> None:
        """Multiply the columns of the blend bands by their factors (a pass over the bands
        only, not the whole image)."""
        t = math.tan(math.radians(channel.hfov_deg) / 2)
        spans = []
        if channel.blend_left_deg > 0:
            spans.append((-1.0, math.tan(math.radians(channel.blend_left_deg - channel.hfov_deg / 2)) / t))
        if channel.blend_right_deg > 0:
            spans.append((math.tan(math.radians(channel.hfov_deg / 2 - channel.blend_right_deg)) / t, 1.0))
        if not spans:
            return
        quads = np.array([[[a, -1], [b, -1], [b, 1], [a, -1], [b, 1], [a, 1]] for a, b in spans], dtype="f4")
        self.band_buf.orphan(quads.nbytes)
        self.band_buf.write(quads.tobytes())
        ctx = self.ctx
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ZERO, moderngl.SRC_COLOR
        blend.use(6)
        self.band["blend_ramp"].value = 6
        self.band_vao.render(vertices=6 * len(spans))
        ctx.disable(moderngl.BLEND)

    def _draw_floes(self, data: WorldData, cam: Camera) -> None:
        """Each tile's broken floes, if its box (with a margin for drift) is in view; their
        side faces only within the level-of-detail distance."""
        keys = list(self.tile_floes)
        corner = np.array([data.ice.tiles.corner[k] for k in keys], dtype=float)
        side = self.model.scene.side
        lo = np.column_stack([corner - FLOE_DRIFT_MARGIN, np.full(len(keys), -2.0)])
        hi = np.column_stack([corner + side + FLOE_DRIFT_MARGIN, np.full(len(keys), 2.0)])
        seen = visible_boxes(cam.view_proj, lo, hi)
        gap = np.maximum(np.maximum(lo[:, :2] - cam.eye[:2], cam.eye[:2] - hi[:, :2]), 0.0)
        near = np.hypot(gap[:, 0], gap[:, 1]) < self.settings.lod_distance_m
        for k, show, full in zip(keys, seen, near):
            if show:
                tops, sides = self.tile_floes[k]
                tops.render()
                if full:
                    sides.render()

    @staticmethod
    def _set(prog: moderngl.Program, **uniforms) -> None:
        for name, value in uniforms.items():
            if name not in prog:
                continue
            if isinstance(value, np.ndarray) and value.shape == (4, 4):
                prog[name].write(_mat(value))
            else:
                prog[name].value = value
