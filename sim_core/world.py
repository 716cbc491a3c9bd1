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
drifts where the whole field does. The instructor's environment (``sim_core.environment``)
lives in the data and is published with every step: the wind loads the ship
(``sim_core.ship.wind``) and drifts the ice, the current carries the ship and the ice, and
a frozen exercise takes its orders but moves nothing and stops its clock, while every tick
still publishes a step.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from sim_core.environment import Environment
from sim_core.frames.hull_contour import waterline_contour
from sim_core.frames.ship_frame import world_vector_to_ship
from sim_core.ice.floes import FROZEN_CRACK, BreakCause, FloeStatus
from sim_core.ice.model import IceModel
from sim_core.ice.bending import CRACK_EVENT, crack_events
from sim_core.ice.drift import IceFrame
from sim_core.ice.step import ice_step
from sim_core.instructor import Command, OtherVessel, Reposition, SetIce, apply_command, move_vessels
from sim_core.ice.step import warm_up as warm_up_ice
from sim_core.ice.tiles import IceData, PreparedTile, advance, new_ice_data
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
)
from sim_core.ship import model as ship_model
from sim_core.ship.model import OrderRejection, ShipData, ShipModel
from sim_core.ship.outputs import ShipOutputs, ship_outputs
from sim_core.regimes.rubble import RubbleModel, compile_rubble
from sim_core.ship.searchlights import SearchlightMount, SearchlightOrder, SearchlightState, order_searchlight
from sim_core.ship.sensors import SensorFaults, sensor_readings
from sim_core.ship.wind import wind_load
from sim_core.ship_in_ice import (contour_in_ice, drift_ice, hull_in_ice, ice_condition, ice_through_water,
                                  rubble_loads, ship_contour_in_ice, wash)

NO_RETILED = np.zeros(0, dtype=RETILED)
NO_RETILED.flags.writeable = False  # shared by the events of every step that lays no ice


@dataclass(frozen=True)
class WorldModel:
    """Static half of the world."""

    ship: ShipModel
    ice: IceModel
    scene: SceneModel
    contour: np.ndarray  # (34, 2) hull waterline contour, ship frame (x forward, y starboard), m
    origin: tuple[float, float]  # latitude, longitude of the field's south-west corner, rad
    searchlights: tuple[SearchlightMount, ...]  # the own ship's, by index
    rubble: RubbleModel  # brash and ridges, met through their resistance models


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
    live_rows: np.ndarray = field(default_factory=lambda: NO_ROWS)  # rows of the breakable tiles
    ahead: dict[int, PreparedTile] = field(default_factory=dict)  # field tile -> prepared for its switch
    late_switches: int = 0  # tiles switched in before their preparation was done
    searchlights: list[SearchlightState] = field(default_factory=list)  # as commanded, one per mount
    environment: Environment = field(default_factory=Environment)  # as the instructor set it
    moving_to: Reposition | None = None  # a move of the ship waiting for its tiles
    vessels: dict[int, OtherVessel] = field(default_factory=dict)  # other vessels the instructor steers, by MMSI
    sensors: SensorFaults = field(default_factory=SensorFaults)  # the instructor's sensor failures
    ice_frame: IceFrame = field(default_factory=IceFrame)  # where the drifting field has gone


