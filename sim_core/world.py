"""The world step: controls -> ship -> scene swaps -> contact and breaking -> floating floes.

``WorldModel`` holds everything static (the compiled ship, the compiled ice templates, the
scene's tile grid); ``WorldData`` everything that changes per step. ``step(model, data,
dt, controls)`` advances it all by dt seconds and returns a ``WorldEvents`` report that
renderers and outputs consume. No I/O, no GL.

Frames: the ship model works in north/east with the heading clockwise from north; the ice
world in x east, y north with angles counter-clockwise from east; the field's south-west
corner is the origin of both. The ice's contact load on the hull (from the last ice step)
enters the ship as its external load, and the ship's Lindqvist resistance is set from
where the bow is: level ice while the hull is breaking cells, a broken channel in
breakable or frozen tiles, open water off the field.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim_core import ship_model
from sim_core.hull_contour import ship_to_world, waterline_contour, world_heading
from sim_core.ice_dynamics import HullMotion, IceData, freeze_tile, ice_step, new_ice_data, place_tile, thaw_tile
from sim_core.ice_model import IceModel
from sim_core.ice_resistance import BROKEN_CHANNEL, LEVEL_ICE, OPEN_WATER
from sim_core.ice_scene import (BREAKABLE, FROZEN, SceneData, SceneModel, SceneUpdate, new_scene_data, tile_corner,
                                tile_layout, update_scene)
from sim_core.ship_model import ShipData, ShipModel
from sim_core.tile_quadtree import tile_under

BREAKING_MEMORY = 2.0  # s: the bow counts as in level ice this long after it last broke a cell


@dataclass(frozen=True)
class WorldModel:
    """Static half of the world."""

    ship: ShipModel
    ice: IceModel
    scene: SceneModel
    contour: np.ndarray  # (34, 2) hull waterline contour, ship frame (x forward, y starboard), m


@dataclass
class WorldData:
    """Dynamic half of the world."""

    ship: ShipData
    ice: IceData
    scene: SceneData
    time: float = 0.0
    last_hull_break: float = -math.inf  # s


@dataclass
class Controls:
    """Console orders for one step; None leaves an order as it was. Rudder in rad (+ to
    starboard); engine by telegraph position name or lever percent (-100..100)."""

    rudder: float | None = None
    telegraph: str | None = None
    lever: float | None = None


@dataclass
class WorldEvents:
    """What one world step did: tiles swapped (flat indices), cells broken (floe rows), and
    the ice load on the hull in the ship frame (X, Y in N; N in N m, + to starboard)."""

    tiles_placed: np.ndarray
    tiles_thawed: np.ndarray
    tiles_frozen: np.ndarray
    broken_by_hull: np.ndarray
    broken_by_contact: np.ndarray
    ice_load: np.ndarray
    rejected: list[str]  # reasons for orders that were clamped or refused


def compile_world(ship: ShipModel, ice: IceModel, scene: SceneModel) -> WorldModel:
    p = ship.particulars
    return WorldModel(ship, ice, scene, waterline_contour(p.length, p.beam))


def new_world_data(model: WorldModel, north: float, east: float, heading: float, speed: float,
                   telegraph: str | None = None) -> WorldData:
    """The ship at (north, east) m from the field's south-west corner, heading rad
    (clockwise from north), steaming at speed m/s; optionally with a telegraph order."""
    ship = ship_model.new_ship_data(model.ship, speed, heading=heading)
    ship.eta[0], ship.eta[1] = north, east
    if telegraph is not None:
        reason = ship_model.order_telegraph(model.ship, ship, telegraph)
        if reason:
            raise ValueError(reason)
    ice = new_ice_data(model.ice, model.contour, model.ship.ice.hull_friction)
    return WorldData(ship, ice, new_scene_data(model.scene))


def apply_controls(ship: ShipModel, data: ShipData, controls: Controls) -> list[str]:
    """Give the orders to the ship; returns the reasons of clamped or refused orders."""
    out = []
    if controls.rudder is not None:
        out.append(ship_model.order_rudder(ship, data, controls.rudder))
    if controls.telegraph is not None:
        out.append(ship_model.order_telegraph(ship, data, controls.telegraph))
    if controls.lever is not None:
        out.append(ship_model.order_lever(ship, data, controls.lever))
    return [r for r in out if r]


def hull_world(model: WorldModel, ship: ShipData) -> tuple[np.ndarray, HullMotion]:
    """The hull's contour points (34, 2) and motion in the ice world."""
    north, east, psi = ship.eta[0], ship.eta[1], ship.eta[5]
    u, v, r = ship.nu[0], ship.nu[1], ship.nu[5]
    s, c = math.sin(psi), math.cos(psi)
    velocity = np.array([u * s + v * c, u * c - v * s])
    return (ship_to_world(model.contour, north, east, psi),
            HullMotion(np.array([east, north]), world_heading(psi), velocity, -r))


def apply_swaps(model: WorldModel, data: WorldData, update: SceneUpdate) -> None:
    """Carry out a scene update in the ice world: place, thaw and freeze tiles."""
    scene, placement = model.scene, data.scene.placement
    for tile in update.place:
        template, turns = tile_layout(scene, tile)
        placement[int(tile)] = len(data.ice.tiles.template)
        place_tile(model.ice, data.ice, template, tile_corner(scene, tile), turns)
    for tile in update.thaw:
        thaw_tile(data.ice, placement[int(tile)])
    for tile in update.freeze:
        freeze_tile(data.ice, placement[int(tile)])


def _ice_condition(model: WorldModel, data: WorldData, bow: np.ndarray) -> tuple[float, int]:
    scene = model.scene
    tile = tile_under(bow, scene.nx, scene.ny, scene.side)
    if tile < 0:
        return 0.0, OPEN_WATER
    h = scene.thickness_at(bow)
    breaking = data.time - data.last_hull_break < BREAKING_MEMORY
    if breaking or data.scene.tile_state[tile] not in (BREAKABLE, FROZEN):
        return h, LEVEL_ICE
    return h, BROKEN_CHANNEL


def step(model: WorldModel, data: WorldData, dt: float, controls: Controls | None = None) -> WorldEvents:
    """Advance the world by dt seconds."""
    rejected = apply_controls(model.ship, data.ship, controls) if controls is not None else []
    ship = data.ship
    contour, _ = hull_world(model, ship)
    ship.ice_h, ship.ice_condition = _ice_condition(model, data, contour[0])  # contour[0] is the stem
    ship_model.step(model.ship, ship, dt)
    contour, hull = hull_world(model, ship)
    update = update_scene(model.scene, data.scene, contour, hull.xy)
    apply_swaps(model, data, update)
    report = ice_step(model.ice, data.ice, hull, dt)
    psi = ship.eta[5]
    fx, fy = report.hull_force
    load = np.array([fx * math.sin(psi) + fy * math.cos(psi), fx * math.cos(psi) - fy * math.sin(psi),
                     -report.hull_moment])
    ship.external[:] = load
    data.time += dt
    if len(report.broken_by_hull):
        data.last_hull_break = data.time
    return WorldEvents(update.place, update.thaw, update.freeze, report.broken_by_hull,
                       report.broken_by_contact, load, rejected)
