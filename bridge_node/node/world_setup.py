"""Build the simulated world of a configured exercise: ship, tile templates, scene.

Templates come from the template library (built and stored on first use, with progress
shown by the caller's ``rich`` progress bar when one is given).
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
from rich.progress import Progress
from shapely.geometry import Polygon

from bridge_node.charts.field_regions import configured_ridges
from bridge_node.library.templates import library_template
from bridge_node.node.config import DEFAULT_CONFIG, ConfigError, NodeConfig, load_ship, resolve_path
from bridge_node.node.floe_field_setup import MAX_CLASSES, FieldRegions, field_regions, lay_floe_fields
from bridge_node.common.errors import UserError
from bridge_node.common.paths import writable_dir
from sim_core.environment import Environment
from sim_core.frames.units import KNOT
from sim_core.ice.model import compile_ice_model
from sim_core.fracture.fragment_count import MAX_THICKNESS
from sim_core.regimes.regime import region_tile_thickness
from sim_core.regimes.rubble import compile_rubble
from sim_core.scene.field import tile_classes
from sim_core.scene.scene import compile_scene, level_ice_name, open_water
from sim_core.ship.model import compile_ship
from sim_core.ship_in_ice import start_drifting
from sim_core.fleet import ShipStart
from sim_core.world import WorldData, WorldModel, compile_world, new_world_data, step


def field_tile_classes(cfg: NodeConfig, config_path: str | None,
                       laid: FieldRegions | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Thickness class of every tile of the configured field, and the class thicknesses (m;
    0 for open water). Where the config's chart or regions (``laid``, else read now) lay
    level ice or open water over a tile's centre, they set its thickness; elsewhere the
    field's thickness profile does."""
    laid = laid or field_regions(cfg)
    regions = None if laid.index is None else region_tile_thickness(laid.regions, laid.index, MAX_THICKNESS)
    grid = None
    if cfg.ice_field.thickness_profile == "grid":
        grid_path = resolve_path(config_path, cfg.ice_field.thickness_grid)
        try:
            grid = np.loadtxt(grid_path, delimiter=",", ndmin=2)
        except (OSError, ValueError) as exc:
            raise UserError(f"{config_path}: ice_field.thickness_grid = {str(grid_path)!r}: {exc}") from None
    try:
        return tile_classes(cfg.ice_field, cfg.fracture.tile_side, grid, regions)
    except ValueError as exc:
        raise UserError(f"{config_path}: ice_field: {exc}") from None


def build_world(cfg: NodeConfig, config_path: str | None, progress: Progress | None = None,
                fleet: bool = True) -> WorldModel:
    """Compile the configured exercise's world: its ship, and with ``fleet`` the other own
    ships of ``[[ships]]``. Dynamics need prism cells."""
    if cfg.fracture.cells != "prism":
        raise UserError(f"{config_path}: fracture.cells = {cfg.fracture.cells!r}: the simulated world needs "
                        "'prism' cells (voronoi3d cells overlap in plan view)")
    ship = compile_ship(load_ship(cfg.ship.name, config_path), cfg.ice_material)
    laid = field_regions(cfg)
    tile_class, level_h = field_tile_classes(cfg, config_path, laid)
    cache = writable_dir(resolve_path(config_path, cfg.paths.cache_dir), f"{config_path or 'default config'}: "
                         "paths.cache_dir")
    packs = lay_floe_fields(cfg, config_path, laid, tile_class, level_h, ship.particulars.beam, cache)
    jobs = [(h, v) for h in level_h[level_h > 0.0] for v in range(cfg.fracture.variants)]  # none for open water
    task = progress.add_task("loading tile templates", total=len(jobs)) if progress else None
    templates = []
    for h, v in jobs:
        templates.append(library_template(Path(cache), float(h), v, cfg.fracture, cfg.ice_material)[0])
        if progress:
            progress.advance(task)
    first = np.cumsum(level_h > 0.0) - 1  # the first template of each class with ice
    per_class = [np.arange(first[k] * cfg.fracture.variants, (first[k] + 1) * cfg.fracture.variants) if h > 0.0
                 else np.zeros(0, dtype=np.int64) for k, h in enumerate(level_h)]
    for variants in packs.templates:  # a floe-field region's class: its own templates
        per_class.append(np.arange(len(templates), len(templates) + len(variants)))
        templates += variants
    class_h, names = packs.class_h, [level_ice_name(h) for h in level_h] + packs.names
    repeat = [0] * len(level_h) + packs.repeat
    if not np.any(class_h <= 0.0) and len(class_h) < MAX_CLASSES:  # for the instructor to lay; no templates
        class_h, names, repeat = np.append(class_h, 0.0), names + [level_ice_name(0.0)], repeat + [0]
        per_class.append(np.zeros(0, dtype=np.int64))
    ice = compile_ice_model(templates, cfg.ice_material, cfg.ice_dynamics)
    try:
        scene = compile_scene(cfg.scene, packs.tile_class, class_h, per_class, cfg.fracture.tile_side,
                              ship.particulars.length, names, repeat)
    except ValueError as exc:
        raise UserError(f"{config_path}: scene: {exc}") from None
    origin = math.radians(cfg.exercise.origin_latitude_deg), math.radians(cfg.exercise.origin_longitude_deg)
    ridges = configured_ridges(cfg.ice_field, cfg.exercise.origin_deg())
    rubble = compile_rubble(laid.regions, laid.index, ridges, scene.nx, scene.ny, scene.side)
    others = tuple(compile_ship(load_ship(s.name, config_path, f"ships.{i}.name"), cfg.ice_material)
                   for i, s in enumerate(cfg.ships)) if fleet else ()
    return compile_world(ship, ice, scene, origin, tuple(light.mount() for light in cfg.render.searchlights), rubble,
                         others)


