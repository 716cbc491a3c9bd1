"""Cameras of the projector channels: the ship's pose and a channel's view direction and
field of view as view and projection matrices (world x east, y north, z up, metres)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bridge_node.render.settings import ChannelSettings
from sim_core.frames.ship_frame import ship_rotation
from sim_core.ship.outputs import ShipOutputs

NEAR = 0.5  # m


def set_matrix(uniform, m: np.ndarray) -> None:
    """Write a row-major numpy 4x4 matrix to a GLSL mat4 uniform (column-major)."""
    uniform.write(np.ascontiguousarray(m.T, dtype="f4").tobytes())


def ship_matrix(north: float, east: float, psi: float, heave: float = 0.0, pitch: float = 0.0,
                roll: float = 0.0) -> np.ndarray:
    """Ship frame (x forward, y starboard, z up) to world (x east, y north, z up), 4x4; the
    ship heaved up by ``heave`` m, pitched bow up by ``pitch`` rad and rolled starboard
    down by ``roll`` rad (yaw, then pitch, then roll)."""
    c, s = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    attitude = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, cr, sr], [0.0, -sr, cr]])
    m = np.eye(4)
    m[:2, :2] = ship_rotation(psi)
    m[:3, :3] = m[:3, :3] @ attitude
    m[:3, 3] = east, north, heave
    return m


def outputs_matrix(ship: ShipOutputs, ice_offset: np.ndarray | tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """``ship_matrix`` of a ship's published outputs (its place, heading, heave, pitch and
    roll), into the ice's frame that lies at ice_offset (m, x east, y north) in the world."""
    return ship_matrix(ship.north - ice_offset[1], ship.east - ice_offset[0], ship.heading, ship.heave, ship.pitch,
                       ship.roll)


@dataclass(frozen=True)
class Camera:
    eye: np.ndarray  # world m
    view: np.ndarray
    proj: np.ndarray

    @property
    def view_proj(self) -> np.ndarray:
        return self.proj @ self.view


def channel_camera(channel: ChannelSettings, eye: tuple[float, float, float], north: float, east: float, psi: float,
                   far: float, heave: float = 0.0, pitch: float = 0.0, roll: float = 0.0) -> Camera:
    """The channel's camera at `eye` (ship frame, m) for the ship at (north, east) m with
    heading psi (rad, from north), heaved up ``heave`` m, pitched bow up ``pitch`` rad and
    rolled starboard down ``roll`` rad: the eye and its view move with the ship, as a
    trainee's on its bridge."""
    return camera_on(channel, eye, ship_matrix(north, east, psi, heave, pitch, roll), far)


def camera_on(channel: ChannelSettings, eye: tuple[float, float, float], to_world: np.ndarray, far: float) -> Camera:
    """The channel's camera at `eye` (ship frame, m) on a ship placed by ``to_world`` (its
    ``ship_matrix``, made once per frame for every channel). Plain floats where numpy's
    per-call cost on 3-vectors would be most of the time (a frame makes one per channel)."""
    rot = to_world[:3, :3]
    eye = rot @ eye + to_world[:3, 3]
    yaw, el = math.radians(channel.yaw_deg), math.radians(channel.pitch_deg)
    f = (rot @ (math.cos(yaw) * math.cos(el), math.sin(yaw) * math.cos(el), math.sin(el))).tolist()
    up = rot[:, 2].tolist()
    r = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    norm = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    r = [c / norm for c in r]
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    view = np.array([[*r, 0.0], [*u, 0.0], [-f[0], -f[1], -f[2], 0.0], [0.0, 0.0, 0.0, 1.0]])
    view[:3, 3] = -view[:3, :3] @ eye
    tx, ty = math.tan(math.radians(channel.hfov_deg) / 2), math.tan(channel.vfov() / 2)
    proj = np.array([[1 / tx, 0, 0, 0], [0, 1 / ty, 0, 0],
                     [0, 0, (far + NEAR) / (NEAR - far), 2 * far * NEAR / (NEAR - far)], [0, 0, -1, 0]])
    return Camera(eye, view, proj)


_BOX_CORNERS = np.stack(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij"), -1).reshape(8, 3)


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The eight corners of axis-aligned boxes (n, 3) lo..hi, world m, homogeneous: (n, 8, 4)."""
    pts = lo[:, None, :] + _BOX_CORNERS[None] * (hi - lo)[:, None, :]
    return np.concatenate([pts, np.ones(pts.shape[:2] + (1,))], axis=-1)


def visible_corners(view_proj: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Which boxes (their ``box_corners``, (n, 8, 4)) may be seen: False only when all eight
    corners lie outside the same clip plane."""
    clip = corners @ view_proj.T
    xyz, w = clip[..., :3], clip[..., 3:]
    return ~((xyz < -w).all(axis=1).any(axis=1) | (xyz > w).all(axis=1).any(axis=1))


def visible_boxes(view_proj: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Which axis-aligned boxes (n, 3) corners lo..hi, world m, may be seen: False only when
    all eight corners lie outside the same clip plane."""
    return visible_corners(view_proj, box_corners(lo, hi))
