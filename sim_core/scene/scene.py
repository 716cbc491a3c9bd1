"""Scene management of the ice field (paper §2.4): which tiles are breakable right now.

Every tile of the field is in one of three ``TileState``s. UNBREAKABLE: one slab of level ice that
costs nothing (the default). BREAKABLE: its pre-fractured template is placed in the ice
world and simulated. FROZEN: it was breakable, the ship has left it behind; its floes keep
their last pose and are drawn, but cost no physics. Unlike the paper's reverse replacement,
freezing keeps the broken channel behind the ship in the scene.

``update_scene`` is pure scene logic over the tile-state array: from the hull's contour
points it decides which tiles to place, thaw and freeze. ``tiles_to_prepare`` names the
tiles in an outer ring beyond R_T that will soon need placing or thawing, so that their
engine objects can be built ahead (R_T itself stays the paper's). The world step applies those
decisions to the ice world. Tile variants and rotations are drawn from a hash of the tile's
index, so neighbours do not repeat and a rerun lays out the same field.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import IntEnum
from typing import Literal

import numpy as np
from pydantic import Field

from sim_core.params import Params
from sim_core.scene.quadtree import detection_radius, tile_under, tiles_near


class TileState(IntEnum):
    """State of a tile of the field."""

    UNBREAKABLE = 0
    BREAKABLE = 1
    FROZEN = 2


class SceneSettings(Params):
    """How the scene swaps tiles around the hull."""

    detection: Literal["contour", "origin"] = Field(
        "contour", description="contour: the paper's 34 contour points and R_T; origin: the traditional test")
    reverse_replacement: bool = Field(True, description="freeze breakable tiles far from the ship")
    reverse_distance: float = Field(700.0, gt=0.0, le=1.0e5, description="freeze beyond this distance, m")
    prepare_ahead: float = Field(
        60.0, ge=0.0, le=1000.0,
        description="tiles within R_T plus this (m) are prepared ahead of their switch; 0 builds them at the switch")
    prepare_budget_ms: float = Field(1.0, gt=0.0, le=50.0, description="wall time per step spent preparing tiles, ms")


# A tile whose ice the instructor changed (``sim_core.instructor.SetIce``), as published:
# its flat index and its new class.
RETILED = np.dtype([("tile", np.int32), ("ice_class", np.uint8)])


@dataclass(frozen=True)
class SceneModel:
    """Static scene data: the tile grid, each tile's thickness class as laid, each class's
    thickness, templates and name (what the instructor calls it)."""

    settings: SceneSettings
    nx: int
    ny: int
    side: float  # m
    radius: float  # detection radius R_T, m
    tile_class: np.ndarray  # (ny * nx,) uint8: thickness class of each tile as laid
    class_thickness: np.ndarray  # (classes,) m
    class_templates: tuple  # per class: array of the ice model's template indices (variants)
    class_names: tuple[str, ...] = ()  # per class: "open water", "level ice 0.50 m", a floe field's egg code
    class_repeat: tuple[int, ...] = ()  # per class: tiles across the square its templates repeat in (0: variants)

    def centre(self, tiles: np.ndarray) -> np.ndarray:
        """Centres (n, 2) of flat tile indices, world m."""
        tiles = np.asarray(tiles)
        return np.column_stack([(tiles % self.nx + 0.5) * self.side, (tiles // self.nx + 0.5) * self.side])

    def thickness_at(self, point: np.ndarray, tile_class: np.ndarray) -> float:
        """Level-ice thickness (m) of the tile holding the point, its class as ``tile_class``
        gives it (``SceneData.tile_class``); 0 off the field."""
        tile = tile_under(point, self.nx, self.ny, self.side)
        return 0.0 if tile < 0 else float(self.class_thickness[tile_class[tile]])


@dataclass
class SceneData:
    """Per-step scene state: every tile's state and class, and where breakable tiles sit in
    the ice world."""

    tile_state: np.ndarray  # (ny * nx,) uint8
    tile_class: np.ndarray  # (ny * nx,) uint8: as laid, unless the instructor changed a tile's ice
    placement: dict[int, int] = field(default_factory=dict)  # tile -> index of its placement in the ice world
    live: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))  # TileState.BREAKABLE tiles


@dataclass
class SceneUpdate:
    """Decisions of one update: flat tile indices to place, thaw and freeze."""

    place: np.ndarray
    thaw: np.ndarray
    freeze: np.ndarray


def compile_scene(settings: SceneSettings, tile_class: np.ndarray, class_thickness: np.ndarray,
                  class_templates: list[np.ndarray], tile_side: float, ship_length: float,
                  class_names: list[str] | None = None, class_repeat: list[int] | None = None) -> SceneModel:
    """Scene model of a field whose tiles (ny, nx) carry thickness classes (indices into
    class_thickness, m); class_templates lists each class's template indices, class_names
    their names (by default "open water" or "level ice H m"), class_repeat the classes whose
    templates are the windows of a repeating square, n x n tiles (0 or none: variants)."""
    radius = detection_radius(tile_side, ship_length)
    if settings.reverse_replacement and settings.reverse_distance < radius + ship_length:
        raise ValueError(f"reverse_distance = {settings.reverse_distance} m must be at least R_T + L = "
                         f"{radius + ship_length:.1f} m, or tiles near the hull would be frozen")
    ny, nx = tile_class.shape
    names = class_names or [level_ice_name(h) for h in class_thickness]
    if len(names) != len(class_thickness) or len(set(names)) != len(names):
        raise ValueError(f"class names {names} must name each of {len(class_thickness)} classes once")
    repeat = tuple(class_repeat or [0] * len(class_thickness))
    if len(repeat) != len(class_thickness) or any(n and len(t) != n * n for n, t in zip(repeat, class_templates)):
        raise ValueError(f"class repeats {repeat}: a class repeating in n x n tiles needs n * n templates")
    return SceneModel(settings, nx, ny, float(tile_side), radius, np.ascontiguousarray(tile_class, np.uint8).ravel(),
                      np.asarray(class_thickness, float), tuple(np.asarray(t, np.int64) for t in class_templates),
                      tuple(names), repeat)


def level_ice_name(thickness: float) -> str:
    """What the instructor calls a level-ice class of this thickness (m)."""
    return "open water" if thickness <= 0.0 else f"level ice {thickness:.2f} m"


def open_water(model: SceneModel) -> SceneModel:
    """The same scene without its field: no tiles, so the ship is in open water everywhere
    (a console commissioned with no ice, ``icebridge links monitor``)."""
    return replace(model, nx=0, ny=0, tile_class=np.zeros(0, dtype=np.uint8))


def new_scene_data(model: SceneModel) -> SceneData:
    """Every tile unbreakable, of its class as laid."""
    return SceneData(np.zeros(model.nx * model.ny, dtype=np.uint8), model.tile_class.copy())


def detected_tiles(model: SceneModel, contour: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Tiles that must be breakable for hulls with these world contour points (n, 2) and
    reference points ((2,) or (h, 2)), m, by the configured detection."""
    if model.settings.detection == "origin":
        tiles = {tile_under(o, model.nx, model.ny, model.side) for o in np.reshape(origin, (-1, 2))}
        return np.array(sorted(tiles - {-1}), dtype=np.int64)
    return tiles_near(contour, model.radius, model.nx, model.ny, model.side)


