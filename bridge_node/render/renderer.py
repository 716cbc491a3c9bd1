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
and the ship's place, written once for every channel into a uniform buffer. The drawing is
the passes' (``bridge_node.render.passes``: one object per effect, its GLSL beside it), which
``SceneRenderer.draw`` sequences for a channel. The scene is drawn in the ice's own frame
(``WorldView.ice_offset``; ``sim_core.ice.drift.IceFrame``), where the tiles, floes and
rasters lie: the ship, its eye and searchlights and the other vessels are moved into it, so
a drifting field needs no upload.
"""
from __future__ import annotations

import functools
import math

import moderngl
import numpy as np

from bridge_node.render.camera import (Camera, box_corners, camera_on, outputs_matrix, ship_matrix, visible_boxes,
                                      visible_corners)
from bridge_node.render.classes import CLASS_INDEX, CLASSES
from bridge_node.render.floe_buffers import FloeBuffer
from bridge_node.render.passes.blend_bands import BlendBandPass
from bridge_node.render.passes.blocks import SharedBlocks
from bridge_node.render.passes.environment import EnvironmentPass
from bridge_node.render.passes.floes import SEEN_DEPTH, FloePass
from bridge_node.render.passes.glsl import FROZEN_CRACKED, UNPLACED_FLOE_FIELD, scene_defines
from bridge_node.render.passes.nav_lights import NavLightPass
from bridge_node.render.passes.ship import ShipPass
from bridge_node.render.meshes import cell_rasters, floe_field_layouts, rim_rasters, template_meshes
from bridge_node.render.scene_uploads import POSE_NAMES, POSE_UNITS, SceneUploads
from bridge_node.render.ridge_sails import SailMeshes
from bridge_node.render.rubble_look import ridge_uniforms, rubble_tile_bits
from bridge_node.render.settings import ChannelSettings, RenderSettings, eye_point
from bridge_node.render.ship_mesh import load_ship, nav_lights, ship_triangles
from bridge_node.render.sky import Sky
from bridge_node.render.textures import relief_noise
from bridge_node.stream.world_view import WorldView
from sim_core.ship.outputs import ShipOutputs
from sim_core.world import WorldModel

FLOE_DRIFT_MARGIN = 30.0  # m: broken floes may drift this far out of their tile
MAX_TILES = 4096 * 4096  # tile table of 8 bytes per tile: 134 MB of texture at most
RASTER_SIZE = 1024  # pixels per tile side of the cell rasters (0.1 m for 100 m tiles)
MIN_RASTER_SIZE = 64  # fewer pixels would blur the leads between the floes of tiles far off
WATER = (0.04, 0.09, 0.11)  # the sea's body colour (albedo of the light it sends back up)
NOISE_UNIT = 8  # texture unit of the relief noise
STATUS_UNIT = 7  # texture unit of the status texture
NAV_LIGHT_LUX = 10.0  # lux: daylight below which navigation lights show at full strength (civil dusk)
CRACK_REACH_PX = 4.0  # raster pixels from a cell edge within which a crack's line may be drawn (the distance)
EYE_WHITE_LUX = 40.0  # lux a surface needs to look white to eyes adapted to the night
TILE_INFO_UNIT, CELL_RASTER_UNIT = 0, 3  # texture units of the tile table and the cell rasters


def raster_size(templates: int, max_texture: int) -> int:
    """Pixels per tile side of the templates' cell rasters, stacked in one texture:
    ``RASTER_SIZE`` for a few templates, half of it for more, and halved again while the
    stack would be taller than the GL's largest texture (``max_texture`` pixels; a floe
    field's 36 templates with level ice's need 256 under llvmpipe's 16384, 64 need 128)."""
    size = RASTER_SIZE if templates <= 4 else RASTER_SIZE // 2
    while templates * size > max_texture and size > MIN_RASTER_SIZE:
        size //= 2
    if templates * size > max_texture:
        raise ValueError(f"{templates} tile templates: their cell rasters need a texture of {templates * size} "
                         f"pixels, more than this GL's {max_texture}")
    return size


