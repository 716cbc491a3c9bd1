"""Where the ship (in the world: north/east, heading clockwise from north) meets the ice
world (x east, y north, angles counter-clockwise from east, in the ice's own frame,
``sim_core.ice.drift.IceFrame``): the hull's contour and motion in the ice, the ice
condition and rubble at the bow that set the ship's resistance, the velocity the floes
drift towards, and the propeller's wash over them.

With ``[ice_dynamics] field_drift`` the whole field drifts with the current and the wind's
free drift; the ice world then steps in its drifting frame, where the floes' drift target
is rest (they drift with the frame) and the hull moves at its velocity over the ice. The
field starts drifting steadily (``start_drifting``). Without it the frame stays at the
world's origin and the floes drift through the fast level ice towards the current plus
their free drift.
"""
from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from sim_core.frames.ship_frame import ship_to_world, ship_vector_to_world, world_heading
from sim_core.ice.drift import drift_frame, free_drift
from sim_core.ice.step import HullMotion
from sim_core.regimes.rubble import rubble_at
from sim_core.scene.quadtree import tile_under
from sim_core.scene.scene import TileState
from sim_core.ship.model import ShipData, propeller_thrust
from sim_core.ship.propeller_jet import jet_velocity, propeller_jet
from sim_core.ship.resistance import BROKEN_CHANNEL, LEVEL_ICE, OPEN_WATER
from sim_core.ship.rubble_resistance import brash_channel_resistance, keel_resistance

if TYPE_CHECKING:
    from sim_core.world import WorldData, WorldModel

BREAKING_MEMORY = 2.0  # s: the bow counts as in level ice this long after it last broke a cell
_STILL = np.zeros(2)


def contour_in_ice(model: WorldModel, data: WorldData, north: float, east: float, heading: float,
                   k: int = 0) -> np.ndarray:
    """The k-th ship's waterline contour (34, 2) in the ice's frame (m) for the ship at
    (north, east) m in the world, heading rad clockwise from north; its first point is the
    stem."""
    return ship_to_world(model.contours[k], north, east, heading) - data.ice_frame.offset


def ship_contour_in_ice(model: WorldModel, data: WorldData, k: int = 0) -> np.ndarray:
    """The k-th ship's waterline contour (34, 2) in the ice's frame, where it is now."""
    eta = data.ships[k].eta
    return contour_in_ice(model, data, eta[0], eta[1], eta[5], k)


def hull_in_ice(model: WorldModel, data: WorldData, k: int = 0) -> tuple[np.ndarray, HullMotion]:
    """The k-th ship's contour points (34, 2) and hull motion in the ice's frame: its place
    less the frame's offset, its velocity over ground less the frame's."""
    ship = data.ships[k]
    north, east, psi = ship.eta[0], ship.eta[1], ship.eta[5]
    over_ground = np.array(ship_vector_to_world((ship.nu[0], ship.nu[1]), psi)) + ship.current[::-1]
    frame = data.ice_frame
    return (ship_contour_in_ice(model, data, k),
            HullMotion(np.array([east, north]) - frame.offset, world_heading(psi), over_ground - frame.velocity,
                       -ship.nu[5], *model.ships[k].bow_surface))


def ice_condition(model: WorldModel, data: WorldData, bow: np.ndarray, k: int = 0) -> tuple[float, int]:
    """The ice thickness (m) and condition (``sim_core.ship.resistance``) at the k-th ship's
    bow (m, ice frame): open water off the field or in a lead, level ice while its hull is
    breaking cells, else a broken channel in breakable or frozen tiles (the channel a ship
    ahead broke too)."""
    scene = model.scene
    tile = tile_under(bow, scene.nx, scene.ny, scene.side)
    if tile < 0:
        return 0.0, OPEN_WATER
    h = scene.thickness_at(bow, data.scene.tile_class)
    if h <= 0.0:  # an open-water tile (a lead, an ice-free region)
        return 0.0, OPEN_WATER
    breaking = data.time - data.hull_breaks[k] < BREAKING_MEMORY
    if breaking or data.scene.tile_state[tile] not in (TileState.BREAKABLE, TileState.FROZEN):
        return h, LEVEL_ICE
    return h, BROKEN_CHANNEL


