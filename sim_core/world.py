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
off the field; the brash and a ridge keel at the stem add theirs (``sim_core.regimes.rubble``).
The ship meets the ice world in the ice's own frame (``sim_core.ship_in_ice``), which
drifts where the whole field does. An exercise may hold several ships (``sim_core.fleet``):
each takes its own orders and breaks ice with its own hull in the one ice world, the scene
keeps the tiles near every hull breakable, and the ships after the first publish their
outputs as ``WorldEvents.others``. The instructor's environment (``sim_core.environment``)
lives in the data and is published with every step: the wind loads the ship
(``sim_core.ship.wind``) and drifts the ice, the current carries the ship and the ice, and
a frozen exercise takes its orders but moves nothing and stops its clock, while every tick
still publishes a step.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from sim_core.environment import Environment
from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice.floes import FROZEN_CRACK, BreakCause, FloeStatus
from sim_core.ice.model import IceModel
from sim_core.ice.bending import CRACK_EVENT, crack_events
from sim_core.ice.drift import IceFrame
from sim_core.ice.step import ice_step
from sim_core.instructor import Command, OtherVessel, Reposition, SetIce, apply_command, move_vessels
from sim_core.ice.step import warm_up as warm_up_ice
from sim_core.ice.tiles import IceData, PreparedTile, add_hull, advance, new_ice_data
from sim_core.scene.quadtree import tiles_near
from sim_core.scene.scene import (RETILED, SceneData, SceneModel, TileState, new_scene_data, retiled_records,
                                  update_scene, with_ice)
from sim_core.scene.switches import (
    NO_FROZEN_FLOES,
    NO_ROWS,
    PlacedTiles,
    apply_swaps,
    cracks_published,
    frozen_cracks_of,
    frozen_floes_of,
    moved_rows,
    placed_tiles,
    prepare_ahead,
    prepare_switch,
    warm_up_moved,
)
from sim_core.fleet import (Controls, KinematicPose, ShipReport, ShipStart, apply_controls, collisions, fleet_contour,
                             fleet_wash, hulls_in_ice, move_ship, new_ship, per_ship, take_ice_loads)
from sim_core.ship.collision import ShipContact
from sim_core.ship.model import OrderRejection, ShipData, ShipModel
from sim_core.ship.outputs import ShipOutputs, ship_outputs
from sim_core.regimes.rubble import RubbleModel, compile_rubble
from sim_core.ship.searchlights import SearchlightMount, SearchlightState, order_searchlight
from sim_core.ship.sensors import SensorFaults, sensor_readings
from sim_core.ship_in_ice import contour_in_ice, drift_ice

__all__ = ["Controls", "KinematicPose", "ShipStart", "WorldData", "WorldEvents", "WorldModel", "compile_world",
           "new_world_data", "snapshot", "step"]

NO_RETILED = np.zeros(0, dtype=RETILED)
NO_RETILED.flags.writeable = False  # shared by the events of every step that lays no ice


@dataclass(frozen=True)
class WorldModel:
    """Static half of the world."""

    ships: tuple[ShipModel, ...]  # the exercise's ships: the first is the node's own (``sim_core.fleet``)
    ice: IceModel
    scene: SceneModel
    contours: tuple[np.ndarray, ...]  # (34, 2) each ship's waterline contour, ship frame (x forward, y starboard), m
    origin: tuple[float, float]  # latitude, longitude of the field's south-west corner, rad
    searchlights: tuple[SearchlightMount, ...]  # the own ship's, by index
    rubble: RubbleModel  # brash and ridges, met through their resistance models

    @property
    def ship(self) -> ShipModel:
        """The node's own ship: the one its bridge's links serve."""
        return self.ships[0]

    @property
    def contour(self) -> np.ndarray:
        """The own ship's waterline contour (34, 2), ship frame, m."""
        return self.contours[0]


