"""The world step: controls -> ship -> scene swaps -> contact and breaking -> floating floes.

``WorldModel`` holds everything static (the compiled ship, the compiled ice templates, the
scene's tile grid, the exercise origin); ``WorldData`` everything that changes per step,
with the one clock, ``WorldData.time``. ``step(model, data, dt, controls)`` advances it all
by dt seconds and returns the ``WorldEvents`` it publishes: the one thing outputs,
renderers and recorders read. ``snapshot(model, data)`` publishes the whole current state
in the same form, for a consumer that joins late. No I/O, no GL.

Frames (see ``sim_core.frames``): the ship model works in north/east with the heading
clockwise from north; the ice world in x east, y north with angles counter-clockwise from
east. The ice's contact load on the hull (from the last ice step) enters the ship as its
external load, and the ship's Lindqvist resistance is set from where the bow is: level ice
while the hull is breaking cells, a broken channel in breakable or frozen tiles, open water
off the field.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from sim_core.frames.hull_contour import waterline_contour
from sim_core.frames.ship_frame import ship_to_world, ship_vector_to_world, world_heading, world_vector_to_ship
from sim_core.ice.floes import BreakCause, FloeStatus, TilePlacement
from sim_core.ice.model import IceModel
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.step import warm_up as warm_up_ice
from sim_core.ice.tiles import (
    IceData,
    PreparedTile,
    advance,
    discard_prepared,
    freeze_tile,
    new_ice_data,
    place_tile,
    prepare_place,
    prepare_thaw,
    reclaim_rows,
    thaw_tile,
)
from sim_core.scene.quadtree import tile_under, tiles_near
from sim_core.scene.scene import (
    SceneData,
    SceneModel,
    SceneUpdate,
    TileState,
    new_scene_data,
    tile_corner,
    tile_layout,
    tiles_to_prepare,
    update_scene,
)
from sim_core.ship import model as ship_model
from sim_core.ship.model import OrderRejection, ShipData, ShipModel
from sim_core.ship.outputs import ShipOutputs, ship_outputs
from sim_core.ship.resistance import BROKEN_CHANNEL, LEVEL_ICE, OPEN_WATER
from sim_core.ship.searchlights import SearchlightMount, SearchlightOrder, SearchlightState, order_searchlight

BREAKING_MEMORY = 2.0  # s: the bow counts as in level ice this long after it last broke a cell
_PREPARE_CHUNK = 64  # cells built between looks at the clock while preparing tiles ahead
_NO_ROWS = np.zeros(0, dtype=np.int64)
# A frozen tile's broken cell as published: placement, offset in the tile, what broke it
# (BreakCause), and its pose (x, y, heave, yaw, roll, pitch; world m and rad) in float32,
# as floe poses travel on the stream. 33 bytes.
FROZEN_FLOE_EVENT = np.dtype([("placement", np.int32), ("cell", np.uint32), ("cause", np.uint8),
                              ("pose", np.float32, 6)])
_NO_FROZEN_FLOES = np.zeros(0, dtype=FROZEN_FLOE_EVENT)
_NO_FROZEN_FLOES.flags.writeable = False  # shared by the events of every step that freezes nothing


@dataclass(frozen=True)
class WorldModel:
    """Static half of the world."""

    ship: ShipModel
    ice: IceModel
    scene: SceneModel
    contour: np.ndarray  # (34, 2) hull waterline contour, ship frame (x forward, y starboard), m
    origin: tuple[float, float]  # latitude, longitude of the field's south-west corner, rad
    searchlights: tuple[SearchlightMount, ...] = ()  # the own ship's, by index


@dataclass
class WorldData:
    """Dynamic half of the world; ``time`` is its one clock."""

    ship: ShipData
    ice: IceData
    scene: SceneData
    time: float = 0.0  # s
    epoch: float = 0.0  # UTC of time 0, unix s: the exercise clock the outputs carry (the node sets it)
    seq: int = 0  # steps taken
    last_hull_break: float = -math.inf  # s
    live_rows: np.ndarray = field(default_factory=lambda: _NO_ROWS)  # rows of the breakable tiles
    ahead: dict[int, PreparedTile] = field(default_factory=dict)  # field tile -> prepared for its switch
    late_switches: int = 0  # tiles switched in before their preparation was done
    searchlights: list[SearchlightState] = field(default_factory=list)  # as commanded, one per mount


@dataclass(frozen=True)
class KinematicPose:
    """Where a logged track puts the ship at the end of a step, instead of its manoeuvring
    model (replay): north, east m from the field's corner, heading rad clockwise from north,
    surge and sway m/s, yaw rate rad/s (+ to starboard)."""

    north: float
    east: float
    heading: float
    surge: float
    sway: float = 0.0
    yaw_rate: float = 0.0


@dataclass
class Controls:
    """Console orders for one step; None leaves an order as it was. Rudder in rad (+ to
    starboard); engine by telegraph position name or lever percent (-100..100). With
    ``kinematic`` set the ship follows that pose instead of its model; the hull then breaks
    the ice along it as a driven ship does. ``searchlights``: orders, applied in turn."""

    rudder: float | None = None
    telegraph: str | None = None
    lever: float | None = None
    kinematic: KinematicPose | None = None
    searchlights: tuple[SearchlightOrder, ...] = ()


@dataclass(frozen=True)
class PlacedTiles:
    """Tiles laid in the ice world, one entry each: flat index in the field, placement index
    in the ice world, template, quarter turns (CCW), south-west corner (m), first floe row
    and row count (rows of one tile are contiguous; a frozen tile has none)."""

    tile: np.ndarray
    placement: np.ndarray
    template: np.ndarray
    quarter_turns: np.ndarray
    corner: np.ndarray  # (k, 2)
    row_start: np.ndarray
    row_count: np.ndarray


@dataclass(frozen=True)
class WorldEvents:
    """What the world publishes after a step (or, with ``snapshot`` set, the whole state).

    A live tile's floe rows keep their numbers (``sim_core.ice.floes``), so consumers can
    keep live floes by row. A tile ``placed`` is given rows, as is a tile thawed (listed in
    both ``placed``, with its new rows, and ``thawed``). A tile ``frozen`` gives its rows up
    (a later placement may be given them), and its broken cells travel as
    ``frozen_floes`` (``FROZEN_FLOE_EVENT`` records): all others of its cells are intact.
    ``floe_rows`` are the rows whose pose or status may have changed: the free floes of the
    live tiles, and every row of a tile placed or thawed in this step; in a snapshot, every
    row of the live tiles, with ``frozen`` and ``frozen_floes`` naming every frozen tile and
    its floes. Poses are (x, y, heave, yaw, roll, pitch) in world m and rad.
    """

    seq: int
    time: float  # s, simulated
    ship: ShipOutputs
    placed: PlacedTiles
    thawed: np.ndarray  # placement indices thawed this step
    frozen: np.ndarray  # placement indices frozen this step (snapshot: every frozen placement)
    broken_by_hull: np.ndarray  # rows
    broken_by_contact: np.ndarray  # rows
    floe_rows: np.ndarray  # (m,)
    floe_pose: np.ndarray  # (m, 6)
    floe_status: np.ndarray  # (m,) FloeStatus
    floes_free: int
    floes_frozen: int
    ice_load: np.ndarray  # X, Y N (ship frame); N N m (+ to starboard)
    rejected: tuple[OrderRejection, ...]
    frozen_floes: np.ndarray = field(default_factory=lambda: _NO_FROZEN_FLOES)
    snapshot: bool = False


def compile_world(ship: ShipModel, ice: IceModel, scene: SceneModel, origin: tuple[float, float] = (0.0, 0.0),
                  searchlights: tuple[SearchlightMount, ...] = ()) -> WorldModel:
    """The static world; origin: latitude and longitude (rad) of the field's corner."""
    p = ship.particulars
    return WorldModel(ship, ice, scene, waterline_contour(p.length, p.beam), origin, searchlights)


