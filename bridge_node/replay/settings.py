"""Replay settings (``[replay]`` in the node config)."""
from __future__ import annotations

from pydantic import Field

from sim_core.params import Params


class ReplaySettings(Params):
    """How a logged track is cleaned and stepped. A gap between fixes longer than
    ``max_gap_s`` is bridged by holding the last state; a fix farther from the last good one
    than ``max_speed_kn`` allows is an impossible jump, listed and skipped. Track logs are
    stepped every ``step_s`` (session records keep the step of the run they record)."""

    max_gap_s: float = Field(30.0, gt=0.0, le=86400.0, description="longer gaps are held and listed, s")
    max_speed_kn: float = Field(40.0, gt=0.0, le=200.0, description="faster jumps are impossible, kn")
    step_s: float = Field(0.5, ge=0.005, le=2.0, description="world step of a track replay, s")