@dataclass
class WorldData:
    """Dynamic half of the world; ``time`` is its one clock."""

    ships: list[ShipData]  # by the model's ships
    ice: IceData
    scene: SceneData
    time: float = 0.0  # s
    epoch: float = 0.0  # UTC of time 0, unix s: the exercise clock the outputs carry (the node sets it)
    seq: int = 0  # steps taken
    hull_breaks: list[float] = field(default_factory=lambda: [-math.inf])  # s: when each ship's hull last broke a cell
    live_rows: np.ndarray = field(default_factory=lambda: NO_ROWS)  # rows of the breakable tiles
    ahead: dict[int, PreparedTile] = field(default_factory=dict)  # field tile -> prepared for its switch
    late_switches: int = 0  # tiles switched in before their preparation was done
    searchlights: list[SearchlightState] = field(default_factory=list)  # as commanded, one per mount
    environment: Environment = field(default_factory=Environment)  # as the instructor set it
    moving_to: Reposition | None = None  # a move of the ship waiting for its tiles
    vessels: dict[int, OtherVessel] = field(default_factory=dict)  # other vessels the instructor steers, by MMSI
    sensors: list[SensorFaults] = field(default_factory=lambda: [SensorFaults()])  # each ship's sensor failures
    ice_frame: IceFrame = field(default_factory=IceFrame)  # where the drifting field has gone

    @property
    def ship(self) -> ShipData:
        """The node's own ship's state."""
        return self.ships[0]


@dataclass(frozen=True)
class WorldEvents:
    """What the world publishes after a step (or, with ``snapshot`` set, the whole state).

    A live tile's floe rows keep their numbers (``sim_core.ice.floes``), so consumers can
    keep live floes by row. A tile ``placed`` is given rows, as is a tile thawed (listed in
    both ``placed``, with its new rows, and ``thawed``). A tile ``frozen`` gives its rows up
    (a later placement may be given them), and its broken cells travel as
    ``frozen_floes`` (``FROZEN_FLOE_EVENT`` records): all others of its cells are intact.
    ``floe_rows`` are the rows whose pose or status changed: the free floes of the live
    tiles that moved, or came free, since they were last published (a floe at rest is not
    sent again), and every row of a tile placed or thawed in this step; in a snapshot, every
    row of the live tiles, with ``frozen`` and ``frozen_floes`` naming every frozen tile and
    its floes. ``cracked`` names the intact cells cracked in the step (in a snapshot, every
    cracked cell of the live tiles; and every cracked cell of a tile placed or thawed) with
    their crack labels (``sim_core.ice.bending``); ``frozen_cracks`` the cracked intact cells
    of the tiles frozen (in a snapshot, of every frozen tile). Poses
    are (x, y, heave, yaw, roll, pitch) in m and rad, and they, the tiles' corners and the
    frozen floes lie in the ice's frame: a point (x, y) of it is at (x, y) + ``ice_offset``
    in the world (``sim_core.ice.drift.IceFrame``; zero unless the field drifts).
    ``retiled`` names the tiles whose ice class the instructor changed at the step's start
    (``RETILED`` records; in a snapshot, every tile whose class is not the one laid).
    ``ship``, ``ice_load`` and ``rejected`` are the own ship's (the first); ``others``
    reports each other ship of the exercise (``sim_core.fleet.ShipReport``).
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
    frozen_floes: np.ndarray = field(default_factory=lambda: NO_FROZEN_FLOES)
    cracked: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=CRACK_EVENT))  # rows cracked, labels
    frozen_cracks: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=FROZEN_CRACK))  # of tiles frozen
    snapshot: bool = False
    environment: Environment = field(default_factory=Environment)  # as of the step's end
    commands: tuple[Command, ...] = ()  # the instructor's commands applied at the step's start
    vessels: tuple[tuple[int, OtherVessel], ...] = ()  # the instructor's other vessels (MMSI, copy) at its end
    instruments: ShipOutputs | None = None  # what the sensors read (their failures applied); None: ``ship``
    ice_offset: tuple[float, float] = (0.0, 0.0)  # m, x east, y north: the ice's frame in the world
    retiled: np.ndarray = field(default_factory=lambda: NO_RETILED)  # tiles given other ice, their classes
    others: tuple[ShipReport, ...] = ()  # the exercise's other ships, in the model's order after the first
    collisions: tuple[ShipContact, ...] = ()  # own ships touching at the step's end (``sim_core.ship.collision``)

    @property
    def readings(self) -> ShipOutputs:
        """The ship as the bridge's instruments read it."""
        return self.ship if self.instruments is None else self.instruments