def new_world_data(model: WorldModel, north: float, east: float, heading: float, speed: float,
                   telegraph: str | None = None) -> WorldData:
    """The ship at (north, east) m from the field's south-west corner, heading rad
    (clockwise from north), steaming at speed m/s; optionally with a telegraph order."""
    ship = ship_model.new_ship_data(model.ship, speed, heading=heading)
    ship.eta[0], ship.eta[1] = north, east
    if telegraph is not None:
        refused = ship_model.order_telegraph(model.ship, ship, telegraph)
        if refused:
            raise ValueError(refused.text)
    ice = new_ice_data(model.ice, model.contour, model.ship.material.hull_friction)
    data = WorldData(ship, ice, new_scene_data(model.scene), searchlights=[m.default for m in model.searchlights])
    warm_up(model, data)
    return data


def warm_up(model: WorldModel, data: WorldData) -> None:
    """Do before the first step what it would otherwise do lazily: load the compiled
    kernels, and build the tiles around the start position (and the ring beyond) in full,
    so that the first step only switches them in."""
    warm_up_ice(model.ice, data.ice)
    contour, _ = hull_world(model, data.ship)
    start = tiles_near(contour, model.scene.radius, model.scene.nx, model.scene.ny, model.scene.side)
    for tile in start.tolist():
        data.ahead[tile] = _prepare(model, data, tile)
    prepare_ahead(model, data, contour, budget_s=math.inf)
    for prepared in data.ahead.values():
        while not prepared.done:
            advance(data.ice, prepared, 1 << 30)


