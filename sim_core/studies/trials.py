"""Standard manoeuvring trials (turning circle, zig-zag, crash stop) and IMO MSC.137(76).

Each trial starts the ship steady on a straight course at the test speed (in ice, the speed
the ship settles at with that shaft speed), executes the manoeuvre at t = 0 and records the
track. Heading is kept unwrapped so heading changes over 360 degrees are measured directly.
A trial keeps its own clock (t = 0 at the execute); the ship's state has none.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from sim_core.frames.units import KNOT
from sim_core.ship.model import (
    ShipData,
    ShipModel,
    equilibrium_rps,
    new_ship_data,
    order_rudder,
    order_telegraph,
    step,
)
from sim_core.ship.resistance import LEVEL_ICE, OPEN_WATER

TRIAL_DT = 0.1  # s


@dataclass
class TrialResult:
    """Results (metrics in SI and in ship lengths where IMO states them) and the track."""

    kind: str
    ship: str
    speed: float  # approach speed, m/s
    rudder: float  # rad (0 for a crash stop)
    ice_h: float
    metrics: dict = field(default_factory=dict)
    track: dict = field(default_factory=dict)  # t, north, east, heading, u, v, r, rudder, rpm arrays

    def as_dict(self) -> dict:
        """JSON-ready summary: edge units (knots, degrees) alongside SI."""
        return {
            "trial": self.kind, "ship": self.ship, "approach_speed_kn": round(self.speed / KNOT, 3),
            "rudder_deg": round(math.degrees(self.rudder), 3), "ice_thickness_m": self.ice_h,
            **{k: (round(v, 4) if isinstance(v, float) else v) for k, v in self.metrics.items()},
        }


def imo_limits(length: float, speed: float) -> dict[str, float]:
    """IMO MSC.137(76) limits for a ship of length (m) at test speed (m/s)."""
    lv = length / speed
    first10 = 10.0 if lv < 10.0 else (5.0 + 0.5 * lv if lv < 30.0 else 20.0)
    second10 = 25.0 if lv < 10.0 else (17.5 + 0.75 * lv if lv < 30.0 else 40.0)
    return {
        "L_over_V_s": lv, "advance_L": 4.5, "tactical_diameter_L": 5.0, "initial_turning_L": 2.5,
        "zigzag10_first_overshoot_deg": first10, "zigzag10_second_overshoot_deg": second10,
        "zigzag20_first_overshoot_deg": 25.0, "track_reach_L": 15.0,
    }


def _approach(model: ShipModel, speed: float, ice_h: float) -> ShipData:
    """Steady straight running at the test speed; in ice, settle first with that shaft speed."""
    condition = LEVEL_ICE if ice_h > 0.0 else OPEN_WATER
    data = new_ship_data(model, speed)
    if ice_h > 0.0:
        data.ice_h, data.ice_condition = ice_h, condition
        data.rps = data.rps_order = equilibrium_rps(model, speed, ice_h, condition)
        last = data.nu[0]
        for _ in range(3000):  # up to 30 minutes to settle
            for _ in range(100):
                step(model, data, TRIAL_DT)
            if abs(data.nu[0] - last) < 1e-3:
                break
            last = data.nu[0]
        data.eta[:] = 0.0
    return data


def _run(model: ShipModel, data: ShipData, control: Callable[[ShipData, float], bool], max_time: float) -> dict:
    """Step until control(data, t) returns True or t reaches max_time (s after the execute);
    return the track arrays."""
    rows = []
    t = 0.0
    while True:
        rows.append((t, data.eta[0], data.eta[1], data.eta[5], data.nu[0], data.nu[1],
                     data.nu[5], data.rudder, data.rps * 60.0))
        if control(data, t) or t >= max_time:
            break
        step(model, data, TRIAL_DT)
        t += TRIAL_DT
    arr = np.array(rows)
    names = ("t", "north", "east", "heading", "u", "v", "r", "rudder", "rpm")
    return {k: arr[:, i] for i, k in enumerate(names)}


def _crossing(x: np.ndarray, y: np.ndarray, level: float) -> float:
    """y where x first reaches level (linear interpolation), NaN if never."""
    idx = np.nonzero(x >= level)[0]
    if len(idx) == 0:
        return float("nan")
    i = idx[0]
    if i == 0:
        return float(y[0])
    f = (level - x[i - 1]) / (x[i] - x[i - 1])
    return float(y[i - 1] + f * (y[i] - y[i - 1]))


def _path_length(track: dict) -> np.ndarray:
    d = np.hypot(np.diff(track["north"]), np.diff(track["east"]))
    return np.concatenate([[0.0], np.cumsum(d)])


def turning_trial(model: ShipModel, speed: float, rudder: float, ice_h: float = 0.0,
                  max_time: float = 3600.0) -> TrialResult:
    """Turning circle with rudder (rad, + starboard): advance and transfer at 90 deg,
    tactical diameter at 180 deg, distance run at 10 deg (initial turning), steady speed."""
    data = _approach(model, speed, ice_h)
    v0 = data.nu[0]
    order_rudder(model, data, rudder)
    side = 1.0 if rudder >= 0.0 else -1.0
    track = _run(model, data, lambda d, t: side * d.eta[5] >= 2.0 * math.pi, max_time)
    turned = side * track["heading"]
    L = model.L
    advance = _crossing(turned, track["north"], math.pi / 2)
    transfer = side * _crossing(turned, track["east"], math.pi / 2)
    tactical = side * _crossing(turned, track["east"], math.pi)
    initial = _crossing(turned, _path_length(track), math.radians(10.0))
    metrics = {
        "advance_m": advance, "advance_L": advance / L, "transfer_m": transfer, "transfer_L": transfer / L,
        "tactical_diameter_m": tactical, "tactical_diameter_L": tactical / L,
        "initial_turning_m": initial, "initial_turning_L": initial / L,
        "time_to_90deg_s": _crossing(turned, track["t"], math.pi / 2),
        "time_to_180deg_s": _crossing(turned, track["t"], math.pi),
        "final_speed_kn": float(np.hypot(track["u"][-1], track["v"][-1]) / KNOT),
        "speed_loss_ratio": float(np.hypot(track["u"][-1], track["v"][-1]) / v0) if v0 > 0 else float("nan"),
    }
    return TrialResult("turning", model.particulars.name, v0, rudder, ice_h, metrics, track)


def zigzag_trial(model: ShipModel, speed: float, angle: float, ice_h: float = 0.0,
                 max_time: float = 3600.0) -> TrialResult:
    """Zig-zag angle/angle (rad): rudder to starboard, reversed each time the heading change
    reaches the angle; first and second overshoot angles and their times."""
    data = _approach(model, speed, ice_h)
    v0 = data.nu[0]
    state = {"side": 1.0, "reversals": [], "extremes": []}
    order_rudder(model, data, angle)

    def control(d: ShipData, t: float) -> bool:
        if state["side"] * d.eta[5] >= angle:
            state["reversals"].append(t)
            state["side"] = -state["side"]
            order_rudder(model, d, state["side"] * angle)
        return len(state["reversals"]) >= 3

    track = _run(model, data, control, max_time)
    t, psi = track["t"], track["heading"]
    rev = state["reversals"] + [t[-1]] * (3 - len(state["reversals"]))
    first = psi[(t >= rev[0]) & (t <= rev[1])]
    second = psi[(t >= rev[1]) & (t <= rev[2])]
    metrics = {
        "first_overshoot_deg": math.degrees(first.max() - angle) if len(first) else float("nan"),
        "second_overshoot_deg": math.degrees(-angle - second.min()) if len(second) else float("nan"),
        "first_reversal_s": rev[0], "second_reversal_s": rev[1], "third_reversal_s": rev[2],
        "completed": len(state["reversals"]) >= 3,
    }
    return TrialResult("zigzag", model.particulars.name, v0, angle, ice_h, metrics, track)


def crash_stop_trial(model: ShipModel, speed: float, ice_h: float = 0.0,
                     max_time: float = 3600.0) -> TrialResult:
    """Full-ahead to crash-astern stop, rudder midships: track reach (distance run along the
    track until the ship stops), head reach, lateral deviation, time to stop."""
    data = _approach(model, speed, ice_h)
    v0 = data.nu[0]
    order_telegraph(model, data, "crash_astern")
    track = _run(model, data, lambda d, t: d.nu[0] <= 0.0, max_time)
    reach = float(_path_length(track)[-1])
    stopped = bool(track["u"][-1] <= 0.0)
    metrics = {
        "track_reach_m": reach, "track_reach_L": reach / model.L,
        "head_reach_m": float(track["north"][-1]), "lateral_deviation_m": float(track["east"][-1]),
        "time_to_stop_s": float(track["t"][-1]) if stopped else float("nan"), "stopped": stopped,
    }
    return TrialResult("crash-stop", model.particulars.name, v0, 0.0, ice_h, metrics, track)


def steady_speed(model: ShipModel, rps: float, ice_h: float = 0.0, ice_condition: int = OPEN_WATER,
                 settle_time: float = 1800.0) -> float:
    """Speed (m/s) the ship settles at, straight ahead, with the shaft at rps, by simulation."""
    data = new_ship_data(model, 0.0, rps=rps)
    data.ice_h, data.ice_condition = ice_h, ice_condition
    for _ in range(math.ceil(settle_time)):
        step(model, data, 1.0)
    return float(data.nu[0])