def compile_world(ship: ShipModel, ice: IceModel, scene: SceneModel, origin: tuple[float, float] = (0.0, 0.0),
                  searchlights: tuple[SearchlightMount, ...] = (), rubble: RubbleModel | None = None,
                  others: tuple[ShipModel, ...] = ()) -> WorldModel:
    """The static world; origin: latitude and longitude (rad) of the field's corner;
    ``rubble``: the field's brash and ridges (None: none); ``others``: the exercise's ships
    besides the own ``ship``, each with its hull in the ice."""
    if rubble is None:
        rubble = compile_rubble([], None, (), scene.nx, scene.ny, scene.side)
    ships = (ship, *others)
    contours = tuple(waterline_contour(s.particulars.length, s.particulars.beam) for s in ships)
    return WorldModel(ships, ice, scene, contours, origin, searchlights, rubble)


def new_world_data(model: WorldModel, north: float, east: float, heading: float, speed: float,
                   telegraph: str | None = None, others: tuple[ShipStart, ...] = ()) -> WorldData:
    """The ship at (north, east) m from the exercise origin (the field's south-west corner
    as laid), heading rad (clockwise from north), steaming at speed m/s; optionally with a
    telegraph order; and the model's other ships where ``others`` starts them."""
    if len(others) != len(model.ships) - 1:
        raise ValueError(f"the world has {len(model.ships) - 1} other ships; {len(others)} starts were given")
    starts = (ShipStart(north, east, heading, speed, telegraph), *others)
    ships = [new_ship(m, start) for m, start in zip(model.ships, starts)]
    ice = new_ice_data(model.ice, model.contour, model.ship.material.hull_friction)
    for m, contour in zip(model.ships[1:], model.contours[1:]):
        add_hull(ice, contour, m.material.hull_friction)
    data = WorldData(ships, ice, new_scene_data(model.scene), hull_breaks=[-math.inf] * len(ships),
                     searchlights=[m.default for m in model.searchlights], sensors=[SensorFaults()] * len(ships))
    warm_up(model, data)
    return data


def warm_up(model: WorldModel, data: WorldData) -> None:
    """Do before the first step what it would otherwise do lazily: load the compiled
    kernels, and build the tiles around the start position (and the ring beyond) in full,
    so that the first step only switches them in."""
    warm_up_ice(model.ice, data.ice)
    warm_up_moved(data)
    contour = fleet_contour(model, data)
    start = with_ice(model.scene, data.scene, tiles_near(contour, model.scene.radius, model.scene.nx,
                                                         model.scene.ny, model.scene.side))
    for tile in start.tolist():
        data.ahead[tile] = prepare_switch(model, data, tile)
    prepare_ahead(model, data, contour, budget_s=math.inf)
    for prepared in data.ahead.values():
        while not prepared.done:
            advance(data.ice, prepared, 1 << 30)


def _report(model: WorldModel, data: WorldData, k: int, load: np.ndarray,
            rejected: list[OrderRejection]) -> ShipReport:
    """The k-th ship's (k >= 1) report: its outputs, as its sensors read them too."""
    truth = ship_outputs(data.ships[k], data.time, *model.origin, data.epoch + data.time, ())
    readings = sensor_readings(truth, data.sensors[k], model.origin)
    return ShipReport(truth, load, tuple(rejected), None if readings is truth else readings)


