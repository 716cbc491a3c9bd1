"""Channels of the projection system and the look of the scene (``[render]`` in the config).

A channel is one projector: its view direction relative to the ship's head (yaw, + to
starboard; pitch, + up), its field of view, resolution, eye point (ship frame: x forward,
y to starboard, z up from the waterline, m; or the ship's bridge eye, on the centre line or
at a wing's end), edge-blend bands (degrees at
its left and right edges, where it overlaps its neighbours), and its output: PNG frames,
a window on a given monitor (glfw; full-screen or at the monitor's corner), or ``none``
(render only, for timing).
"""
from __future__ import annotations

import math
from datetime import datetime
from typing import Annotated, Literal

from pydantic import AwareDatetime, Field, model_validator

from sim_core.params import Params, repeated
from sim_core.ship.searchlights import MAX_SEARCHLIGHTS, SearchlightMount, SearchlightState


EyeName = Literal["bridge", "port_wing", "starboard_wing"]
WING_OVERHANG_M = 0.5  # m: a wing's eye outside the beam, to look down the ship's side


def eye_point(eye: list[float] | EyeName, bridge_eye: list[float], beam: float) -> tuple[float, float, float]:
    """A channel's eye in the ship frame (m): its own point, or the ship's bridge eye (x, z)
    on the centre line or at a wing's end."""
    if not isinstance(eye, str):
        return eye[0], eye[1], eye[2]
    y = {"bridge": 0.0, "port_wing": -1.0, "starboard_wing": 1.0}[eye] * (0.5 * beam + WING_OVERHANG_M)
    return bridge_eye[0], y, bridge_eye[1]


class ChannelSettings(Params):
    name: Annotated[str, Field(min_length=1, max_length=32, pattern=r"^[A-Za-z0-9_\-]+$")]
    yaw_deg: float = Field(0.0, ge=-180.0, le=180.0, description="view direction from the bow, + starboard")
    pitch_deg: float = Field(0.0, ge=-60.0, le=60.0, description="+ up")
    hfov_deg: float = Field(60.0, gt=1.0, lt=170.0, description="horizontal field of view")
    vfov_deg: float | None = Field(None, gt=1.0, lt=170.0, description="unset: from hfov and the aspect ratio")
    width: int = Field(1280, ge=16, le=8192)
    height: int = Field(720, ge=16, le=8192)
    eye: Annotated[list[float], Field(min_length=3, max_length=3)] | EyeName = Field(
        "bridge", description="ship frame, m; or the ship's bridge eye: on the centre line or a wing's end")
    blend_left_deg: float = Field(0.0, ge=0.0, le=30.0)
    blend_right_deg: float = Field(0.0, ge=0.0, le=30.0)
    gamma: float = Field(2.2, ge=1.0, le=3.0, description="projector gamma for the blend ramps")
    warp: str | None = Field(None, description="PFM warp grid of the projector on a curved screen "
                                               "(see render/warp.py; relative to the config file, checked when "
                                               "it loads); unset: flat")
    output: Literal["png", "window", "none"] = "png"
    monitor: int = Field(0, ge=0, le=15, description="window output: the monitor's number")
    fullscreen: bool = Field(False, description="window output: full-screen on that monitor")

    @model_validator(mode="after")
    def _blend_fits(self) -> "ChannelSettings":
        if self.blend_left_deg + self.blend_right_deg >= self.hfov_deg:
            raise ValueError(f"blend bands ({self.blend_left_deg} + {self.blend_right_deg} deg) must be "
                             f"narrower than hfov_deg = {self.hfov_deg}")
        return self

    def vfov(self) -> float:
        """Vertical field of view, rad."""
        if self.vfov_deg is not None:
            return math.radians(self.vfov_deg)
        return 2.0 * math.atan(math.tan(math.radians(self.hfov_deg) / 2.0) * self.height / self.width)


def _front_channels() -> list[ChannelSettings]:
    # pitched 5 deg down, so that the bow and the ice beside it are on the screens
    return [ChannelSettings(name="port", yaw_deg=-55.0, pitch_deg=-5.0, blend_right_deg=5.0),
            ChannelSettings(name="centre", yaw_deg=0.0, pitch_deg=-5.0, blend_left_deg=5.0, blend_right_deg=5.0),
            ChannelSettings(name="starboard", yaw_deg=55.0, pitch_deg=-5.0, blend_left_deg=5.0),
            ChannelSettings(name="astern", yaw_deg=180.0, eye=[-60.0, 0.0, 25.0])]