def apply_controls(ship: ShipModel, data: ShipData, controls: Controls) -> list[OrderRejection]:
    """Give the orders to the ship; returns the orders it clamped or refused."""
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
    velocity = np.array(ship_vector_to_world((ship.nu[0], ship.nu[1]), psi))
    return (ship_to_world(model.contour, north, east, psi),
            HullMotion(np.array([east, north]), world_heading(psi), velocity, -ship.nu[5]))


def _tile_rows(tiles: TilePlacement, placements: list[int]) -> np.ndarray:
    """Rows of the given placements, concatenated."""
    if not placements:
        return _NO_ROWS
    return np.concatenate([tiles.rows(k) for k in placements])


def _placed_tiles(tiles: TilePlacement, field_tiles: list[int], placements: list[int]) -> PlacedTiles:
    """The published record of placements (their field tiles given alongside)."""
    return PlacedTiles(
        np.array(field_tiles, dtype=np.int64), np.array(placements, dtype=np.int64),
        np.array([tiles.template[k] for k in placements], dtype=np.int64),
        np.array([tiles.quarter_turns[k] for k in placements], dtype=np.int64),
        np.array([tiles.corner[k] for k in placements], dtype=float).reshape(-1, 2),
        np.array([tiles.row_start[k] for k in placements], dtype=np.int64),
        np.array([tiles.row_count[k] for k in placements], dtype=np.int64))


def apply_swaps(model: WorldModel, data: WorldData, update: SceneUpdate) -> tuple[PlacedTiles, np.ndarray, np.ndarray]:
    """Carry out a scene update in the ice world: place, thaw and freeze tiles. Returns the
    tiles given rows (placed, and thawed with their new rows) and the placement indices
    thawed and frozen."""
    scene, placement = model.scene, data.scene.placement
    reclaim_rows(data.ice)
    new = []
    for tile in update.place.tolist():
        template, turns = tile_layout(scene, tile)
        placement[tile] = place_tile(model.ice, data.ice, template, tile_corner(scene, tile), turns,
                                     _take_prepared(model, data, tile))
        new.append(placement[tile])
    thawed = [placement[tile] for tile in update.thaw.tolist()]
    frozen = [placement[tile] for tile in update.freeze.tolist()]
    for tile, k in zip(update.thaw.tolist(), thawed):
        thaw_tile(model.ice, data.ice, k, _take_prepared(model, data, tile))
    for k in frozen:
        freeze_tile(data.ice, k)
    if new or thawed or frozen:
        data.live_rows = _tile_rows(data.ice.tiles, [placement[t] for t in data.scene.live.tolist()])
    return (_placed_tiles(data.ice.tiles, update.place.tolist() + update.thaw.tolist(), new + thawed),
            np.array(thawed, dtype=np.int64), np.array(frozen, dtype=np.int64))


