"""Collisions between the exercise's own ships: where two waterlines touch, the impulse of
the impact and the energy it releases into the hulls' structure.

Each hull is a rigid body in the plane with its manoeuvring model's masses: mass plus
added mass in surge, the coupled sway-yaw mass matrix about midship (``ShipModel``). The
impact is the external mechanics of Pedersen and Zhang (P. T. Pedersen and S. Zhang, "On
impact mechanics in ship collisions", Marine Structures 11(10), 1998, pp. 429-449): one
impulse at the contact point, along the contact normal and the tangent, with
  K = sum over both ships of W M^-1 W^T
(W: the normal and tangent as generalized forces of each ship, M: its mass matrix) taking
the impulse to the change of the relative velocity at the point. The impact is fully
plastic, as theirs (restitution 0): the ships stick along the normal, and along the
tangent too where friction suffices (|J_t| <= mu J_n), else they slide with J_t = mu J_n.
The energy lost, E = -(J . v + 1/2 J^T K J) for the relative velocity v before the
impact, is theirs too: what crushes the hulls' structure (their E_xi and E_eta).

The geometry is Chipmunk's (``cpShapesCollide`` on each waterline's convex hull, through
pymunk's C API: pymunk's ``shapes_collide`` asserts where shapes do not touch). Where the
waterlines still overlap after an impact (a ship placed into another by the instructor, a
replayed ship that follows its log whatever it meets), the normal impulse also pushes
them apart at a velocity growing with the overlap: Baumgarte's position correction as
sequential-impulse solvers use it (E. Catto, "Fast and Simple Physics using Sequential
Impulses", Game Developers Conference 2006), capped so that a deep overlap is undone in
seconds, not in one violent step. A ship that follows a logged track (``kinematic``) has
no inverse mass: the other ship alone gives way.

The impulse reaches each ship as its contact load over the next step (J / dt in its
frame, at midship), beside the ice's and the wind's: the step gives it the same velocity
change as the impulse, through the same mass matrix.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pymunk
from pymunk._chipmunk import lib

from sim_core.frames.ship_frame import ship_to_world, ship_vector_to_world, world_vector_to_ship
from sim_core.ship.model import ShipData, ShipModel

FRICTION = 0.3  # steel on steel, sliding: the hulls' friction coefficient mu (an input of Pedersen and Zhang's model)
PUSH_OUT = 0.2  # Catto's Baumgarte factor beta: the push-out velocity undoes this share of the overlap per step
SLOP = 0.05  # m of overlap left alone (so that touching ships do not chatter)
MAX_PUSH_OUT = 0.5  # m/s: the fastest the push-out parts overlapping ships


@dataclass(frozen=True)
class ShipContact:
    """Two own ships touching at the end of a step, or an own ship and a vessel the
    instructor steers, and the impact between them. Own ships by their index in the world
    model (a < b; one index and the vessel's MMSI in ``vessel``); the point and the normal
    in the world (m from the exercise origin; a unit vector from a into b, or into the
    vessel), north and east components."""

    ships: tuple[int, ...]
    north: float  # m
    east: float  # m
    normal: tuple[float, float]  # north, east
    depth: float  # m: how far the waterlines overlap along the normal
    closing_speed: float  # m/s along the normal before the impact (> 0: closing)
    impulse: float  # N s: the normal impulse each ship took
    energy: float  # J: lost in the impact, into the hulls' structure (Pedersen and Zhang's E)
    vessel: int | None = None  # the instructor's vessel's MMSI, where it is the other body


def waterline_overlap(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Where two waterlines overlap, as Chipmunk finds it on their convex hulls.

    Parameters
    ----------
    a, b : (n, 2) float
        The contours in the world, x east, y north, m.

    Returns
    -------
    None where they do not touch; else the unit normal (2,) from a into b, the contact
    point (2,) (the middle of Chipmunk's contact points), both x east, y north, m, and the
    overlap along the normal (m, >= 0).
    """
    if np.any(a.max(axis=0) < b.min(axis=0)) or np.any(b.max(axis=0) < a.min(axis=0)):
        return None
    shapes = [pymunk.Poly(pymunk.Body(body_type=pymunk.Body.STATIC), p.tolist()) for p in (a, b)]
    for shape in shapes:
        shape.cache_bb()
    found = lib.cpShapesCollide(shapes[0]._shape, shapes[1]._shape)
    if found.count == 0:
        return None
    points = [found.points[i] for i in range(found.count)]
    middle = np.mean([[(p.pointA.x + p.pointB.x) / 2, (p.pointA.y + p.pointB.y) / 2] for p in points], axis=0)
    return np.array([found.normal.x, found.normal.y]), middle, max(0.0, -min(p.distance for p in points))


def _rows(ship: ShipModel | None, psi: float, arm: np.ndarray,
          directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The world directions (k, 2; x east, y north) acting at arm (m from midship, world) as
    the ship's generalized loads W (k, 3: X, Y N; N N m, + to starboard, per unit force),
    and W M^-1 (k, 3): the velocity changes (surge, sway m/s; yaw rad/s) per unit impulse
    (zero for a body without a model, which gives way to nothing)."""
    px, py = world_vector_to_ship(tuple(arm), psi)
    w = np.array([[fx, fy, px * fy - py * fx] for fx, fy in (world_vector_to_ship(tuple(d), psi) for d in directions)])
    m_inv = np.zeros((3, 3))
    if ship is not None:
        m_inv[0, 0], m_inv[1:, 1:] = 1.0 / ship.surge_mass, ship.inv_sway_yaw
    return w, w @ m_inv


def point_velocity(ship: ShipData, arm: np.ndarray) -> np.ndarray:
    """The velocity over ground (x east, y north, m/s) of the hull's point at arm (m from
    midship, world): the ship's through the water, its turn, and the current."""
    psi, r = ship.eta[5], ship.nu[5]
    px, py = world_vector_to_ship(tuple(arm), psi)
    east, north = ship_vector_to_world((ship.nu[0] - r * py, ship.nu[1] + r * px), psi)
    return np.array([east + ship.current[1], north + ship.current[0]])


def _impulse(k: np.ndarray, v: np.ndarray, bias: float) -> np.ndarray:
    """The impulse (normal, tangent; N s) on the second ship of a pair that stops the
    relative velocity v (normal, tangent; m/s) at the point, leaving the normal's at
    ``bias`` m/s apart: sticking where friction allows, else sliding (Pedersen and Zhang)."""
    if np.linalg.det(k) <= 0.0:
        return np.zeros(2)
    stick = np.linalg.solve(k, np.array([bias - v[0], -v[1]]))
    if stick[0] > 0.0 and abs(stick[1]) <= FRICTION * stick[0]:
        return stick
    slide = FRICTION * math.copysign(1.0, stick[1])
    along = k[0, 0] + slide * k[0, 1]
    j_n = (bias - v[0]) / (along if along > 0.0 else k[0, 0])
    return np.array([j_n, slide * j_n]) if j_n > 0.0 else np.zeros(2)


def _midship(ship: ShipData) -> np.ndarray:
    """The ship's reference point in the world, x east, y north, m."""
    return np.array([ship.eta[1], ship.eta[0]])


def _impact(models: Sequence[ShipModel | None], ships: Sequence[ShipData], pair: tuple[int, int], kinematic: Sequence[bool],
            overlap: tuple[np.ndarray, np.ndarray, float], dt: float) -> tuple[ShipContact, list[np.ndarray]]:
    """The contact of a pair of ships and the loads (X, Y N; N N m; one per ship of the
    pair) that give each its share of the impulse over dt s. The energy is the impact's
    alone, without the push-out."""
    normal, point, depth = overlap
    basis = np.array([normal, [-normal[1], normal[0]]])  # normal, tangent (x east, y north)
    rows, k, velocity = [], np.zeros((2, 2)), []
    for i in pair:
        arm = point - _midship(ships[i])
        w, w_m = _rows(models[i], ships[i].eta[5], arm, basis)
        rows.append(w)
        velocity.append(point_velocity(ships[i], arm))
        if not kinematic[i]:
            k += w_m @ w.T
    v = basis @ (velocity[1] - velocity[0])
    j = _impulse(k, v, min(MAX_PUSH_OUT, PUSH_OUT * max(0.0, depth - SLOP) / dt))
    plastic = _impulse(k, v, 0.0)
    energy = max(0.0, -(plastic @ v + 0.5 * plastic @ k @ plastic))
    loads = [np.zeros(3) if kinematic[i] else sign * (rows[n].T @ j) / dt
             for n, (i, sign) in enumerate(zip(pair, (-1.0, 1.0)))]
    contact = ShipContact(pair, float(point[1]), float(point[0]), (float(normal[1]), float(normal[0])), depth,
                          float(-v[0]), float(j[0]), float(energy))
    return contact, loads


def ship_collisions(models: Sequence[ShipModel | None], ships: Sequence[ShipData], contours: Sequence[np.ndarray],
                    kinematic: Sequence[bool], dt: float,
                    own: int | None = None) -> tuple[np.ndarray, tuple[ShipContact, ...]]:
    """The ships touching one another, and the contact loads that part them.

    Parameters
    ----------
    models, ships : the bodies, model (None: one without, kinematic) and state, by index:
        the exercise's own ships first, then any vessels the instructor steers
    contours : (n, 2) float each, the waterline in the body's frame (x forward, y
        starboard), m
    kinematic : per body, whether it follows a logged track or a script (and gives way
        to nothing)
    dt : float, the step over which the loads act, s
    own : how many of the bodies are own ships (None: all); no pair of the others is tried

    Returns
    -------
    The loads (bodies, 3): X, Y N in each body's frame, N N m (+ to starboard), at
    midship, over the next step; and every touching pair's ``ShipContact``.
    """
    loads = np.zeros((len(ships), 3))
    contacts = []
    reach = [float(np.hypot(*c.T).max()) for c in contours]
    for a in range(len(ships) if own is None else own):
        for b in range(a + 1, len(ships)):
            if math.dist(ships[a].eta[:2], ships[b].eta[:2]) > reach[a] + reach[b]:
                continue
            world = [ship_to_world(contours[i], ships[i].eta[0], ships[i].eta[1], ships[i].eta[5]) for i in (a, b)]
            overlap = waterline_overlap(*world)
            if overlap is None:
                continue
            contact, (load_a, load_b) = _impact(models, ships, (a, b), kinematic, overlap, dt)
            loads[a] += load_a
            loads[b] += load_b
            contacts.append(contact)
    return loads, tuple(contacts)
