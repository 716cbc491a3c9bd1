"""Replay settings (``[replay]`` in the node config)."""
from __future__ import annotations

from pydantic import Field

from sim_core.params import Params

MAX_GAP_RUN_M = 1000.0  # m: the default of ``max_gap_run_m``
GAP_SPEED_TOLERANCE = 0.25  # the default of ``gap_speed_tolerance``


class ReplaySettings(Params):
    """How a logged track is cleaned and stepped. Fixes further apart than ``max_gap_s``
    are a gap: it is interpolated (cubic Hermite on the logged speed and course) unless the
    vessel would run more than ``max_gap_run_m`` through it at its logged speed, or the
    interpolated speed leaves the logged speeds at its ends by more than
    ``gap_speed_tolerance`` (the data contradicts itself); such gaps are bridged by holding
    the last state and listed. A fix farther from the last good one than ``max_speed_kn``
    allows is an impossible jump, listed and skipped. Track logs are stepped every
    ``step_s`` (session records keep the step of the run they record).

    Defaults: a ship at 20 kn reporting once a minute runs 620 m between reports, one at
    anchor every 3 min a few metres, so 1000 m bridges the public AIS archives (one report
    a minute) at any usual speed and holds a 10 min dropout at 6 kn; 0.25 lets the
    interpolated speed dip 5 % in a U-turn within one gap (a cubic's speed through a half
    circle) with margin, and flags positions that need 25 % more or less than logged."""

    max_gap_s: float = Field(30.0, gt=0.0, le=86400.0,
                             description="fixes further apart are a gap: interpolated if consistent, else held, s")
    max_gap_run_m: float = Field(MAX_GAP_RUN_M, ge=0.0, le=100_000.0,
                                 description="a gap the vessel runs further through at its logged speed is held, m")
    gap_speed_tolerance: float = Field(GAP_SPEED_TOLERANCE, ge=0.0, le=5.0,
                                       description="interpolated speed off the logged by more: gap held, fraction")
    max_speed_kn: float = Field(40.0, gt=0.0, le=200.0, description="faster jumps are impossible, kn")
    step_s: float = Field(0.5, ge=0.005, le=2.0, description="world step of a track replay, s")