def warm_up(model: WorldModel, cfg: NodeConfig) -> None:
    """Compile the numba kernels (or load them from numba's cache) before a real-time run,
    by stepping a throwaway copy of the exercise with its bow in the ice for a few ticks;
    otherwise the first ice contact would stall the loop for seconds."""
    data = start_world(model, cfg)
    data.ship.eta[0] = 0.0  # the stem 75 m into the ice: tiles placed, cells broken, floes floating
    for _ in range(3):
        step(model, data, 1.0 / 30.0)


def start_position(model: WorldModel, cfg: NodeConfig) -> tuple[float, float]:
    """The configured start (north, east), m from the field's corner: by default one ship
    length south of the ice edge, on the centre line of the middle tile column."""
    ex, scene = cfg.exercise, model.scene
    north = ex.start_north if ex.start_north is not None else -model.ship.particulars.length
    east = ex.start_east if ex.start_east is not None else (scene.nx // 2 + 0.5) * scene.side
    return north, east


def open_water_world(cfg: NodeConfig, config_path: str | None) -> tuple[WorldModel, WorldData]:
    """The configured exercise without its ice field, the ship at rest at the exercise's
    origin, engine stopped, the exercise's clock and environment at the start: a console
    commissioned in open water (``icebridge links monitor``)."""
    model = build_world(cfg, config_path, fleet=False)
    model = dataclasses.replace(model, scene=open_water(model.scene))
    data = new_world_data(model, 0.0, 0.0, 0.0, 0.0)
    start_exercise(model, data, cfg)
    return model, data


def start_exercise(model: WorldModel, data: WorldData, cfg: NodeConfig) -> None:
    """Set the exercise clock (time 0 at ``render.start_utc``) and the environment at the
    start (``render.visibility_m``; the wind and current of ``[exercise]``), and a field
    that drifts as a whole drifting steadily in them."""
    ex = cfg.exercise
    data.epoch = cfg.render.start_utc.timestamp()
    data.environment = Environment(
        visibility=cfg.render.visibility_m, wind_speed=ex.wind_speed_kn * KNOT,
        wind_from=math.radians(ex.wind_from_deg), current_speed=ex.current_speed_kn * KNOT,
        current_to=math.radians(ex.current_to_deg))
    start_drifting(model, data)


def start_world(model: WorldModel, cfg: NodeConfig, config_path: str | None = None) -> WorldData:
    """World data at the configured start (``start_position``), heading, speed and
    telegraph order, the model's other ships at theirs (``[[ships]]``), with the exercise's
    clock and environment at the start (``start_exercise``). ConfigError where two ships'
    hulls would overlap at the start."""
    ex = cfg.exercise
    others = tuple(ShipStart(s.start_north, s.start_east, math.radians(s.start_heading_deg), s.start_speed_kn * KNOT,
                             s.start_telegraph) for s in cfg.ships[:len(model.ships) - 1])
    data = new_world_data(model, *start_position(model, cfg), math.radians(ex.start_heading_deg),
                          ex.start_speed_kn * KNOT, ex.start_telegraph, others)
    _check_apart(model, data, config_path)
    start_exercise(model, data, cfg)
    return data


def _check_apart(model: WorldModel, data: WorldData, config_path: str | None) -> None:
    """ConfigError naming both ships' keys where two hulls overlap at the start."""
    hulls = []
    for contour, ship in zip(model.contours, data.ships):
        c, s = math.cos(ship.eta[5]), math.sin(ship.eta[5])
        north = ship.eta[0] + contour[:, 0] * c - contour[:, 1] * s
        east = ship.eta[1] + contour[:, 0] * s + contour[:, 1] * c
        hulls.append(Polygon(np.column_stack([east, north])))
    keys = ["exercise.start_north/start_east"] + [f"ships.{i}.start_north/start_east" for i in range(len(hulls) - 1)]
    for j, hull in enumerate(hulls):
        for k in range(j):
            if hull.intersects(hulls[k]):
                at = f"north {data.ships[j].eta[0]:.0f} m, east {data.ships[j].eta[1]:.0f} m"
                raise ConfigError(f"{config_path or DEFAULT_CONFIG}: {keys[j]} = {at}: this ship's hull overlaps the "
                                  f"one that starts at {keys[k]}; start the ships apart")