def with_ice(model: SceneModel, data: SceneData, tiles: np.ndarray) -> np.ndarray:
    """The tiles (flat indices) that hold ice: open-water tiles (thickness 0) are never placed."""
    return tiles[model.class_thickness[data.tile_class[tiles]] > 0.0]


def retiled_records(tiles: np.ndarray, classes: np.ndarray) -> np.ndarray:
    """The published records (``RETILED``) of tiles (flat indices) and their classes."""
    out = np.zeros(len(tiles), dtype=RETILED)
    out["tile"], out["ice_class"] = tiles, classes
    return out


def tiles_to_prepare(model: SceneModel, data: SceneData, contour: np.ndarray) -> np.ndarray:
    """Unbreakable or frozen tiles with ice within R_T + ``prepare_ahead`` of the contour
    points (n, 2) m: those a switch may soon need."""
    if model.settings.prepare_ahead <= 0.0:
        return np.zeros(0, dtype=np.int64)
    near = with_ice(model, data, tiles_near(contour, model.radius + model.settings.prepare_ahead, model.nx, model.ny,
                                      model.side))
    return near[data.tile_state[near] != TileState.BREAKABLE]


def update_scene(model: SceneModel, data: SceneData, contour: np.ndarray, origin: np.ndarray) -> SceneUpdate:
    """Decide and record this step's swaps: detected unbreakable tiles with ice are placed,
    detected frozen tiles thawed, and (with reverse replacement) breakable tiles whose centre lies
    farther than the reverse distance from every hull's reference point are frozen. contour:
    every hull's waterline points (n, 2), m; origin: their reference points ((2,) or (h, 2))."""
    wanted = with_ice(model, data, detected_tiles(model, contour, origin))
    state = data.tile_state[wanted]
    place, thaw = wanted[state == TileState.UNBREAKABLE], wanted[state == TileState.FROZEN]
    live = data.live
    if model.settings.reverse_replacement and len(live):
        offsets = model.centre(live)[:, None, :] - np.reshape(origin, (1, -1, 2))  # (tiles, hulls, 2)
        freeze = live[np.all(np.hypot(offsets[..., 0], offsets[..., 1]) > model.settings.reverse_distance, axis=1)]
    else:
        freeze = live[:0]
    data.tile_state[place] = TileState.BREAKABLE
    data.tile_state[thaw] = TileState.BREAKABLE
    data.tile_state[freeze] = TileState.FROZEN
    if len(place) or len(thaw) or len(freeze):
        data.live = np.setdiff1d(np.concatenate([live, place, thaw]), freeze)
    return SceneUpdate(place, thaw, freeze)


def tile_layout(model: SceneModel, tile: int, tile_class: int) -> tuple[int, int]:
    """(template index, quarter turns) for a tile of this class: for a class repeating in a
    square of n x n tiles, the window of the square at the tile's place in it (column % n,
    row % n), unturned, so neighbours continue each other's floes; else a variant of the
    class and a rotation, both from a hash of the tile index (SplitMix64's finaliser)."""
    repeat = model.class_repeat[tile_class] if model.class_repeat else 0
    if repeat:
        column, row = int(tile) % model.nx, int(tile) // model.nx
        return int(model.class_templates[tile_class][(row % repeat) * repeat + column % repeat]), 0
    z = (int(tile) + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
    z ^= z >> 31
    variants = model.class_templates[tile_class]
    return int(variants[z % len(variants)]), int((z >> 8) % 4)


def tile_corner(model: SceneModel, tile: int) -> tuple[float, float]:
    """South-west corner of a tile, world m."""
    return (tile % model.nx) * model.side, (tile // model.nx) * model.side