class SceneRenderer(SceneUploads):
    """GPU resources of one world; draws it for any channel."""

    def __init__(self, ctx: moderngl.Context, model: WorldModel, settings: RenderSettings) -> None:
        self.ctx, self.model, self.settings = ctx, model, settings
        self._configured_aims = [light.mount().default for light in settings.searchlights]  # before any order
        scene = model.scene
        if max((t.n_cells for t in model.ice.templates), default=0) >= FROZEN_CRACKED:
            raise ValueError(f"the renderer draws tiles of fewer than {FROZEN_CRACKED} cells (a frozen tile's status "
                             "entries number them)")
        if scene.nx * scene.ny > MAX_TILES:
            raise ValueError(f"the renderer draws fields of up to {MAX_TILES} tiles; "
                             f"this one has {scene.nx * scene.ny}")
        # per tile: first status entry (its first row, or a frozen tile's first cell entry),
        # template | quarter turns << 16, level-ice thickness (m, float bits), 1 if breakable
        self.tile_thickness = scene.class_thickness[scene.tile_class].astype("f4")  # as laid, until retiled
        self.floe_field_info = floe_field_layouts(model, np.arange(len(scene.tile_class)), scene.tile_class)
        self.rubble_bits = rubble_tile_bits(model.rubble)  # the tile table flag entry's upper bytes
        self.tile_info = ctx.texture((scene.nx, scene.ny), 4, self._first_tile_table().tobytes(), dtype="i4")
        self.tile_info.filter = moderngl.NEAREST, moderngl.NEAREST
        mesh = load_ship(model.ship.particulars, model.contour, settings.freeboard_m)
        self.ship_extent = mesh.bounds  # (2, 3): lower and upper corner, ship frame, m
        self.meshes = template_meshes(model)
        self.mesh_vbos = [ctx.buffer(m.vertices.tobytes()) for m in self.meshes]
        self.raster_size = raster_size(len(model.ice.templates), ctx.info["GL_MAX_TEXTURE_SIZE"])
        cells = cell_rasters(model, self.raster_size)
        self.rim_px = settings.wet_rim_m / scene.side * self.raster_size
        # 4 components, the 4th unused: on llvmpipe, fetches of 3 cost a tenth of the frame more
        # neighbours within the wet rim, and at least within the cracks' reach (their lines)
        neighbours = rim_rasters(cells, self.raster_size, max(self.rim_px, CRACK_REACH_PX))
        raster = np.dstack([cells, neighbours, np.zeros_like(cells)])
        self.cell_raster = ctx.texture((self.raster_size, raster.shape[0]), 4, raster.tobytes(), dtype="u2")
        self.cell_raster.filter = moderngl.NEAREST, moderngl.NEAREST
        self.tile_floes: dict[int, tuple[FloeBuffer, FloeBuffer]] = {}  # placement -> (tops, sides)
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
        self._make_passes(ship_triangles(mesh), nav_lights(model.ship.particulars, mesh.bounds))
        self.sails = SailMeshes(ctx, self.ships.program, model.rubble, self.slab_z, settings.sail_distance_m)
        noise = relief_noise()
        self.noise = ctx.texture(noise.shape[:2], 4, noise.tobytes())
        self.noise.build_mipmaps()
        # minified, the nearest texel of the nearest mip level (on llvmpipe the relief's fetches cost
        # 40 % less than bilinear ones, and in noise the difference does not show); magnified (near
        # the eye, below the wings), bilinear
        self.noise.filter = moderngl.NEAREST_MIPMAP_NEAREST, moderngl.LINEAR
        self.sky: Sky | None = None
        self._ship_seen: ShipOutputs | None = None  # the ship published, whose matrix is _ship_to_world
        self._ship_to_world = np.eye(4)
        self._tile_boxes: tuple[list[int], np.ndarray, np.ndarray, np.ndarray] = ([], *np.zeros((3, 0, 2)))

    def _first_tile_table(self, tiles: np.ndarray | None = None) -> np.ndarray:
        """The tile table's rows (of these tiles; None: all) while not simulated: each
        tile's thickness, and a floe field's tiles their layouts, drawn from their
        templates' rasters."""
        tiles = np.arange(len(self.tile_thickness)) if tiles is None else tiles
        info = np.zeros((len(tiles), 4), "i4")
        info[:, 2] = self.tile_thickness[tiles].view("i4")
        info[:, 3] = self.rubble_bits[tiles]
        for i, tile in enumerate(tiles.tolist()):
            if tile in self.floe_field_info:
                info[i, 1], info[i, 3] = self.floe_field_info[tile], UNPLACED_FLOE_FIELD | self.rubble_bits[tile]
        return info

    def _make_passes(self, hull: np.ndarray, lights: np.ndarray) -> None:
        """The passes, their programs compiled with the field's searchlights and rubble, and
        their constants set; the uniform buffers they share."""
        ctx, rubble, scene = self.ctx, self.model.rubble, self.model.scene
        defines = scene_defines(len(self.settings.searchlights), rubble.has_brash, bool(rubble.ridges))
        units = {"noise": NOISE_UNIT, "status": STATUS_UNIT, **dict(zip(POSE_NAMES, POSE_UNITS))}
        self.ships = ShipPass(ctx, defines, units, hull)
        self.floes = FloePass(ctx, defines, units)
        self.environment = EnvironmentPass(ctx, defines, {
            **units, **ridge_uniforms(rubble), "tile_info": TILE_INFO_UNIT, "cell_raster": CELL_RASTER_UNIT,
            "slab_z": self.slab_z, "far": self.settings.far_m, "raster_size": self.raster_size, "rim_px": self.rim_px,
            "field_size": (scene.nx * scene.side, scene.ny * scene.side), "tile_side": scene.side})
        self.nav_lights = NavLightPass(ctx, defines, lights)
        self.blend_bands = BlendBandPass(ctx)
        self.blocks = SharedBlocks(ctx, defines["LIGHT_SLOTS"])
        self.blocks.attach(self.ships.program, self.floes.program, self.environment.ground, self.environment.sky,
                           self.nav_lights.program)

    def update(self, view: WorldView) -> None:
        """Upload what changed in the view (``SceneUploads.update``) and write the frame's
        ``Scene`` block: the sky, the visibility, the clock and the searchlights."""
        super().update(view)
        self._tile_boxes = self._floe_tile_boxes(view)
        sky = self.sky
        self.blocks.write_scene(sun=sky.sun, visibility=view.environment.visibility, direct=sky.direct,
                                relief_reach=self.settings.relief_reach_m, ambient=sky.ambient, time=view.time,
                                zenith_colour=sky.zenith, horizon_colour=sky.horizon, water_colour=WATER,
                                **self._searchlights(view.ship, view.ice_offset))

    def draw(self, view: WorldView, channel: ChannelSettings, blend: moderngl.Texture,
             classes: bool = False) -> Camera:
        """Draw the scene for one channel into the bound framebuffer, its columns scaled by
        the blend texture (width x 1 float: the channel's edge-blend factors); with
        ``classes``, its class mask instead (flat class colours: no reflections, lights or
        blending). ``update`` has taken the view's frame."""
        ctx, s = self.ctx, self.settings
        p = self.model.ship.particulars
        if view.ship is not self._ship_seen:  # the ship's matrix, once per frame for every channel
            self._ship_seen, self._ship_to_world = view.ship, outputs_matrix(view.ship, view.ice_offset)
        cam = camera_on(channel, eye_point(channel.eye, p.look.bridge_eye, p.beam), self._ship_to_world, s.far_m)
        self.blocks.write_view(cam.view_proj, cam.eye, classes)
        ctx.clear(*(np.divide(CLASSES[CLASS_INDEX["sky"]][1], 255.0) if classes else self.sky.horizon), depth=1.0)
        self.tile_info.use(TILE_INFO_UNIT)
        self.cell_raster.use(CELL_RASTER_UNIT)
        self.noise.use(NOISE_UNIT)
        for tex, unit in zip(self.pose, POSE_UNITS):
            tex.use(unit)
        if self.status is not None:
            self.status.use(STATUS_UNIT)
        # near to far: ship, floes, then the environment behind them, so that the depth test
        # spares the full-screen pass every pixel already covered
        ctx.enable(moderngl.DEPTH_TEST)
        ships = self._ship_matrices(view, cam)
        self.ships.draw(ships)
        if self.model.rubble.ridges:
            self.ships.draw_sails(self.sails, cam.eye)
        tiles = self._floe_tiles(cam)
        sides = functools.partial(self._sides, view)
        self.floes.draw(tiles, self.tile_floes, sides, s.lod_distance_m)
        self.environment.draw(cam, channel)
        if classes:
            return cam
        self.floes.reflections(tiles, sides, s.reflection_distance_m)
        self.nav_lights.draw(ships, channel.height, min(NAV_LIGHT_LUX / max(self.sky.illuminance, 1e-6), 1.0))
        self.blend_bands.draw(channel, blend)
        return cam

    def build_all(self, view: WorldView) -> None:
        """Build now what the renderer otherwise builds a little each frame (the ridges'
        sails near the ship): for a single frame that should show everything (a snapshot)."""
        self.sails.update(np.array([view.ship.east, view.ship.north]) - view.ice_offset, budget_s=math.inf)

    def _searchlights(self, ship: ShipOutputs, ice_offset: np.ndarray) -> dict:
        """The searchlights' entries of the ``Scene`` block for the published ship: positions
        in the ice's frame (the world's less ice_offset, m), beam axes, and per beam the
        cosine of half its width and its intensity over the illuminance the eye sees as white (the daylight's, or EYE_WHITE_LUX at
        night); 0 for a light switched off. Each is aimed as published (the console's
        orders), else as configured."""
        n = max(len(self.settings.searchlights), 1)  # the blocks' arrays (LIGHT_SLOTS), filled whole
        pos, axis, beam = np.zeros((n, 4)), np.zeros((n, 4)), np.zeros((n, 4))
        beam[:, 0] = 1.0
        to_world = outputs_matrix(ship, ice_offset)
        for k, light in enumerate(self.settings.searchlights):
            aim = ship.searchlights[k] if k < len(ship.searchlights) else self._configured_aims[k]
            az, el = ship.heading + aim.bearing, aim.elevation
            pos[k, :3] = (to_world @ np.array([*light.position, 1.0]))[:3]
            axis[k, :3] = math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el)
            beam[k, 0] = math.cos(math.radians(light.beam_deg) / 2)
            beam[k, 1] = light.intensity_cd / max(self.sky.illuminance, EYE_WHITE_LUX) if aim.on else 0.0
        return {"light_pos": pos, "light_axis": axis, "light_beam": beam}

    def _floe_tile_boxes(self, view: WorldView) -> tuple[list[int], np.ndarray, np.ndarray, np.ndarray]:
        """The tiles with broken floes and their boxes, once per frame: (placements, the
        boxes' corners (n, 8, 4), with a margin for drift and their mirror images in the water;
        the boxes' lower and upper corners across the water (n, 2), m)."""
        keys = list(self.tile_floes)
        corner = np.array([view.placements[k].corner for k in keys], dtype=float).reshape(-1, 2)
        lo, hi = corner - FLOE_DRIFT_MARGIN, corner + self.model.scene.side + FLOE_DRIFT_MARGIN
        depth = np.full((len(keys), 1), SEEN_DEPTH)
        return keys, box_corners(np.hstack([lo, -depth]), np.hstack([hi, depth])), lo, hi

    def _floe_tiles(self, cam: Camera) -> list[tuple[int, float]]:
        """The tiles with broken floes whose box is in view: (placement, distance from the
        eye across the water to the box, m)."""
        keys, corners, lo, hi = self._tile_boxes
        if not keys:
            return []
        seen = visible_corners(cam.view_proj, corners)
        gap = np.maximum(np.maximum(lo - cam.eye[:2], cam.eye[:2] - hi), 0.0)
        dist = np.hypot(gap[:, 0], gap[:, 1])
        return [(k, d) for k, show, d in zip(keys, seen.tolist(), dist.tolist()) if show]

    def _ship_matrices(self, view: WorldView, cam: Camera) -> list[np.ndarray]:
        """Ship frame to world of the own ship and of each other vessel in view and within the
        far distance, scaled to its length and beam (the own ship's where unknown, 0) and in
        height as in beam."""
        out = [self._ship_to_world]
        traffic = getattr(view, "traffic", None)
        if traffic is None or len(traffic) == 0:
            return out
        p = self.model.ship.particulars
        length = np.where(traffic["length"] > 0, traffic["length"], p.length)
        beam = np.where(traffic["beam"] > 0, traffic["beam"], p.beam)
        lo, hi = self.ship_extent
        reach = np.hypot(lo[:2], hi[:2]).max() * np.maximum(length / p.length, beam / p.beam)
        x, y = traffic["x"] - view.ice_offset[0], traffic["y"] - view.ice_offset[1]  # into the ice's frame
        centre = np.column_stack([x, y, np.zeros(len(traffic))])
        pad = np.column_stack([reach, reach, np.full(len(traffic), hi[2] * (beam / p.beam).max())])
        near = np.hypot(x - cam.eye[0], y - cam.eye[1]) < self.settings.far_m
        for k in np.flatnonzero(visible_boxes(cam.view_proj, centre - pad, centre + pad) & near):
            scale = np.diag([length[k] / p.length, beam[k] / p.beam, beam[k] / p.beam, 1.0])
            out.append(ship_matrix(y[k], x[k], traffic["heading"][k]) @ scale)
        return out
