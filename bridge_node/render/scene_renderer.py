"""Draw the world state to the projector channels with moderngl.

GPU data mirrors the MuJoCo-style split of the simulation. Static: one vertex buffer per
tile template (every cell's triangles about its centroid, with the cell's index), the
sea, slab and own-ship meshes. Dynamic: two float textures holding every floe row's pose
(x, y, heave, yaw; roll, pitch, status), an instance buffer per template listing the first
floe row of each placed tile, and a one-byte-per-tile texture of tile states. All floes of
a template are drawn in one instanced call: the vertex shader finds its floe row as the
tile's first row plus the cell index and fetches the pose. Per frame only the pose rows of
tiles placed or simulated since the last frame are uploaded; frozen tiles cost nothing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import moderngl
import numpy as np

from bridge_node.render import shaders
from bridge_node.render.render_settings import ChannelSettings, RenderSettings
from sim_core.ice_scene import BREAKABLE
from sim_core.world import WorldData, WorldModel

GL_CLIP_DISTANCE0 = 0x3000
POSE_WIDTH = 2048  # texels per line of the pose textures
NEAR = 0.5  # m
SKY_HORIZON, SKY_ZENITH = (0.78, 0.84, 0.90), (0.38, 0.55, 0.78)
FOG = (0.70, 0.74, 0.78)
WATER = (0.10, 0.17, 0.22)
ICE_INTACT, ICE_BROKEN, ICE_EDGE = (0.93, 0.95, 0.97), (0.60, 0.68, 0.75), (0.52, 0.68, 0.78)


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


def _template_vertices(model: WorldModel, template: int) -> np.ndarray:
    """Interleaved (position 3f, normal 3f, cell index i4) of the triangles of a template
    that can be seen from above the water: bottom faces are left out. Triangles are wound
    counter-clockwise seen from outside, so back faces can be culled."""
    ice = model.ice
    g0, g1 = ice.template_start[template], ice.template_start[template + 1]
    t0, t1 = ice.tri_start[g0], ice.tri_start[g1]
    tris = ice.tris[t0:t1].copy()
    cell = np.repeat(np.arange(g1 - g0), np.diff(ice.tri_start[g0:g1 + 1]))
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    inward = (n * tris.mean(axis=1)).sum(axis=1) < 0.0  # the centroid is the origin
    n[inward] *= -1.0
    tris[inward] = tris[inward][:, ::-1]
    keep = n[:, 2] > -0.5
    tris, n, cell = tris[keep], n[keep], cell[keep]
    out = np.zeros(len(tris) * 3, dtype=[("p", "f4", 3), ("n", "f4", 3), ("c", "i4")])
    out["p"] = tris.reshape(-1, 3)
    out["n"] = np.repeat(n, 3, axis=0)
    out["c"] = np.repeat(cell, 3)
    return out


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
        tri = ctx.buffer(np.array([[-1, -1], [3, -1], [-1, 3]], dtype="f4").tobytes())
        self.env_vao = ctx.vertex_array(self.env, [(tri, "2f", "in_ndc")])
        self.quad = ctx.buffer(np.array([[-1, -1], [1, -1], [1, 1], [-1, -1], [1, 1], [-1, 1]], dtype="f4").tobytes())
        self.tile_state = ctx.texture((scene.nx, scene.ny), 1, dtype="u1")
        self.tile_state.filter = moderngl.NEAREST, moderngl.NEAREST
        self._tile_state = np.full(scene.nx * scene.ny, 255, dtype=np.uint8)  # forces the first upload
        hull = _ship_vertices(model.contour, settings.freeboard_m)
        self.ship_vao = ctx.vertex_array(self.ship, [(ctx.buffer(hull.tobytes()), "3f 3f", "in_pos", "in_normal")])
        self.templates = []
        for k in range(len(model.ice.templates)):
            vbo = ctx.buffer(_template_vertices(model, k).tobytes())
            self.templates.append({"vbo": vbo, "vertices": vbo.size // 28, "instances": 0, "ibo": None, "vao": None})
        self.pose_a = self.pose_b = None
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
        """Upload what changed since the last call: tile states, new tiles' instances, and
        the poses of the rows of tiles placed or simulated since then."""
        tiles = data.ice.tiles
        state = data.scene.tile_state
        changed = np.nonzero(state != self._tile_state)[0]
        if len(changed):
            nx = self.model.scene.nx
            if len(changed) > 64:
                self.tile_state.write(np.ascontiguousarray(state).tobytes())
            else:
                for t in changed:
                    self.tile_state.write(bytes([state[t]]), viewport=(int(t % nx), int(t // nx), 1, 1))
            self._tile_state = state.copy()
        st = data.ice.state
        self._ensure_pose_capacity(st.n)
        if len(tiles.template) != self._placed:
            self._placed = len(tiles.template)
            for k, t in enumerate(self.templates):
                starts = np.array([s for s, tk in zip(tiles.row_start, tiles.template) if tk == k], dtype="i4")
                t["instances"] = len(starts)
                if len(starts):
                    t["ibo"] = self.ctx.buffer(starts.tobytes())
                    t["vao"] = self.ctx.vertex_array(self.floe, [
                        (t["vbo"], "3f 3f i", "in_pos", "in_normal", "in_cell"), (t["ibo"], "i/i", "in_row_start")])
        # rows of tiles live now or at the last upload (a tile frozen since then gets its final pose)
        live = [tiles.row_start[data.scene.placement[int(t)]] for t in data.scene.live if int(t) in data.scene.placement]
        self._upload_poses(st, min([self._uploaded_rows, *live, *self._live_rows]))
        self._live_rows = live
        self._uploaded_rows = st.n

    def _ensure_pose_capacity(self, rows: int) -> None:
        lines = max(1, math.ceil(rows / POSE_WIDTH))
        if lines <= self._pose_lines:
            return
        lines = max(lines, 2 * self._pose_lines)
        for name in ("pose_a", "pose_b"):
            old = getattr(self, name)
            if old is not None:
                old.release()
            tex = self.ctx.texture((POSE_WIDTH, lines), 4, dtype="f4")
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

    # -- drawing --------------------------------------------------------------------------
    def draw(self, data: WorldData, channel: ChannelSettings) -> Camera:
        """Draw the scene for one channel into the bound framebuffer."""
        ctx, s = self.ctx, self.settings
        north, east, psi = (float(v) for v in (data.ship.eta[0], data.ship.eta[1], data.ship.eta[5]))
        cam = channel_camera(channel, north, east, psi, s.far_m)
        vp = cam.view_proj
        ctx.clear(*FOG, depth=1.0)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        fog = {"eye": tuple(cam.eye), "visibility": s.visibility_m, "fog_colour": FOG}
        scene = self.model.scene
        self.tile_state.use(0)
        ice = tuple(c * (0.7 + 0.3 * max(self.sun[2], 0.0)) for c in ICE_INTACT)
        self._set(self.env, inv_view_proj=np.linalg.inv(vp), horizon_colour=SKY_HORIZON, zenith_colour=SKY_ZENITH,
                  water_colour=WATER, ice_colour=ice, slab_z=self.slab_z, far=s.far_m, tile_state=0,
                  field_size=(scene.nx * scene.side, scene.ny * scene.side), tile_side=scene.side, **fog)
        self.env_vao.render()
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.enable_direct(GL_CLIP_DISTANCE0)
        if self.pose_a is not None:
            self.pose_a.use(1)
            self.pose_b.use(2)
            self._set(self.floe, view_proj=vp, pose_a=1, pose_b=2, pose_width=POSE_WIDTH, sun=self.sun,
                      intact_colour=ICE_INTACT, broken_colour=ICE_BROKEN, edge_colour=ICE_EDGE, **fog)
            ctx.enable(moderngl.CULL_FACE)
            for t in self.templates:
                if t["instances"]:
                    t["vao"].render(instances=t["instances"])
            ctx.disable(moderngl.CULL_FACE)  # the ship matrix mirrors (starboard-handed frame)
        ctx.disable_direct(GL_CLIP_DISTANCE0)
        self._set(self.ship, view_proj=vp, ship_to_world=ship_matrix(north, east, psi), sun=self.sun, **fog)
        self.ship_vao.render()
        return cam

    @staticmethod
    def _set(prog: moderngl.Program, **uniforms) -> None:
        for name, value in uniforms.items():
            if name not in prog:
                continue
            if isinstance(value, np.ndarray) and value.shape == (4, 4):
                prog[name].write(_mat(value))
            else:
                prog[name].value = value