def rubble_loads(model: WorldModel, k: int, ship: ShipData, stem: np.ndarray) -> None:
    """Set the k-th ship's brash resistance (at 5 knots) and ridge-keel load from the
    rubble at its stem (m, ice frame; ``sim_core.ship.rubble_resistance``): the brash's
    channel resistance times the share of the tile it covers, and the keel's down to the
    ship's draught."""
    if model.rubble.empty:
        return
    share, thickness, ridges, depth = rubble_at(model.rubble, float(stem[0]), float(stem[1]))
    hull = model.ships[k]
    ship.brash_resistance = share * brash_channel_resistance(thickness, hull.bow)
    m = model.ice.material
    ship.keel_load = 0.0 if ridges is None else keel_resistance(
        min(depth, hull.d), hull.B, ridges.friction_angle, ridges.cohesion, ridges.porosity,
        m.water_density, m.density, m.gravity)


def ice_drift(model: WorldModel, data: WorldData) -> np.ndarray:
    """The velocity (world x east, y north, m/s) the ice drifts at: the current plus its
    free drift in the wind (``sim_core.ice.drift``)."""
    s, env = model.ice.settings, data.environment
    north, east = free_drift(*env.wind_north_east(), model.origin[0], s.wind_drift_factor,
                             math.radians(s.wind_drift_angle_deg))
    current_north, current_east = env.current_north_east()
    return np.array([current_east + east, current_north + north])


def ice_through_water(data: WorldData) -> np.ndarray:
    """The velocity of the ice the ship is in through the water (north, east m/s), whose
    ice resistance takes the ship's surge over the ice: the drifting field's velocity less
    the current's; the current reversed where the level ice is fast."""
    frame = data.ice_frame.velocity  # east, north; zero for a fast field
    current_north, current_east = data.environment.current_north_east()
    return np.array([frame[1] - current_north, frame[0] - current_east])


def start_drifting(model: WorldModel, data: WorldData) -> None:
    """Where the whole field drifts, set it drifting steadily at the exercise's start (its
    wind and current have blown long before): the frame at the ice's drift velocity."""
    if model.ice.settings.field_drift:
        data.ice_frame.velocity[:] = ice_drift(model, data)


def drift_ice(model: WorldModel, data: WorldData, dt: float) -> np.ndarray:
    """Move the ice's frame by dt s where the whole field drifts, and return the velocity
    the floes drift towards in the ice world (m/s, x east, y north): rest where the field
    drifts (they drift with it), else the ice's drift velocity."""
    s = model.ice.settings
    if not s.field_drift:
        return ice_drift(model, data)
    drift_frame(data.ice_frame, ice_drift(model, data), dt, s.drag_time_s)
    return _STILL


def wash(model: WorldModel, data: WorldData, k: int = 0) -> Callable[[np.ndarray], np.ndarray] | None:
    """The k-th ship's propeller jet as a water velocity field over points of the ice
    world, or None (no thrust, or the wash switched off): ``sim_core.ship.propeller_jet``."""
    m, ship = model.ships[k], data.ships[k]
    if not model.ice.settings.propeller_wash:
        return None
    thrust, _, inflow = propeller_thrust(m, ship.nu[0], ship.nu[1], ship.nu[5], ship.rps)
    north, east, psi = ship.eta[0], ship.eta[1], ship.eta[5]
    origin = ship_to_world(np.array([[m.x_p * m.L, 0.0]]), north, east, psi)[0] - data.ice_frame.offset
    jet = propeller_jet(origin, np.array(ship_vector_to_world((1.0, 0.0), psi)), thrust, inflow, m.d_p, m.d, m.rho)
    return None if jet is None else functools.partial(jet_velocity, jet)