def _prepare(model: WorldModel, data: WorldData, tile: int) -> PreparedTile:
    """Start preparing a field tile's switch: a new placement, or the thaw of its frozen one."""
    if data.scene.tile_state[tile] == TileState.FROZEN:
        return prepare_thaw(model.ice, data.ice, data.scene.placement[tile])
    template, turns = tile_layout(model.scene, tile)
    return prepare_place(model.ice, template, tile_corner(model.scene, tile), turns)


def _take_prepared(model: WorldModel, data: WorldData, tile: int) -> PreparedTile | None:
    """The tile's preparation for its switch now, counting a switch that finds it unfinished."""
    prepared = data.ahead.pop(tile, None)
    if model.scene.settings.prepare_ahead > 0.0 and (prepared is None or not prepared.done):
        data.late_switches += 1
    return prepared


def prepare_ahead(model: WorldModel, data: WorldData, contour: np.ndarray, budget_s: float) -> None:
    """Build, nearest first and for at most budget_s seconds of wall time, the engine
    objects of the tiles that the hull (contour points (n, 2), m) will soon switch in, and
    drop preparations the hull has left well behind. Touches no physics."""
    scene = model.scene
    wanted = tiles_to_prepare(scene, data.scene, contour)
    if len(data.ahead) > len(wanted):
        keep = set(tiles_near(contour, scene.radius + 2.0 * scene.settings.prepare_ahead,
                              scene.nx, scene.ny, scene.side).tolist())
        for tile in [t for t in data.ahead if t not in keep]:
            discard_prepared(data.ice, data.ahead.pop(tile))
    if not len(wanted):
        return
    order = wanted[np.argsort(np.hypot(*(scene.centre(wanted) - contour.mean(axis=0)).T), kind="stable")]
    deadline = time.perf_counter() + budget_s
    for tile in order.tolist():
        if tile not in data.ahead:
            data.ahead[tile] = _prepare(model, data, tile)
        prepared = data.ahead[tile]
        while not prepared.done and time.perf_counter() < deadline:
            advance(data.ice, prepared, _PREPARE_CHUNK)
        if time.perf_counter() >= deadline:
            return


def _moved_rows(data: WorldData, placed: PlacedTiles) -> np.ndarray:
    """Rows whose pose or status may have changed in a step: the free floes of the live
    tiles (broken cells included), and every row of the tiles placed or thawed in it.
    Intact cells of live tiles do not move, and frozen tiles have no rows."""
    st = data.ice.state
    live = data.live_rows
    moving = live[st.status[live] == FloeStatus.FREE]
    return np.union1d(moving, _tile_rows(data.ice.tiles, placed.placement.tolist())) if len(placed.placement) \
        else moving


def _frozen_floes(ice: IceData, placements: list[int]) -> np.ndarray:
    """The published records (``FROZEN_FLOE_EVENT``) of frozen placements' floes."""
    if not placements:  # most steps freeze nothing
        return _NO_FROZEN_FLOES
    records = [ice.frozen[k] for k in placements]
    out = np.zeros(sum(len(r) for r in records), dtype=FROZEN_FLOE_EVENT)
    out["placement"] = np.repeat(placements, [len(r) for r in records])
    if len(out):
        floes = np.concatenate(records)
        out["cell"], out["cause"] = floes["cell"], floes["cause"]
        out["pose"] = np.column_stack([floes["xy"], floes["heave"], floes["yaw"], floes["roll"], floes["pitch"]])
    return out


def _ice_condition(model: WorldModel, data: WorldData, bow: np.ndarray) -> tuple[float, int]:
    scene = model.scene
    tile = tile_under(bow, scene.nx, scene.ny, scene.side)
    if tile < 0:
        return 0.0, OPEN_WATER
    h = scene.thickness_at(bow)
    breaking = data.time - data.last_hull_break < BREAKING_MEMORY
    if breaking or data.scene.tile_state[tile] not in (TileState.BREAKABLE, TileState.FROZEN):
        return h, LEVEL_ICE
    return h, BROKEN_CHANNEL


