"""The own ships' failures as the station knows them: each ship's steering pumps, engine
power and sensors, from the failure commands applied on the stream and from the node's
status replies (which know those applied before the station joined), and the alarms they
raise. Ship 0 is the first (``[ship]``); an alarm of ship k > 0 is named as the event log
names its commands (``ship k: ...``)."""
from __future__ import annotations

from dataclasses import dataclass, field

from sim_core.instructor import EngineFailure, SteeringFailure
from sim_core.ship.sensors import SensorFailure

# (sensor, mode) -> what the instruments show: an alarm's text
SENSOR_TEXT = {("gyro", "frozen"): "gyro frozen", ("gyro", "offset"): "gyro offset", ("gnss", "lost"): "GNSS fix lost",
               ("gnss", "jumping"): "GNSS position jumping", ("log", "frozen"): "speed log frozen"}
FAILURES = (SteeringFailure, EngineFailure, SensorFailure)


@dataclass
class ShipFailures:
    """One own ship's failures, as the last failure seen (stream or status) set them."""

    steering: int = 2  # steering pumps working
    power: float = 1.0  # share of the engine's power available
    sensors: dict[str, str] = field(default_factory=lambda: {"gyro": "ok", "gnss": "ok", "log": "ok"})
    seq: int = -1  # the step of the last failure of this ship seen on the stream

    def note(self, command: SteeringFailure | EngineFailure | SensorFailure, seq: int) -> None:
        """Keep the state a failure command applied at step ``seq`` leaves."""
        if isinstance(command, SteeringFailure):
            self.steering = command.pumps
        elif isinstance(command, EngineFailure):
            self.power = command.power_share
        else:
            self.sensors = {**self.sensors, command.sensor: command.mode}
        self.seq = seq

    def take(self, fields: dict) -> None:
        """Take a status reply's failure fields of this ship; those it lacks stay."""
        self.steering = fields.get("steering_pumps", self.steering)
        self.power = fields.get("power_percent", self.power * 100.0) / 100.0
        self.sensors = {**self.sensors, **fields.get("sensors", {})}

    def alarms(self) -> list[str]:
        """The alarms these failures raise."""
        active = []
        if self.steering < 2:
            active.append("steering gear: " + ("rudder stuck (both pumps failed)" if self.steering == 0
                                               else "one pump failed (half rate)"))
        if self.power < 1.0:
            active.append("engine: blackout" if self.power <= 0.0 else f"engine: {self.power * 100:.0f} % power")
        return active + ["sensor: " + SENSOR_TEXT.get((k, mode), f"{k} {mode}") for k, mode in self.sensors.items()
                         if mode != "ok"]

    def panel(self) -> dict:
        """The failures as the page shows them."""
        return {"pumps_failed": 2 - self.steering, "power_percent": round(self.power * 100.0, 1),
                "sensors": self.sensors}


class FleetFailures:
    """Every own ship's failures; a ship is known from its first failure or status reply."""

    def __init__(self) -> None:
        self.ships = [ShipFailures()]

    def ship(self, k: int) -> ShipFailures:
        """Ship k's failures (all working until seen otherwise)."""
        while len(self.ships) <= k:
            self.ships.append(ShipFailures())
        return self.ships[k]

    def note(self, command: object, seq: int) -> None:
        """Keep what a command applied at step ``seq`` does to its ship, if it is a failure."""
        if isinstance(command, FAILURES):
            self.ship(command.ship).note(command, seq)

    def rejoined(self) -> None:
        """The stream was joined anew: the next status reply is taken for every ship."""
        for ship in self.ships:
            ship.seq = -1

    def take(self, status: dict) -> None:
        """Take a status reply's failures of each ship (the first ship's at its top level,
        the others' in ``other_ships``) where it is newer than the last failure seen on the
        stream."""
        seq = status.get("seq", -1)
        for k, fields in enumerate([status, *status.get("other_ships", [])]):
            if seq >= self.ship(k).seq:
                self.ships[k].take(fields)

    def alarms(self) -> list[str]:
        """Every ship's failure alarms, another ship's after its number."""
        return [(f"ship {k}: " if k else "") + text for k, ship in enumerate(self.ships) for text in ship.alarms()]

    def panel(self) -> list[dict]:
        """Each ship's failures as the page shows them, the first ship first."""
        return [ship.panel() for ship in self.ships]
