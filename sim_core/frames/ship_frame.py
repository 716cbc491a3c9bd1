"""The one rotation between the ship frame and the ice world, each way.

Ship frame: x forward, y to starboard (MMG, heading psi clockwise from north). World: x
east, y north, angles counter-clockwise from east. A ship-frame vector (a, b) points
a * (sin psi, cos psi) + b * (cos psi, -sin psi) in the world; the ship's heading is the
world angle pi/2 - psi. Everything that turns vectors or points between the two frames
(the hull contour, the hull's velocity, the ice load, the renderer's ship matrix, the
instruments' course over ground) goes through these functions.
"""
from __future__ import annotations

import math

import numpy as np


def ship_rotation(psi: float) -> np.ndarray:
    """2x2 matrix taking ship-frame vectors (x forward, y starboard) to world (x east,
    y north) for heading psi (rad, clockwise from north); its transpose goes back."""
    s, c = math.sin(psi), math.cos(psi)
    return np.array([[s, c], [c, -s]])


def ship_to_world(points: np.ndarray, north: float, east: float, psi: float) -> np.ndarray:
    """Ship-frame points (n, 2), m, of a ship at (north, east) m with heading psi (rad), to
    world (x east, y north), m."""
    return np.asarray(points, dtype=float) @ ship_rotation(psi).T + np.array([east, north])


def ship_vector_to_world(vector: tuple[float, float], psi: float) -> tuple[float, float]:
    """One ship-frame vector (forward, starboard) as world (east, north) components."""
    s, c = math.sin(psi), math.cos(psi)
    a, b = vector
    return a * s + b * c, a * c - b * s


def world_vector_to_ship(vector: tuple[float, float], psi: float) -> tuple[float, float]:
    """One world vector (east, north) as ship-frame components (forward, starboard)."""
    s, c = math.sin(psi), math.cos(psi)
    x, y = vector
    return x * s + y * c, x * c - y * s


def world_heading(psi: float) -> float:
    """World angle (rad, CCW from east) of a ship heading psi (rad, clockwise from north)."""
    return 0.5 * math.pi - psi