def _publish(model: WorldModel, data: WorldData, rows: np.ndarray, loads: np.ndarray,
             rejected: list[list[OrderRejection]], **fields) -> WorldEvents:
    """Events with the ships' outputs, ice loads ((ships, 3): X, Y N; N N m) and refused
    orders (by ship), the given rows' poses and statuses, and counts."""
    st = data.ice.state
    pose = np.column_stack([st.xy[rows], st.heave[rows], st.yaw[rows], st.roll[rows], st.pitch[rows]])
    utc = data.epoch + data.time
    ship = ship_outputs(data.ship, data.time, *model.origin, utc, tuple(data.searchlights))
    others = tuple(_report(model, data, k, loads[k], rejected[k]) for k in range(1, len(data.ships)))
    readings = sensor_readings(ship, data.sensors[0], model.origin)
    return WorldEvents(seq=data.seq, time=data.time, ship=ship, instruments=None if readings is ship else readings,
                       ice_load=loads[0], rejected=tuple(rejected[0]), others=others,
                       floe_rows=rows, floe_pose=pose, floe_status=st.status[rows].copy(),
                       floes_free=st.count(FloeStatus.FREE), floes_frozen=data.ice.frozen.count,
                       environment=data.environment, ice_offset=tuple(data.ice_frame.offset.tolist()),
                       vessels=tuple((m, dataclasses.replace(v)) for m, v in data.vessels.items()), **fields)


def _apply_commands(model: WorldModel, data: WorldData, commands: tuple[Command, ...]) -> dict:
    """Apply the step's commands, and a waiting move whose tiles are ready; returns the
    events' fields of what was applied: the commands (a move as ``at_once``), and the tiles
    given other ice."""
    laid = data.scene.tile_class.copy() if any(isinstance(c, SetIce) for c in commands) else None
    applied = [done for c in commands if (done := apply_command(model, data, c)) is not None]
    to = data.moving_to
    if to is not None:
        contour = fleet_contour(model, data)  # with the moving ship where it goes
        start = sum(len(c) for c in model.contours[:to.ship])
        contour[start:start + len(model.contours[to.ship])] = contour_in_ice(model, data, to.north, to.east,
                                                                            to.heading, to.ship)
        if prepare_ahead(model, data, contour, model.scene.settings.prepare_budget_ms * 1e-3):
            applied.append(apply_command(model, data, dataclasses.replace(to, at_once=True)))
    if laid is None:
        return {"commands": tuple(applied), "retiled": NO_RETILED}
    tiles = np.flatnonzero(laid != data.scene.tile_class)
    return {"commands": tuple(applied), "retiled": retiled_records(tiles, data.scene.tile_class[tiles])}


def _externals(data: WorldData) -> np.ndarray:
    """Every ship's external load now (ships, 3): X, Y N; N N m."""
    return np.array([ship.external for ship in data.ships])


def _held(model: WorldModel, data: WorldData, rejected: list[list[OrderRejection]]) -> WorldEvents:
    """A frozen exercise's step: nothing moves and the clock stands, but the step is counted
    and published, so that every tick's listeners (the links above all) report the state."""
    data.seq += 1
    return _publish(model, data, NO_ROWS, _externals(data), rejected, placed=placed_tiles(data.ice.tiles, [], []),
                    thawed=NO_ROWS, frozen=NO_ROWS, broken_by_hull=NO_ROWS, broken_by_contact=NO_ROWS)


def _take_orders(model: WorldModel, data: WorldData, controls: list[Controls | None]) -> list[list[OrderRejection]]:
    """Give each ship its orders, and the own ship its searchlights'; returns the orders
    each ship clamped or refused."""
    rejected = [apply_controls(m, ship, c) if c is not None else []
                for m, ship, c in zip(model.ships, data.ships, controls)]
    for order in controls[0].searchlights if controls[0] is not None else ():
        if refused := order_searchlight(model.searchlights, data.searchlights, order):
            rejected[0].append(refused)
    return rejected