@dataclass(frozen=True)
class KinematicPose:
    """Where a logged track puts the ship at the end of a step, instead of its manoeuvring
    model (replay): north, east m from the exercise origin (the field's corner as laid),
    heading rad clockwise from north, surge and sway m/s, yaw rate rad/s (+ to starboard)."""

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
    its floes. ``cracked`` names the intact cells cracked in the step (in a snapshot, every
    cracked cell of the live tiles; and every cracked cell of a tile placed or thawed) with
    their crack labels (``sim_core.ice.bending``); ``frozen_cracks`` the cracked intact cells
    of the tiles frozen (in a snapshot, of every frozen tile). Poses
    are (x, y, heave, yaw, roll, pitch) in m and rad, and they, the tiles' corners and the
    frozen floes lie in the ice's frame: a point (x, y) of it is at (x, y) + ``ice_offset``
    in the world (``sim_core.ice.drift.IceFrame``; zero unless the field drifts).
    ``retiled`` names the tiles whose ice class the instructor changed at the step's start
    (``RETILED`` records; in a snapshot, every tile whose class is not the one laid).
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

    @property
    def readings(self) -> ShipOutputs:
        """The ship as the bridge's instruments read it."""
        return self.ship if self.instruments is None else self.instruments


def compile_world(ship: ShipModel, ice: IceModel, scene: SceneModel, origin: tuple[float, float] = (0.0, 0.0),
                  searchlights: tuple[SearchlightMount, ...] = (), rubble: RubbleModel | None = None) -> WorldModel:
    """The static world; origin: latitude and longitude (rad) of the field's corner;
    ``rubble``: the field's brash and ridges (None: none)."""
    p = ship.particulars
    if rubble is None:
        rubble = compile_rubble([], None, (), scene.nx, scene.ny, scene.side)
    return WorldModel(ship, ice, scene, waterline_contour(p.length, p.beam), origin, searchlights, rubble)


def new_world_data(model: WorldModel, north: float, east: float, heading: float, speed: float,
                   telegraph: str | None = None) -> WorldData:
    """The ship at (north, east) m from the exercise origin (the field's south-west corner
    as laid), heading rad (clockwise from north), steaming at speed m/s; optionally with a
    telegraph order."""
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
    contour = ship_contour_in_ice(model, data)
    start = with_ice(model.scene, data.scene, tiles_near(contour, model.scene.radius, model.scene.nx,
                                                         model.scene.ny, model.scene.side))
    for tile in start.tolist():
        data.ahead[tile] = prepare_switch(model, data, tile)
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