def _publish(model: WorldModel, data: WorldData, rows: np.ndarray, **fields) -> WorldEvents:
    """Events with the ship's outputs, the given rows' poses and statuses, and counts."""
    st = data.ice.state
    pose = np.column_stack([st.xy[rows], st.heave[rows], st.yaw[rows], st.roll[rows], st.pitch[rows]])
    ship = ship_outputs(data.ship, data.time, *model.origin, data.epoch + data.time, tuple(data.searchlights))
    return WorldEvents(seq=data.seq, time=data.time, ship=ship,
                       floe_rows=rows, floe_pose=pose, floe_status=st.status[rows].copy(),
                       floes_free=st.count(FloeStatus.FREE), floes_frozen=data.ice.frozen.count, **fields)


def step(model: WorldModel, data: WorldData, dt: float, controls: Controls | None = None) -> WorldEvents:
    """Advance the world by dt seconds; returns what it publishes."""
    rejected = apply_controls(model.ship, data.ship, controls) if controls is not None else []
    for order in controls.searchlights if controls is not None else ():
        if refused := order_searchlight(model.searchlights, data.searchlights, order):
            rejected.append(refused)
    ship = data.ship
    contour, _ = hull_world(model, ship)
    ship.ice_h, ship.ice_condition = _ice_condition(model, data, contour[0])  # contour[0] is the stem
    if controls is not None and controls.kinematic is not None:
        k = controls.kinematic
        ship.eta[0], ship.eta[1], ship.eta[5] = k.north, k.east, k.heading
        ship.nu[0], ship.nu[1], ship.nu[5] = k.surge, k.sway, k.yaw_rate
    else:
        ship_model.step(model.ship, ship, dt)
    contour, hull = hull_world(model, ship)
    placed, thawed, frozen = apply_swaps(model, data, update_scene(model.scene, data.scene, contour, hull.xy))
    report = ice_step(model.ice, data.ice, hull, dt)
    prepare_ahead(model, data, contour, model.scene.settings.prepare_budget_ms * 1e-3)
    load = np.array([*world_vector_to_ship(report.hull_force, ship.eta[5]), -report.hull_moment])
    ship.external[:] = load
    data.time += dt
    data.seq += 1
    if len(report.broken_by_hull):
        data.last_hull_break = data.time
    rows = _moved_rows(data, placed)
    return _publish(model, data, rows, placed=placed, thawed=thawed, frozen=frozen,
                    frozen_floes=_frozen_floes(data.ice, frozen.tolist()), broken_by_hull=report.broken_by_hull, broken_by_contact=report.broken_by_contact,
                    ice_load=load, rejected=tuple(rejected))


def snapshot(model: WorldModel, data: WorldData) -> WorldEvents:
    """The whole published state now, as events with ``snapshot`` set: every placed tile,
    every row of the live tiles, every broken cell, the frozen placements and their floes."""
    tiles, st = data.ice.tiles, data.ice.state
    by_tile = sorted(data.scene.placement.items(), key=lambda kv: kv[1])
    frozen = [k for t, k in by_tile if data.scene.tile_state[t] == TileState.FROZEN]
    rows = data.live_rows
    broken = rows[st.status[rows] == FloeStatus.FREE]
    placed = _placed_tiles(tiles, [t for t, _ in by_tile], [k for _, k in by_tile])
    return _publish(model, data, rows, placed=placed,
                    thawed=_NO_ROWS, frozen=np.array(frozen, dtype=np.int64),
                    frozen_floes=_frozen_floes(data.ice, frozen),
                    broken_by_hull=broken[st.cause[broken] == BreakCause.HULL],
                    broken_by_contact=broken[st.cause[broken] == BreakCause.CONTACT],
                    ice_load=data.ship.external.copy(), rejected=(), snapshot=True)
