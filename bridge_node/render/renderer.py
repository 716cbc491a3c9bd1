"""Draw the world state to the projector channels with moderngl.

GPU data mirrors the MuJoCo-style split of the simulation. Static: each template's cells as
indexed triangles about their centroids (seen from above the water: no bottom faces; each
vertex names its cell), shared by every tile laid with the template; each template's cell
raster (which cell covers each 0.1 m of the tile); the own ship's mesh. Dynamic: two float
textures holding every floe row's pose (its attitude as a quaternion, made on the CPU; x,
y, heave) and a texture of each row's status, a tile table (each placed tile's first
status entry, template and rotation, and whether it is breakable), and per tile the
triangles of its broken floes (tops and sides apart), to which a cell's triangles are
appended once, when it breaks: a live tile keeps a copy of its floes' vertices (faster to
fetch on llvmpipe), a frozen tile only indices into its template's. The vertex
shader finds each vertex's floe from the tile's first row and the vertex's cell, and
places it by the pose textures. A frozen tile gives its rows up (they go to other tiles):
its floes get pose entries of their own, and its cells status entries that name each
broken cell's floe, numbered from the last texture line down while live rows fill from the
first line up; its floes' side faces are indexed only when first needed. A tile's floes are
drawn only when its box is in the channel's view, their side faces only within the
level-of-detail distance; within the reflection distance their side faces are drawn once
more, mirrored in the water plane over the sea, as their reflections. Level ice
(unbreakable tiles and the intact cells of breakable ones) is drawn per pixel by the
environment pass from the cell raster, so it costs no triangles: on a software rasteriser
the vertex work of thousands of intact cells would dominate the frame. Per frame only the
poses of tiles placed or simulated since the last frame are uploaded; a frozen tile's
once, when it freezes. Also static: the relief noise texture (mipmapped) and each tile's
level-ice thickness (in the tile table); per frame, the sun and sky of the exercise's time
and the ship's place.
"""
from __future__ import annotations

import math

import moderngl
import numpy as np

from bridge_node.render import object_shaders, shaders
from bridge_node.render.camera import Camera, channel_camera, outputs_matrix, set_matrix, ship_matrix, visible_boxes
from bridge_node.render.classes import CLASS_INDEX, CLASSES
from bridge_node.render.floe_buffers import FloeBuffer, horizon_split
from bridge_node.render.meshes import cell_rasters, floe_field_layouts, rim_rasters, template_meshes
from bridge_node.render.scene_uploads import POSE_NAMES, POSE_UNITS, SceneUploads
from bridge_node.render.ridge_sails import SailMeshes
from sim_core.regimes.rubble import RubbleModel
from bridge_node.render.rubble_look import ridge_uniforms, rubble_tile_bits
from bridge_node.render.shaders import FROZEN_CRACKED, UNPLACED_FLOE_FIELD
from bridge_node.render.settings import ChannelSettings, RenderSettings, eye_point
from bridge_node.render.ship_mesh import load_ship, nav_lights, ship_triangles
from bridge_node.render.sky import Sky
from bridge_node.render.textures import relief_noise
from bridge_node.stream.world_view import WorldView
from sim_core.ship.outputs import ShipOutputs
from sim_core.world import WorldModel

GL_CLIP_DISTANCE0 = 0x3000
FLOE_DRIFT_MARGIN = 30.0  # m: broken floes may drift this far out of their tile
MAX_TILES = 4096 * 4096  # tile table of 8 bytes per tile: 134 MB of texture at most
RASTER_SIZE = 1024  # pixels per tile side of the cell rasters (0.1 m for 100 m tiles)
WATER = (0.04, 0.09, 0.11)  # the sea's body colour (albedo of the light it sends back up)
NOISE_UNIT = 8  # texture unit of the relief noise
STATUS_UNIT = 7  # texture unit of the status texture
NAV_LIGHT_LUX = 10.0  # lux: daylight below which navigation lights show at full strength (civil dusk)
CRACK_REACH_PX = 4.0  # raster pixels from a cell edge within which a crack's line may be drawn (the distance)
EYE_WHITE_LUX = 40.0  # lux a surface needs to look white to eyes adapted to the night