def _publish(model: WorldModel, data: WorldData, rows: np.ndarray, **fields) -> WorldEvents:
    """Events with the ship's outputs, the given rows' poses and statuses, and counts."""
    st = data.ice.state
    pose = np.column_stack([st.xy[rows], st.heave[rows], st.yaw[rows], st.roll[rows], st.pitch[rows]])
    ship = ship_outputs(data.ship, data.time, *model.origin, data.epoch + data.time, tuple(data.searchlights))
    readings = sensor_readings(ship, data.sensors, model.origin)
    return WorldEvents(seq=data.seq, time=data.time, ship=ship, instruments=None if readings is ship else readings,
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
        contour = contour_in_ice(model, data, to.north, to.east, to.heading)
        if prepare_ahead(model, data, contour, model.scene.settings.prepare_budget_ms * 1e-3):
            applied.append(apply_command(model, data, dataclasses.replace(to, at_once=True)))
    if laid is None:
        return {"commands": tuple(applied), "retiled": NO_RETILED}
    tiles = np.flatnonzero(laid != data.scene.tile_class)
    return {"commands": tuple(applied), "retiled": retiled_records(tiles, data.scene.tile_class[tiles])}


def _held(model: WorldModel, data: WorldData, rejected: list[OrderRejection]) -> WorldEvents:
    """A frozen exercise's step: nothing moves and the clock stands, but the step is counted
    and published, so that every tick's listeners (the links above all) report the state."""
    data.seq += 1
    return _publish(model, data, NO_ROWS, placed=placed_tiles(data.ice.tiles, [], []), thawed=NO_ROWS,
                    frozen=NO_ROWS, broken_by_hull=NO_ROWS, broken_by_contact=NO_ROWS,
                    ice_load=data.ship.external.copy(), rejected=tuple(rejected))


def _environment_loads(model: WorldModel, data: WorldData) -> np.ndarray:
    """Set the current the ship moves in; returns the wind load on it (X, Y N; N N m)."""
    ship, env = data.ship, data.environment
    ship.current[:] = env.current_north_east()
    psi = ship.eta[5]
    c, s = math.cos(psi), math.sin(psi)
    u = ship.nu[0] + c * ship.current[0] + s * ship.current[1]  # over ground, in the ship's axes
    v = ship.nu[1] - s * ship.current[0] + c * ship.current[1]
    return np.array(wind_load(model.ship.particulars.windage, u, v, psi, env))


def step(model: WorldModel, data: WorldData, dt: float, controls: Controls | None = None,
         commands: tuple[Command, ...] = ()) -> WorldEvents:
    """Advance the world by dt seconds after the instructor's ``commands``, with the
    console's orders (a frozen exercise: take them, move nothing); returns what it
    publishes."""
    applied = _apply_commands(model, data, commands)  # the events' commands and retiled
    rejected = apply_controls(model.ship, data.ship, controls) if controls is not None else []
    for order in controls.searchlights if controls is not None else ():
        if refused := order_searchlight(model.searchlights, data.searchlights, order):
            rejected.append(refused)
    if data.environment.frozen:
        return dataclasses.replace(_held(model, data, rejected), **applied)
    ship = data.ship
    wind = _environment_loads(model, data)
    contour = ship_contour_in_ice(model, data)
    ship.ice_h, ship.ice_condition = ice_condition(model, data, contour[0])  # contour[0] is the stem
    rubble_loads(model, ship, contour[0])
    ship.ice_drift[:] = ice_through_water(data)
    if controls is not None and controls.kinematic is not None:
        k = controls.kinematic
        ship.eta[0], ship.eta[1], ship.eta[5] = k.north, k.east, k.heading
        ship.nu[0], ship.nu[1], ship.nu[5] = k.surge, k.sway, k.yaw_rate
    else:
        ship_model.step(model.ship, ship, dt)
    water = drift_ice(model, data, dt)
    contour, hull = hull_in_ice(model, data)
    placed, thawed, frozen = apply_swaps(model, data, update_scene(model.scene, data.scene, contour, hull.xy), contour)
    report = ice_step(model.ice, data.ice, hull, dt, water, wash(model, data))
    if data.moving_to is None:  # (a move's tiles are prepared first)
        prepare_ahead(model, data, contour, model.scene.settings.prepare_budget_ms * 1e-3)
    load = np.array([*world_vector_to_ship(report.hull_force, ship.eta[5]), -report.hull_moment])
    ship.external[:] = load + wind
    move_vessels(data.vessels, dt)
    data.time += dt
    data.seq += 1
    if len(report.broken_by_hull):
        data.last_hull_break = data.time
    rows = moved_rows(data, placed)
    return _publish(model, data, rows, placed=placed, thawed=thawed, frozen=frozen,
                    frozen_floes=frozen_floes_of(data.ice, frozen.tolist()), broken_by_hull=report.broken_by_hull,
                    broken_by_contact=report.broken_by_contact,
                    cracked=cracks_published(data, placed, report.cracked),
                    frozen_cracks=frozen_cracks_of(data.ice, frozen.tolist()), ice_load=load, rejected=tuple(rejected),
                    **applied)


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
    return _publish(model, data, rows, placed=placed,
                    thawed=NO_ROWS, frozen=np.array(frozen, dtype=np.int64),
                    frozen_floes=frozen_floes_of(data.ice, frozen),
                    broken_by_hull=broken[st.cause[broken] == BreakCause.HULL],
                    broken_by_contact=broken[st.cause[broken] == BreakCause.CONTACT],
                    cracked=crack_events(st.crack, rows), frozen_cracks=frozen_cracks_of(data.ice, frozen),
                    ice_load=data.ship.external.copy(), rejected=(),
                    retiled=retiled_records(changed, data.scene.tile_class[changed]),
                    snapshot=True)
