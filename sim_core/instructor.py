"""What an instructor does to a running exercise, as typed values the world applies at a
step's start (``step(..., commands=...)``), in the order given: freeze and resume, move the
own ship, set the visibility, the exercise clock, the wind and the current, and fail the
steering gear, the engine or a sensor (``sim_core.ship.sensors``), steer other vessels
(``OtherVessel``, kept in the world and moved with each step, so that a replay has them
where the run had them), and lay other ice over an area of the field (``SetIce``). SI: m,
m/s, rad, unix s. Values are checked where they are made (``bridge_node.control.commands``);
here they are only applied.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely

from sim_core.ice.tiles import discard_prepared
from sim_core.scene.quadtree import tiles_near
from sim_core.scene.scene import TileState
from sim_core.ship.model import equilibrium_rps
from sim_core.ship_in_ice import ship_contour_in_ice
from sim_core.ship.sensors import SensorFailure, fail_sensor

if TYPE_CHECKING:
    from sim_core.world import WorldData, WorldModel


@dataclass(frozen=True)
class Freeze:
    """Freeze (physics held, clock stopped) or resume the exercise."""

    frozen: bool


@dataclass(frozen=True)
class Reposition:
    """The world's ``ship``-th ship (0: the own ship) to (north, east) m from the exercise
    origin (the field's corner as laid), heading rad clockwise from north, speed m/s ahead
    through the water, engine turning to hold it, rudder midships.
    Not ``at_once``: the ship moves at the first step by which the tiles around the new
    place have been prepared ahead (within the steps' budget, so that no step stalls);
    the step that moves it publishes the move ``at_once``, as a replay gives it."""

    north: float
    east: float
    heading: float
    speed: float
    at_once: bool = False
    ship: int = 0


@dataclass(frozen=True)
class SetEnvironment:
    """New values for some of the environment's fields (``sim_core.environment``); the
    others keep theirs."""

    changes: tuple[tuple[str, float], ...]


@dataclass(frozen=True)
class SetClock:
    """The exercise clock to this UTC now, unix s (the time of day, the sun)."""

    utc: float


@dataclass(frozen=True)
class SteeringFailure:
    """The steering gear's pumps that work: 2 all, 1 (half the rate), 0 (the rudder stuck);
    of the world's ``ship``-th ship (0: the own ship)."""

    pumps: int
    ship: int = 0


@dataclass(frozen=True)
class EngineFailure:
    """The share of the engine's power available: 1 all, 0 a blackout; of the world's
    ``ship``-th ship (0: the own ship)."""

    power_share: float
    ship: int = 0


@dataclass
class OtherVessel:
    """A vessel the instructor steers: north, east m from the exercise origin (the field's
    corner as laid), course rad clockwise from north, speed m/s over ground (straight on),
    name (AIS 6-bit text), length and beam m."""

    name: str
    north: float
    east: float
    course: float
    speed: float
    length: float
    beam: float


@dataclass(frozen=True)
class AddVessel:
    """A new vessel (or one replaced) under this MMSI."""

    mmsi: int
    vessel: OtherVessel


@dataclass(frozen=True)
class MoveVessel:
    """A vessel to (north, east) m."""

    mmsi: int
    north: float
    east: float


@dataclass(frozen=True)
class SteerVessel:
    """A vessel on a new course (rad) and speed (m/s)."""

    mmsi: int
    course: float
    speed: float


@dataclass(frozen=True)
class RemoveVessel:
    """A vessel gone from the exercise."""

    mmsi: int


@dataclass(frozen=True)
class SetIce:
    """Lay the ice class named ``ice`` (one of ``SceneModel.class_names``) over the tiles whose
    centres lie in the polygon: (east, north) m from the exercise origin, as a region's
    (``sim_core.regimes.settings``), where the field lies now (a drifting field has moved
    from where it was laid). Only ice the
    ship has not met changes: tiles placed or frozen keep theirs, and so do the tiles within
    R_T + ``prepare_ahead`` of the hull, about to be switched in (their engine objects are
    built ahead; building new ones at the switch would stall the step)."""

    polygon: tuple[tuple[float, float], ...]
    ice: str


Command = (Freeze | Reposition | SetEnvironment | SetClock | SteeringFailure | EngineFailure | SensorFailure
           | AddVessel | MoveVessel | SteerVessel | RemoveVessel | SetIce)
VESSEL_COMMANDS = (AddVessel, MoveVessel, SteerVessel, RemoveVessel)
SHIP_COMMANDS = (Reposition, SteeringFailure, EngineFailure, SensorFailure)  # to the world's ``ship``-th ship


def apply_command(model: WorldModel, data: WorldData, command: Command) -> Command | None:
    """Carry one command out on the world, before its step; returns it as applied (None
    for a move that waits for its tiles: ``WorldData.moving_to``)."""
    if isinstance(command, Freeze):
        data.environment = dataclasses.replace(data.environment, frozen=command.frozen)
    elif isinstance(command, SetEnvironment):
        data.environment = dataclasses.replace(data.environment, **dict(command.changes))
    elif isinstance(command, SetClock):
        data.epoch = command.utc - data.time
    elif isinstance(command, SHIP_COMMANDS) and not 0 <= command.ship < len(data.ships):
        return None  # a ship the world lacks (a record replayed on another exercise)
    elif isinstance(command, SteeringFailure):
        data.ships[command.ship].steering_pumps = command.pumps
    elif isinstance(command, EngineFailure):
        data.ships[command.ship].power_share = command.power_share
    elif isinstance(command, SensorFailure):
        data.sensors[command.ship] = fail_sensor(data.sensors[command.ship], command, data.ships[command.ship])
    elif isinstance(command, VESSEL_COMMANDS):
        return command if _command_vessel(data.vessels, command) else None
    elif isinstance(command, Reposition) and not command.at_once:
        data.moving_to = command
        return None
    elif isinstance(command, Reposition):
        data.moving_to = None
        move_ship(model, data, command)
    elif isinstance(command, SetIce) and command.ice not in model.scene.class_names:
        return None  # ice the world lacks (a record replayed on another exercise)
    elif isinstance(command, SetIce):
        lay_ice(model, data, command)
    return command


def lay_ice(model: WorldModel, data: WorldData, command: SetIce) -> None:
    """Carry a ``SetIce`` out on the scene (its ice one the model has). Preparations of the
    tiles it changes are dropped (``prepare_ahead`` redoes them)."""
    scene, ice_class = model.scene, model.scene.class_names.index(command.ice)
    area = shapely.Polygon(np.array(command.polygon) - data.ice_frame.offset)  # in the ice's frame
    x0, y0, x1, y1 = area.bounds
    ix = np.arange(max(0, int(x0 // scene.side)), min(scene.nx, int(x1 // scene.side) + 1))
    iy = np.arange(max(0, int(y0 // scene.side)), min(scene.ny, int(y1 // scene.side) + 1))
    tiles = (iy[:, None] * scene.nx + ix[None, :]).ravel()
    centre = scene.centre(tiles)
    tiles = tiles[shapely.contains_xy(area, centre[:, 0], centre[:, 1])
                  & (data.scene.tile_state[tiles] == TileState.UNBREAKABLE)
                  & (data.scene.tile_class[tiles] != ice_class)]
    near = tiles_near(ship_contour_in_ice(model, data), scene.radius + scene.settings.prepare_ahead,
                      scene.nx, scene.ny, scene.side)
    tiles = np.setdiff1d(tiles, near)
    data.scene.tile_class[tiles] = ice_class
    for tile in tiles.tolist():
        if tile in data.ahead:
            discard_prepared(data.ice, data.ahead.pop(tile))


def _command_vessel(vessels: dict[int, OtherVessel], command: Command) -> bool:
    """Carry out a command to another vessel; False where it names none the world has."""
    if isinstance(command, AddVessel):
        vessels[command.mmsi] = dataclasses.replace(command.vessel)  # its own copy, moved by the steps
        return True
    vessel = vessels.get(command.mmsi)
    if vessel is None:
        return False
    if isinstance(command, MoveVessel):
        vessel.north, vessel.east = command.north, command.east
    elif isinstance(command, SteerVessel):
        vessel.course, vessel.speed = command.course, command.speed
    else:
        del vessels[command.mmsi]
    return True


def move_vessels(vessels: dict[int, OtherVessel], dt: float) -> None:
    """Every other vessel straight on for dt s."""
    for v in vessels.values():
        v.north += v.speed * math.cos(v.course) * dt
        v.east += v.speed * math.sin(v.course) * dt


def move_ship(model: WorldModel, data: WorldData, to: Reposition) -> None:
    """Move the ship ``to`` names; its wake of broken ice stays where it was, and the scene
    switches the tiles around the new place in at the step."""
    ship = data.ships[to.ship]
    ship.eta[:] = 0.0
    ship.nu[:] = 0.0
    ship.eta[0], ship.eta[1], ship.eta[5] = to.north, to.east, to.heading % (2.0 * math.pi)
    ship.nu[0] = to.speed
    ship.rps = ship.rps_order = equilibrium_rps(model.ships[to.ship], to.speed)
    ship.rudder = ship.rudder_order = 0.0
    ship.external[:] = 0.0
    data.hull_breaks[to.ship] = -math.inf