class SceneRenderer(SceneUploads):
    """GPU resources of one world; draws it for any channel."""

    def __init__(self, ctx: moderngl.Context, model: WorldModel, settings: RenderSettings) -> None:
        self.ctx, self.model, self.settings = ctx, model, settings
        self._configured_aims = [light.mount().default for light in settings.searchlights]  # before any order
        scene = model.scene
        self._make_programs(len(settings.searchlights), model.rubble)
        if max((t.n_cells for t in model.ice.templates), default=0) >= FROZEN_CRACKED:
            raise ValueError(f"the renderer draws tiles of fewer than {FROZEN_CRACKED} cells (a frozen tile's status "
                             "entries number them)")
        if scene.nx * scene.ny > MAX_TILES:
            raise ValueError(f"the renderer draws fields of up to {MAX_TILES} tiles; "
                             f"this one has {scene.nx * scene.ny}")
        # per tile: first status entry (its first row, or a frozen tile's first cell entry),
        # template | quarter turns << 16, level-ice thickness (m, float bits), 1 if breakable
        self.tile_thickness = scene.class_thickness[scene.tile_class].astype("f4")
        self.floe_field_info = floe_field_layouts(model)  # tile -> its template | turns << 16
        self.rubble_bits = rubble_tile_bits(model.rubble)  # the tile table flag entry's upper bytes
        self.tile_info = ctx.texture((scene.nx, scene.ny), 4, self._first_tile_table().tobytes(), dtype="i4")
        self.tile_info.filter = moderngl.NEAREST, moderngl.NEAREST
        mesh = load_ship(model.ship.particulars, model.contour, settings.freeboard_m)
        self.ship_extent = mesh.bounds  # (2, 3): lower and upper corner, ship frame, m
        hull = ship_triangles(mesh)
        self.ship_vao = ctx.vertex_array(self.ship, [(ctx.buffer(hull.tobytes()), "3f 3f 3f", "in_pos", "in_normal",
                                                      "in_colour")])
        self.nav = ctx.program(vertex_shader=object_shaders.NAV_VS, fragment_shader=object_shaders.NAV_FS)
        points = nav_lights(model.ship.particulars, mesh.bounds)
        self.nav_vao = ctx.vertex_array(self.nav, [(ctx.buffer(points.tobytes()), "3f 3f 2f", "in_pos", "in_colour",
                                                    "in_sector")])
        self.meshes = template_meshes(model)
        self.mesh_vbos = [ctx.buffer(m.vertices.tobytes()) for m in self.meshes]
        self.raster_size = RASTER_SIZE if len(model.ice.templates) <= 4 else RASTER_SIZE // 2
        cells = cell_rasters(model, self.raster_size)
        self.rim_px = settings.wet_rim_m / scene.side * self.raster_size
        # 4 components, the 4th unused: on llvmpipe, fetches of 3 cost a tenth of the frame more
        # neighbours within the wet rim, and at least within the cracks' reach (their lines)
        neighbours = rim_rasters(cells, self.raster_size, max(self.rim_px, CRACK_REACH_PX))
        raster = np.dstack([cells, neighbours, np.zeros_like(cells)])
        self.cell_raster = ctx.texture((self.raster_size, raster.shape[0]), 4, raster.tobytes(), dtype="u2")
        self.cell_raster.filter = moderngl.NEAREST, moderngl.NEAREST
        self.tile_floes: dict[int, tuple[FloeBuffer, FloeBuffer]] = {}  # placement -> (tops, sides)
        self._tile_draw: dict[int, dict] = {}  # placement -> the floe program's uniforms for its tile
        self._sides_due: set[int] = set()  # frozen placements whose side faces are made when first needed
        self._drawn = np.zeros(0, dtype=bool)  # by row: its triangles are in its tile's buffers
        self.pose: list[moderngl.Texture] = []  # each floe row's (and frozen floe's) attitude and place
        self.status: moderngl.Texture | None = None  # each floe row's status, each frozen tile's cell's floe
        self._pose_lines = self._status_lines = 0
        self._frozen: dict[int, tuple[int, int]] = {}  # frozen placement -> its first floe and first cell entry
        self._frozen_floes = self._frozen_cells = 0  # entries given to frozen tiles (renumbered as textures grow)
        h = model.ice.thickness.mean() if len(model.ice.thickness) else 0.0
        mat = model.ice.material
        self.slab_z = float(h * (1.0 - mat.density / mat.water_density))
        self.template_thickness = [t.thickness for t in model.ice.templates]
        self.sails = SailMeshes(ctx, self.ship, model.rubble, self.slab_z, settings.sail_distance_m)
        noise = relief_noise()
        self.noise = ctx.texture(noise.shape[:2], 4, noise.tobytes())
        self.noise.build_mipmaps()
        # minified, the nearest texel of the nearest mip level (on llvmpipe the relief's fetches cost
        # 40 % less than bilinear ones, and in noise the difference does not show); magnified (near
        # the eye, below the wings), bilinear
        self.noise.filter = moderngl.NEAREST_MIPMAP_NEAREST, moderngl.LINEAR
        self.sky: Sky | None = None

    def _first_tile_table(self) -> np.ndarray:
        """The tile table before any tile is simulated: every tile's thickness, and a floe
        field's tiles their layouts, drawn from their templates' rasters."""
        info = np.zeros((len(self.tile_thickness), 4), "i4")
        info[:, 2] = self.tile_thickness.view("i4")
        info[:, 3] = self.rubble_bits
        for tile, layout in self.floe_field_info.items():
            info[tile, 1], info[tile, 3] = layout, UNPLACED_FLOE_FIELD | self.rubble_bits[tile]
        return info

    def _make_programs(self, lights: int, rubble: RubbleModel) -> None:
        """The shader programs (with ``lights`` searchlights, and the environment pass with
        brash and ridges where the field has them, its ridge uniforms set once) and the
        screen-space buffers of the environment, sky and blend band."""
        ctx = self.ctx
        env = shaders.with_rubble(shaders.with_lights(shaders.ENV_FS, lights), rubble.has_brash, bool(rubble.ridges))
        self.env = ctx.program(vertex_shader=shaders.ENV_VS, fragment_shader=env)
        self._set(self.env, **ridge_uniforms(rubble))
        self.floe = ctx.program(vertex_shader=object_shaders.FLOE_VS,
                                fragment_shader=shaders.with_lights(object_shaders.FLOE_FS, lights))
        self.ship = ctx.program(vertex_shader=object_shaders.SHIP_VS,
                                fragment_shader=shaders.with_lights(object_shaders.SHIP_FS, lights))
        self.band = ctx.program(vertex_shader=object_shaders.BAND_VS, fragment_shader=object_shaders.BAND_FS)
        self.band_buf = ctx.buffer(reserve=2 * 6 * 2 * 4)
        self.band_vao = ctx.vertex_array(self.band, [(self.band_buf, "2f", "in_ndc")])
        self.sky_prog = ctx.program(vertex_shader=shaders.ENV_VS,
                                    fragment_shader=shaders.with_lights(shaders.SKY_FS, lights))
        self.env_buf = ctx.buffer(reserve=2 * 9 * 5 * 4)  # ground, then sky: 3 triangles each at most
        self.env_vao = ctx.vertex_array(self.env, [(self.env_buf, "2f 3f", "in_ndc", "in_ray")])
        self.sky_vao = ctx.vertex_array(self.sky_prog, [(self.env_buf, "2f 3f", "in_ndc", "in_ray")])

    # -- per frame uploads ----------------------------------------------------------------

    def draw(self, view: WorldView, channel: ChannelSettings, blend: moderngl.Texture,
             classes: bool = False) -> Camera:
        """Draw the scene for one channel into the bound framebuffer, its columns scaled by
        the blend texture (width x 1 float: the channel's edge-blend factors); with
        ``classes``, its class mask instead (flat class colours: no reflections, lights or
        blending)."""
        ctx, s = self.ctx, self.settings
        north, east, psi = view.ship.north, view.ship.east, view.ship.heading
        p = self.model.ship.particulars
        cam = channel_camera(channel, eye_point(channel.eye, p.look.bridge_eye, p.beam), north, east, psi, s.far_m,
                             view.ship.heave, view.ship.pitch, view.ship.roll)
        vp = cam.view_proj
        sky = self.sky
        common = {"eye": tuple(cam.eye), "visibility": view.environment.visibility, "sun": sky.sun,
                  "direct": sky.direct, "ambient": sky.ambient, "zenith_colour": sky.zenith,
                  "horizon_colour": sky.horizon,
                  "noise": NOISE_UNIT, "water_colour": WATER,
                  "relief_reach": s.relief_reach_m, "time": view.time, "classes": classes,
                  **self._searchlights(view.ship)}
        ctx.clear(*(np.divide(CLASSES[CLASS_INDEX["sky"]][1], 255.0) if classes else sky.horizon), depth=1.0)
        self.tile_info.use(0)
        self.cell_raster.use(3)
        self.noise.use(NOISE_UNIT)
        for tex, unit in zip(self.pose, POSE_UNITS):
            tex.use(unit)
        if self.status is not None:
            self.status.use(STATUS_UNIT)
        # near to far: ship, floes, then the environment behind them, so that the depth test
        # spares the full-screen pass every pixel already covered
        ctx.enable(moderngl.DEPTH_TEST)
        ships = self._ship_matrices(view, cam)
        self._set(self.ship, view_proj=vp, **common)
        for k, m in enumerate(ships):  # the own ship first
            self._set(self.ship, ship_class=CLASS_INDEX["own_ship" if k == 0 else "other_vessel"])
            set_matrix(self.ship["ship_to_world"], m)
            self.ship_vao.render()
        if self.model.rubble.ridges:
            self._draw_sails(cam)
        tiles = self._floe_tiles(view, cam) if self.tile_floes else None
        if tiles:
            ctx.enable_direct(GL_CLIP_DISTANCE0)
            ctx.enable(moderngl.CULL_FACE)  # not for the ship: its matrix mirrors (starboard-handed frame)
            self._set(self.floe, view_proj=vp, **dict(zip(POSE_NAMES, POSE_UNITS)), status=STATUS_UNIT, reflected=False,
                      **common)
            self._draw_floes(view, tiles)
            ctx.disable(moderngl.CULL_FACE)
            ctx.disable_direct(GL_CLIP_DISTANCE0)
        self._draw_environment(cam, channel, common)
        if classes:
            return cam
        if tiles:
            self._draw_reflections(view, tiles)
        self._draw_nav_lights(ships, cam, channel.height, view.environment.visibility)
        self._blend_bands(channel, blend)
        return cam

    def build_all(self, view: WorldView) -> None:
        """Build now what the renderer otherwise builds a little each frame (the ridges'
        sails near the ship): for a single frame that should show everything (a snapshot)."""
        self.sails.update(np.array([view.ship.east, view.ship.north]), budget_s=math.inf)

    def _draw_sails(self, cam: Camera) -> None:
        """The ridges' sails near the eye, with the ship program (its uniforms set)."""
        self.sails.update(cam.eye)
        self._set(self.ship, ship_class=CLASS_INDEX["level_ice"])
        set_matrix(self.ship["ship_to_world"], np.eye(4))
        self.sails.render()

    def _draw_environment(self, cam: Camera, channel: ChannelSettings, common: dict) -> None:
        """The environment pass below the horizon (sea and level ice, per pixel) and the sky
        pass above it."""
        half = math.radians(channel.hfov_deg) / 2
        ground, above = horizon_split(cam, math.tan(half), math.tan(channel.vfov() / 2), channel.width,
                                      channel.height)
        self.env_buf.write(np.vstack([ground, above]).astype("f4").tobytes())
        scene = self.model.scene
        if len(ground):
            self._set(self.env, slab_z=self.slab_z, far=self.settings.far_m, tile_info=0,
                      cell_raster=3, raster_size=self.raster_size, rim_px=self.rim_px, status=STATUS_UNIT,
                      field_size=(scene.nx * scene.side, scene.ny * scene.side), tile_side=scene.side,
                      **common)
            self.env_vao.render(vertices=len(ground))
        if len(above):
            self._set(self.sky_prog, **common)
            self.sky_vao.render(vertices=len(above), first=len(ground))

    def _searchlights(self, ship: ShipOutputs) -> dict:
        """The searchlights' uniforms for the published ship: world positions, beam axes, the
        cosines of half their beams, and their intensities over the illuminance the eye
        sees as white (the daylight's, or EYE_WHITE_LUX at night); 0 for a light switched
        off. Each is aimed as published (the console's orders), else as configured."""
        n = max(len(self.settings.searchlights), 1)  # the shaders' arrays (see shaders.with_lights), filled whole
        pos, axis, cos, power = np.zeros((n, 3)), np.zeros((n, 3)), np.ones(n), np.zeros(n)
        to_world = outputs_matrix(ship)
        for k, light in enumerate(self.settings.searchlights):
            aim = ship.searchlights[k] if k < len(ship.searchlights) else self._configured_aims[k]
            az, el = ship.heading + aim.bearing, aim.elevation
            pos[k] = (to_world @ np.array([*light.position, 1.0]))[:3]
            axis[k] = math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el)
            cos[k] = math.cos(math.radians(light.beam_deg) / 2)
            power[k] = light.intensity_cd / max(self.sky.illuminance, EYE_WHITE_LUX) if aim.on else 0.0
        return {"light_pos": pos, "light_axis": axis, "light_cos": cos, "light_power": power}

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

    def _floe_tiles(self, view: WorldView, cam: Camera) -> list[tuple[int, float]]:
        """The tiles with broken floes whose box (with a margin for drift, and its mirror
        image in the water) is in view: (placement, distance from the eye across the
        water to the box, m)."""
        keys = list(self.tile_floes)
        corner = np.array([view.placements[k].corner for k in keys], dtype=float)
        side = self.model.scene.side
        lo = np.column_stack([corner - FLOE_DRIFT_MARGIN, np.full(len(keys), -object_shaders.SEEN_DEPTH)])
        hi = np.column_stack([corner + side + FLOE_DRIFT_MARGIN, np.full(len(keys), object_shaders.SEEN_DEPTH)])
        seen = visible_boxes(cam.view_proj, lo, hi)
        gap = np.maximum(np.maximum(lo[:, :2] - cam.eye[:2], cam.eye[:2] - hi[:, :2]), 0.0)
        dist = np.hypot(gap[:, 0], gap[:, 1])
        return [(k, float(d)) for k, show, d in zip(keys, seen, dist) if show]

    def _draw_floes(self, view: WorldView, tiles: list[tuple[int, float]]) -> None:
        """The tiles' broken floes; their side faces only within the level-of-detail distance."""
        for k, dist in tiles:
            self._set(self.floe, **self._tile_draw[k])
            self.tile_floes[k][0].render()
            if dist < self.settings.lod_distance_m:
                self._sides(view, k).render()

    def _draw_reflections(self, view: WorldView, tiles: list[tuple[int, float]]) -> None:
        """The floes' reflections in the sea, within the reflection distance: their side
        faces above the water, mirrored in the water plane and blended over the sea by its
        Fresnel share (tops, seen from below the water, are culled). Polygon offset puts a
        mirrored freeboard before the submerged part of the same side, in whose plane it lies."""
        near = [(k, d) for k, d in tiles if d < self.settings.reflection_distance_m]
        if not near:
            return
        ctx = self.ctx
        ctx.enable_direct(GL_CLIP_DISTANCE0)
        ctx.enable(moderngl.CULL_FACE | moderngl.BLEND)
        ctx.front_face = "cw"  # the mirror turns the winding
        ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        ctx.polygon_offset = -1.0, -1.0
        self.floe["reflected"].value = True
        for k, _ in near:
            self._set(self.floe, **self._tile_draw[k])
            self._sides(view, k).render()
        self.floe["reflected"].value = False
        ctx.polygon_offset = 0.0, 0.0
        ctx.front_face = "ccw"
        ctx.disable(moderngl.CULL_FACE | moderngl.BLEND)
        ctx.disable_direct(GL_CLIP_DISTANCE0)

    def _ship_matrices(self, view: WorldView, cam: Camera) -> list[np.ndarray]:
        """Ship frame to world of the own ship and of each other vessel in view and within the
        far distance, scaled to its length and beam (the own ship's where unknown, 0) and in
        height as in beam."""
        ship = view.ship
        out = [outputs_matrix(ship)]
        traffic = getattr(view, "traffic", None)
        if traffic is None or len(traffic) == 0:
            return out
        p = self.model.ship.particulars
        length = np.where(traffic["length"] > 0, traffic["length"], p.length)
        beam = np.where(traffic["beam"] > 0, traffic["beam"], p.beam)
        lo, hi = self.ship_extent
        reach = np.hypot(lo[:2], hi[:2]).max() * np.maximum(length / p.length, beam / p.beam)
        centre = np.column_stack([traffic["x"], traffic["y"], np.zeros(len(traffic))])
        pad = np.column_stack([reach, reach, np.full(len(traffic), hi[2] * (beam / p.beam).max())])
        near = np.hypot(traffic["x"] - cam.eye[0], traffic["y"] - cam.eye[1]) < self.settings.far_m
        for k in np.flatnonzero(visible_boxes(cam.view_proj, centre - pad, centre + pad) & near):
            scale = np.diag([length[k] / p.length, beam[k] / p.beam, beam[k] / p.beam, 1.0])
            out.append(ship_matrix(traffic["y"][k], traffic["x"][k], traffic["heading"][k]) @ scale)
        return out

    def _draw_nav_lights(self, matrices: list[np.ndarray], cam: Camera, height: int, visibility: float) -> None:
        """The ships' navigation lights, added where their sectors face the eye, as strong
        as the daylight leaves them (full below NAV_LIGHT_LUX), fogged by the visibility (m)."""
        strength = min(NAV_LIGHT_LUX / max(self.sky.illuminance, 1e-6), 1.0)
        if strength < 0.01:
            return
        ctx = self.ctx
        ctx.enable(moderngl.PROGRAM_POINT_SIZE | moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        ctx.depth_mask = False
        self._set(self.nav, view_proj=cam.view_proj, eye=tuple(cam.eye), visibility=visibility,
                  point_px=max(3.0, 6.0 * height / 720), strength=strength)
        for m in matrices:
            set_matrix(self.nav["ship_to_world"], m)
            self.nav_vao.render(moderngl.POINTS)
        ctx.depth_mask = True
        ctx.disable(moderngl.PROGRAM_POINT_SIZE | moderngl.BLEND)

    @staticmethod
    def _set(prog: moderngl.Program, **uniforms) -> None:
        for name, value in uniforms.items():
            if name not in prog:
                continue
            if isinstance(value, np.ndarray) and value.shape == (4, 4):
                set_matrix(prog[name], value)
            elif isinstance(value, np.ndarray):  # a uniform array, written whole
                prog[name].write(value.astype("f4").tobytes())
            else:
                prog[name].value = value