def step(model: WorldModel, data: WorldData, dt: float,
         controls: Controls | Sequence[Controls | None] | None = None,
         commands: tuple[Command, ...] = ()) -> WorldEvents:
    """Advance the world by dt seconds after the instructor's ``commands``, with the
    consoles' orders (one ``Controls``: the own ship's; a sequence: one per ship, None for
    none; a frozen exercise: take them, move nothing); returns what it publishes."""
    timer = data.ice.timer
    timer.start()
    applied = _apply_commands(model, data, commands)  # the events' commands and retiled
    orders = per_ship(controls, len(model.ships))
    rejected = _take_orders(model, data, orders)
    if data.environment.frozen:
        return dataclasses.replace(_held(model, data, rejected), **applied)
    winds = [move_ship(model, data, k, dt, c) for k, c in enumerate(orders)]
    move_vessels(data.vessels, dt)
    impacts, touching = collisions(model, data, orders, dt)
    water = drift_ice(model, data, dt)
    timer.lap("ships")
    contours, hulls = hulls_in_ice(model, data)
    contour = np.concatenate(contours)
    update = update_scene(model.scene, data.scene, contour, np.array([h.xy for h in hulls]))
    placed, thawed, frozen = apply_swaps(model, data, update, contours)
    timer.lap("tile switches")
    report = ice_step(model.ice, data.ice, hulls, dt, water, fleet_wash(model, data))
    if data.moving_to is None:  # (a move's tiles are prepared first)
        prepare_ahead(model, data, contour, model.scene.settings.prepare_budget_ms * 1e-3)
    timer.lap("tiles ahead")
    data.time += dt
    data.seq += 1
    loads = take_ice_loads(data, report, winds, impacts)
    rows = moved_rows(data, placed)
    events = _publish(model, data, rows, loads, rejected, collisions=touching, placed=placed, thawed=thawed,
                      frozen=frozen, frozen_floes=frozen_floes_of(data.ice, frozen.tolist()),
                      broken_by_hull=report.broken_by_hull, broken_by_contact=report.broken_by_contact,
                      cracked=cracks_published(data, placed, report.cracked),
                      frozen_cracks=frozen_cracks_of(data.ice, frozen.tolist()), **applied)
    timer.lap("publish")
    return events


def snapshot(model: WorldModel, data: WorldData) -> WorldEvents:
    """The whole published state now, as events with ``snapshot`` set: every placed tile,
    every row of the live tiles, every broken cell, the frozen placements and their floes."""
    tiles, st = data.ice.tiles, data.ice.state
    by_tile = sorted(data.scene.placement.items(), key=lambda kv: kv[1])
    frozen = [k for t, k in by_tile if data.scene.tile_state[t] == TileState.FROZEN]
    rows = data.live_rows
    broken = rows[st.status[rows] == FloeStatus.FREE]
    placed = placed_tiles(tiles, [t for t, _ in by_tile], [k for _, k in by_tile])
    changed = np.flatnonzero(data.scene.tile_class != model.scene.tile_class)
    return _publish(model, data, rows, _externals(data), [[] for _ in data.ships], placed=placed,
                    thawed=NO_ROWS, frozen=np.array(frozen, dtype=np.int64),
                    frozen_floes=frozen_floes_of(data.ice, frozen),
                    broken_by_hull=broken[st.cause[broken] == BreakCause.HULL],
                    broken_by_contact=broken[st.cause[broken] == BreakCause.CONTACT],
                    cracked=crack_events(st.crack, rows), frozen_cracks=frozen_cracks_of(data.ice, frozen),
                    retiled=retiled_records(changed, data.scene.tile_class[changed]),
                    snapshot=True)
