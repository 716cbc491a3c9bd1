"""The exercise's ships: each with its own model, state and orders, and its own hull in the
one ice world.

The first ship is the one the node's bridge serves (``WorldModel.ship``); the others follow
it in ``WorldModel.ships``. Every hull breaks ice in the one contact space
(``sim_core.ice.hull_bodies``), so a ship that follows another meets the channel the first
broke: its bow is in breakable ice it does not break, which is the broken-channel
condition of its resistance (``ship_in_ice.ice_condition``), and it pushes the floes the
first left. Each ship takes its own orders, meets its own wind and ice, and publishes its
own outputs; the instructor's environment, the ice field and the clock are shared.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sim_core.frames.hull_contour import waterline_contour
from sim_core.frames.ship_frame import world_vector_to_ship
from sim_core.ice.step import HullMotion, IceStepReport
from sim_core.ship import model as ship_model
from sim_core.ship.collision import ShipContact, ship_collisions
from sim_core.ship.model import OrderRejection, ShipData, ShipModel
from sim_core.ship.outputs import ShipOutputs
from sim_core.ship.searchlights import SearchlightOrder
from sim_core.ship.wind import wind_load
from sim_core.ship_in_ice import hull_in_ice, ice_condition, ice_through_water, rubble_loads, ship_contour_in_ice, wash

if TYPE_CHECKING:
    from sim_core.instructor import OtherVessel
    from sim_core.world import WorldData, WorldModel


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
class ShipStart:
    """Where another ship of the exercise starts: north, east m from the exercise origin,
    heading rad clockwise from north, speed m/s, and optionally a telegraph order."""

    north: float
    east: float
    heading: float
    speed: float
    telegraph: str | None = None


@dataclass(frozen=True)
class ShipReport:
    """What a step publishes of a ship after the first: its outputs, the ice's contact load
    on its hull (X, Y N in the ship's frame; N N m, + to starboard), the orders it clamped
    or refused, and what its sensors read (None: the outputs, every sensor well)."""

    outputs: ShipOutputs
    ice_load: np.ndarray
    rejected: tuple[OrderRejection, ...] = ()
    instruments: ShipOutputs | None = None

    @property
    def readings(self) -> ShipOutputs:
        """The ship as its bridge's instruments read it."""
        return self.outputs if self.instruments is None else self.instruments


def new_ship(model: ShipModel, start: ShipStart) -> ShipData:
    """A ship's state at its start; a telegraph order the ship refuses is a ValueError."""
    ship = ship_model.new_ship_data(model, start.speed, heading=start.heading)
    ship.eta[0], ship.eta[1] = start.north, start.east
    if start.telegraph is not None:
        refused = ship_model.order_telegraph(model, ship, start.telegraph)
        if refused:
            raise ValueError(refused.text)
    return ship


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


def per_ship(controls: Controls | Sequence[Controls | None] | None, ships: int) -> list[Controls | None]:
    """The step's controls, one entry per ship: a single ``Controls`` is the first ship's."""
    if controls is None or isinstance(controls, Controls):
        return [controls] + [None] * (ships - 1)
    if len(controls) != ships:
        raise ValueError(f"the world has {ships} ships; controls were given for {len(controls)}")
    return list(controls)


def environment_load(model: WorldModel, data: WorldData, k: int) -> np.ndarray:
    """Set the current the k-th ship moves in; returns the wind load on it (X, Y N; N N m)."""
    ship, env = data.ships[k], data.environment
    ship.current[:] = env.current_north_east()
    psi = ship.eta[5]
    c, s = math.cos(psi), math.sin(psi)
    u = ship.nu[0] + c * ship.current[0] + s * ship.current[1]  # over ground, in the ship's axes
    v = ship.nu[1] - s * ship.current[0] + c * ship.current[1]
    return np.array(wind_load(model.ships[k].particulars.windage, u, v, psi, env))


def move_ship(model: WorldModel, data: WorldData, k: int, dt: float, controls: Controls | None) -> np.ndarray:
    """Advance the k-th ship by dt in the ice its bow is in: by its manoeuvring model, or to
    the kinematic pose its controls give (its ice resistance still reckoned for its
    outputs). Returns the wind load on it (X, Y N; N N m)."""
    ship, hull = data.ships[k], model.ships[k]
    wind = environment_load(model, data, k)
    stem = ship_contour_in_ice(model, data, k)[0]
    ship.ice_h, ship.ice_condition = ice_condition(model, data, stem, k)
    rubble_loads(model, k, ship, stem)
    ship.ice_drift[:] = ice_through_water(data)
    if controls is not None and controls.kinematic is not None:
        pose = controls.kinematic
        ship.eta[0], ship.eta[1], ship.eta[5] = pose.north, pose.east, pose.heading
        ship.nu[0], ship.nu[1], ship.nu[5] = pose.surge, pose.sway, pose.yaw_rate
        ship_model.ice_force(hull, ship, pose.surge - ship.ice_drift[0] * math.cos(pose.heading)
                             - ship.ice_drift[1] * math.sin(pose.heading))
    else:
        ship_model.step(hull, ship, dt)
    return wind


def fleet_contour(model: WorldModel, data: WorldData) -> np.ndarray:
    """Every ship's waterline contour in the ice's frame, stacked (34 x ships, 2) m, in the
    model's order: the scene keeps the tiles near any of them breakable."""
    return np.concatenate([ship_contour_in_ice(model, data, k) for k in range(len(model.ships))])


def hulls_in_ice(model: WorldModel, data: WorldData) -> tuple[list[np.ndarray], list[HullMotion]]:
    """Every ship's contour points (34, 2) and hull motion in the ice's frame."""
    both = [hull_in_ice(model, data, k) for k in range(len(model.ships))]
    return [c for c, _ in both], [h for _, h in both]


def collisions(model: WorldModel, data: WorldData, orders: Sequence[Controls | None],
               dt: float) -> tuple[np.ndarray, tuple[ShipContact, ...]]:
    """The ships touching one another, or a vessel the instructor steers, where this step's
    moves left them, and the loads ((ships, 3): X, Y N; N N m) that give each own ship its
    impulse over the next step (``sim_core.ship.collision``). A ship on a logged track
    and a scripted vessel give way to nothing; a vessel is drawn as a ship's waterline of
    its length and beam (``waterline_contour``)."""
    own = len(model.ships)
    near = [(mmsi, v) for mmsi, v in data.vessels.items()
            if any(math.dist((v.north, v.east), s.eta[:2]) < v.length + m.L for m, s in zip(model.ships, data.ships))]
    if own < 2 and not near:
        return np.zeros((own, 3)), ()
    kinematic = [c is not None and c.kinematic is not None for c in orders] + [True] * len(near)
    bodies = [*data.ships, *(_vessel_body(v) for _, v in near)]
    contours = [*model.contours, *(waterline_contour(v.length, v.beam) for _, v in near)]
    loads, touching = ship_collisions([*model.ships, *(None for _ in near)], bodies, contours, kinematic, dt, own)
    return loads[:own], tuple(c if c.ships[1] < own else
                              dataclasses.replace(c, ships=c.ships[:1], vessel=near[c.ships[1] - own][0])
                              for c in touching)


def _vessel_body(vessel: OtherVessel) -> ShipData:
    """A scripted vessel as a ship's state: where it is, heading its course at its speed."""
    body = ShipData()
    body.eta[0], body.eta[1], body.eta[5] = vessel.north, vessel.east, vessel.course
    body.nu[0] = vessel.speed
    return body


def take_ice_loads(data: WorldData, report: IceStepReport, winds: list[np.ndarray], impacts: np.ndarray) -> np.ndarray:
    """Give each ship the ice's contact load on its hull, with its wind load and the
    other ships' impacts (``collisions``), as its external load for the next step, and note
    the ships whose hulls broke cells; returns the ice's contact loads (ships, 3): X, Y N in
    each ship's frame; N N m (+ to starboard)."""
    loads = np.zeros((len(data.ships), 3))
    for k, ship in enumerate(data.ships):
        loads[k] = (*world_vector_to_ship(report.hull_force[k], ship.eta[5]), -report.hull_moment[k])
        ship.external[:] = loads[k] + winds[k] + impacts[k]
        if report.hull_broke[k]:
            data.hull_breaks[k] = data.time
    return loads


def fleet_wash(model: WorldModel, data: WorldData) -> Callable[[np.ndarray], np.ndarray] | None:
    """The ships' propeller jets together, as one water velocity field over points of the
    ice world (``ship_in_ice.wash``), or None where no ship washes the ice."""
    jets = [w for k in range(len(model.ships)) if (w := wash(model, data, k)) is not None]
    if len(jets) <= 1:
        return jets[0] if jets else None
    return lambda points: sum(jet(points) for jet in jets)