class SearchlightSettings(Params):
    """One of the own ship's searchlights: where it stands, where it points until the
    console trains it, the limits of its mount, its beam."""

    position: list[float] = Field(default_factory=lambda: [20.0, 0.0, 30.0], min_length=3, max_length=3,
                                  description="ship frame, m")
    bearing_deg: float = Field(0.0, ge=-180.0, le=180.0, description="from the bow, + starboard")
    depression_deg: float = Field(8.0, ge=0.0, le=60.0, description="below the horizontal")
    beam_deg: float = Field(8.0, gt=0.5, le=60.0, description="full width of the beam's cone")
    intensity_cd: float = Field(2.0e6, gt=0.0, le=1.0e9, description="luminous intensity on the axis, cd")
    on: bool = Field(True, description="switched on until the console says otherwise")
    train_range_deg: Annotated[list[Annotated[float, Field(ge=-180.0, le=180.0)]], Field(min_length=2, max_length=2)] \
        = Field(default_factory=lambda: [-180.0, 180.0], description="[min, max] bearing the console may order")
    tilt_range_deg: Annotated[list[Annotated[float, Field(ge=-90.0, le=90.0)]], Field(min_length=2, max_length=2)] \
        = Field(default_factory=lambda: [-60.0, 10.0], description="[min, max] elevation the console may order, + up")

    @model_validator(mode="after")
    def _aim_in_range(self) -> "SearchlightSettings":
        for (lo, hi), value, what in ((self.train_range_deg, self.bearing_deg, "bearing_deg"),
                                      (self.tilt_range_deg, -self.depression_deg, "-depression_deg")):
            if not lo <= value <= hi:
                raise ValueError(f"{what} = {value}: outside its range [{lo}, {hi}]")
        return self

    def mount(self) -> SearchlightMount:
        """The light's limits and default aim for the world, rad."""
        return SearchlightMount(SearchlightState(self.on, math.radians(self.bearing_deg),
                                                 -math.radians(self.depression_deg)),
                                (math.radians(self.train_range_deg[0]), math.radians(self.train_range_deg[1])),
                                (math.radians(self.tilt_range_deg[0]), math.radians(self.tilt_range_deg[1])))


class RenderSettings(Params):
    """The projection system and the environment's look."""

    channels: list[ChannelSettings] = Field(default_factory=_front_channels, min_length=1)
    visibility_m: float = Field(8000.0, ge=50.0, le=100_000.0,
                                description="meteorological visibility at the start (the instructor changes it; the "
                                            "channels draw the world's, as published)")
    far_m: float = Field(20_000.0, ge=500.0, le=200_000.0, description="far clip distance")
    start_utc: AwareDatetime = Field(datetime.fromisoformat("2026-04-10T10:40:00+00:00"),
                                     description="date and time (with its UTC offset) the exercise starts at: the "
                                                 "world's exercise clock, which the outputs carry and which, with "
                                                 "the position, sets the sun and the sky")
    searchlights: list[SearchlightSettings] = Field(
        default_factory=list, max_length=MAX_SEARCHLIGHTS,
        description="the own ship's searchlights, in the console's light order 0..3; the console switches and trains them")
    msaa_samples: Literal["auto", 1, 4] = Field(
        "auto", description="multisample anti-aliasing samples per pixel (Mesa llvmpipe offers 4 at most); auto: 4 "
                            "on a GPU, 1 on a software rasteriser (llvmpipe), where 4 cost a third of the frame rate")
    relief_reach_m: float = Field(
        300.0, ge=10.0, le=1.0e7, description="the finest snow relief octave (23 m period) is fetched within this "
        "distance, coarser ones within as many times it as their period is longer; beyond, finer than a pixel row")
    wet_rim_m: float = Field(1.5, ge=0.0, le=10.0, description="width of the wet, darker rim of level ice along "
                                                               "open water (0: none)")
    freeboard_m: float = Field(9.0, ge=0.5, le=40.0, description="own ship's deck height above the waterline")
    lod_distance_m: float = Field(300.0, ge=0.0, le=1.0e6, description="floe side faces drawn within this distance")
    sail_distance_m: float = Field(800.0, ge=0.0, le=1.0e5, description="ridge sails drawn as rubble within this "
                                                                        "distance; beyond, flat")
    reflection_distance_m: float = Field(150.0, ge=0.0, le=1.0e6, description="floes' reflections in the sea drawn "
                                                                             "within this distance (0: none)")
    processes: Literal["local", "none"] = Field(
        "local", description="local: icebridge run starts a render process per channel group; none: render nothing")
    groups: list[list[str]] | None = Field(
        None, description="channels per render process (one display/GPU each); unset: all channels in one")
    fps: float = Field(60.0, ge=1.0, le=240.0, description="frame rate of render processes with window channels")
    headless_fps: float = Field(5.0, ge=1.0, le=60.0, description="frame rate of headless render processes")
    niceness: int = Field(
        10, ge=0, le=19, description="scheduling niceness of render processes: the physics loop comes first for the CPU")

    @model_validator(mode="after")
    def _unique_names(self) -> "RenderSettings":
        doubled = repeated([c.name for c in self.channels])
        if doubled:
            raise ValueError(f"channel names must be unique, repeated: {doubled}")
        grouped = [n for g in self.groups or [] for n in g]
        unknown = sorted(set(grouped) - {c.name for c in self.channels})
        if unknown or repeated(grouped) or any(not g for g in self.groups or []):
            raise ValueError(f"groups: each channel at most once, no empty group; unknown: {unknown}, "
                             f"repeated: {repeated(grouped)}")
        return self
