"""What the ship's sensors read, with the instructor's sensor failures: a gyro frozen at the
heading it had or reading with an offset, a GNSS receiver without a fix or with a position
that jumps, a speed log frozen at the speeds it had. The truth (``WorldEvents.ship``) goes
to the renderers and the station; the readings (``WorldEvents.instruments``) go to the
bridge's instruments. A failure's held values are taken from the ship when it is applied
and the jumps are drawn from the exercise's clock, so a replay reads the same as the run.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from sim_core.frames.geodesy import local_to_geodetic
from sim_core.ship.model import ShipData
from sim_core.ship.outputs import ShipOutputs

SENSOR_MODES = {"gyro": ("ok", "frozen", "offset"), "gnss": ("ok", "lost", "jumping"), "log": ("ok", "frozen")}
JUMP_PERIOD_S = 10.0  # s a jumping GNSS position holds one offset before it jumps again
_JUMP_SEED = 0x1CEB  # the jumps' random stream, with the jump's index (same in every run and replay)


@dataclass(frozen=True)
class SensorFailure:
    """A sensor's new state: ``sensor`` and ``mode`` from ``SENSOR_MODES`` ("ok": repaired);
    ``amount`` is the gyro's offset (rad, + clockwise) or the GNSS jump's size (m); of the
    world's ``ship``-th ship (0: the own ship)."""

    sensor: str
    mode: str
    amount: float = 0.0
    ship: int = 0


@dataclass(frozen=True)
class SensorFaults:
    """The sensors' failures now, with the values a frozen sensor holds."""

    gyro: str = "ok"
    gyro_offset: float = 0.0  # rad
    gyro_held: float = 0.0  # rad, the heading a frozen gyro shows
    gnss: str = "ok"
    gnss_jump: float = 0.0  # m
    log: str = "ok"
    log_held: tuple[float, float] = (0.0, 0.0)  # surge, sway m/s a frozen log shows

    def modes(self) -> dict[str, str]:
        """Each sensor's mode by name."""
        return {"gyro": self.gyro, "gnss": self.gnss, "log": self.log}


def fail_sensor(faults: SensorFaults, failure: SensorFailure, ship: ShipData) -> SensorFaults:
    """The faults after ``failure``; a sensor that freezes holds the ship's value now."""
    if failure.sensor == "gyro":
        return dataclasses.replace(faults, gyro=failure.mode, gyro_offset=failure.amount,
                                   gyro_held=float(ship.eta[5]) % (2.0 * math.pi))
    if failure.sensor == "gnss":
        return dataclasses.replace(faults, gnss=failure.mode, gnss_jump=failure.amount)
    return dataclasses.replace(faults, log=failure.mode, log_held=(float(ship.nu[0]), float(ship.nu[1])))


def gnss_jump(time: float, size: float) -> tuple[float, float]:
    """The jumping position's offset (north, east m) at simulated ``time`` s: ``size`` m in a
    direction drawn anew every ``JUMP_PERIOD_S``."""
    rng = np.random.default_rng((_JUMP_SEED, int(time // JUMP_PERIOD_S)))
    bearing = rng.uniform(0.0, 2.0 * math.pi)
    return size * math.cos(bearing), size * math.sin(bearing)


def sensor_readings(truth: ShipOutputs, faults: SensorFaults, origin: tuple[float, float]) -> ShipOutputs:
    """What the instruments read of ``truth`` with ``faults`` (the field's corner at
    ``origin``, latitude and longitude rad); ``truth`` itself when every sensor is well."""
    if faults == SensorFaults():
        return truth
    changes: dict[str, object] = {}
    if faults.gyro == "frozen":
        changes |= {"heading": faults.gyro_held, "rate_of_turn": 0.0}
    elif faults.gyro == "offset":
        changes["heading"] = (truth.heading + faults.gyro_offset) % (2.0 * math.pi)
    if faults.gnss == "lost":
        changes["fix_valid"] = False
    elif faults.gnss == "jumping":
        dn, de = gnss_jump(truth.time, faults.gnss_jump)
        north, east = truth.north + dn, truth.east + de
        changes |= dict(zip(("latitude", "longitude"), local_to_geodetic(north, east, *origin)),
                        north=north, east=east)
    if faults.log == "frozen":
        changes["speed_longitudinal"], changes["speed_transverse"] = faults.log_held
    return dataclasses.replace(truth, **changes)
