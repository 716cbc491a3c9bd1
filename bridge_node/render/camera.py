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


def outputs_matrix(ship: ShipOutputs) -> np.ndarray:
    """``ship_matrix`` of a ship's published outputs: its place, heading, heave, pitch and roll."""
    return ship_matrix(ship.north, ship.east, ship.heading, ship.heave, ship.pitch, ship.roll)


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
    to_world = ship_matrix(north, east, psi, heave, pitch, roll)
    eye = (to_world @ np.array([*eye, 1.0]))[:3]
    yaw, el = math.radians(channel.yaw_deg), math.radians(channel.pitch_deg)
    f = to_world[:3, :3] @ [math.cos(yaw) * math.cos(el), math.sin(yaw) * math.cos(el), math.sin(el)]
    r = np.cross(f, to_world[:3, 2])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = r, u, -f
    view[:3, 3] = -view[:3, :3] @ eye
    tx, ty = math.tan(math.radians(channel.hfov_deg) / 2), math.tan(channel.vfov() / 2)
    proj = np.array([[1 / tx, 0, 0, 0], [0, 1 / ty, 0, 0],
                     [0, 0, (far + NEAR) / (NEAR - far), 2 * far * NEAR / (NEAR - far)], [0, 0, -1, 0]])
    return Camera(eye, view, proj)


def visible_boxes(view_proj: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Which axis-aligned boxes (n, 3) corners lo..hi, world m, may be seen: False only when
    all eight corners lie outside the same clip plane."""
    corners = np.stack(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij"), -1).reshape(8, 3)
    pts = lo[:, None, :] + corners[None] * (hi - lo)[:, None, :]
    clip = np.concatenate([pts, np.ones(pts.shape[:2] + (1,))], axis=-1) @ view_proj.T
    x, y, z, w = clip[..., 0], clip[..., 1], clip[..., 2], clip[..., 3]
    outside = [x < -w, x > w, y < -w, y > w, z < -w, z > w]
    return ~np.any([o.all(axis=1) for o in outside], axis=0)
