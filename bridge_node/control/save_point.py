"""Save points: rewind and fork. ``icebridge ctl save NAME`` marks the exercise's state at
a step in its session record (``saves/NAME.json``), and ``icebridge run --fork SAVE``
starts a new exercise from it: the record is re-simulated to that step
(``bridge_node.node.fork``) and the new run goes on live from there, with its own record
that names the point it forked from (``fork.json``), so that it too replays exactly.

Why by re-simulation and not by a snapshot of the world's memory: the contact solver keeps
its contacts from step to step (pymunk's arbiters, warm-started impulses), which pymunk's
copy and pickle of a space leave out, so a world restored from a snapshot would go on
differently from the run that was saved. The same orders at the same steps give the same
world, bit for bit (the replay tests check it), and the save point carries the ship's
published state to prove that the re-simulation reached it.
"""
from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path

from bridge_node.common.errors import UserError
from bridge_node.common.input_files import read_input_text
from sim_core.world import WorldEvents

SAVE_NAME = r"^[A-Za-z0-9_-]{1,40}$"
SAVES_FOLDER = "saves"
FORK_FILE = "fork.json"  # in a forked run's session record: the save point it started from
SAVE_FORMAT = "icebridge-save/1"
SAVE_MAX_BYTES = 65536  # a save point is some hundred bytes
_STATE_FIELDS = ("north", "east", "heading", "speed_longitudinal", "speed_transverse", "rate_of_turn",
                 "rudder_angle", "shaft_rps")


@dataclass(frozen=True)
class SaveRequest:
    """Save the exercise's state after this tick's step, as ``saves/NAME.json``."""

    name: str


@dataclass(frozen=True)
class SavePoint:
    """A step of a session record: the record's folder, the step's number and simulated time,
    and the ship's state after it (``state_of``)."""

    record: str
    seq: int
    time: float
    state: dict[str, float]

    def as_json(self) -> str:
        return json.dumps({"format": SAVE_FORMAT, **dataclasses.asdict(self)}, indent=1)


def state_of(events: WorldEvents) -> dict[str, float]:
    """The ship's state a step published, and its floe counts: what a re-simulation must reach."""
    ship = events.ship
    return {**{k: getattr(ship, k) for k in _STATE_FIELDS}, "floes_free": events.floes_free,
            "floes_frozen": events.floes_frozen}


def read_save(path: Path) -> SavePoint:
    """A save point file; UserError naming the file and what is wrong with it."""
    text = read_input_text(path, "save point", SAVE_MAX_BYTES)
    try:
        d = json.loads(text)
        if d.get("format") != SAVE_FORMAT:
            raise ValueError(f"format {d.get('format')!r}, not {SAVE_FORMAT!r}")
        point = SavePoint(str(d["record"]), d["seq"], float(d["time"]), {k: float(v) for k, v in d["state"].items()})
        if not isinstance(point.seq, int) or isinstance(point.seq, bool) or point.seq < 1:
            raise ValueError(f"seq {point.seq!r} is not a step number (1 or more)")
        if not all(math.isfinite(v) for v in (point.time, *point.state.values())):
            raise ValueError("a value that is not finite")
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise UserError(f"{path}: not an IceBridge save point ({exc})") from None
    if not Path(point.record).is_dir():
        raise UserError(f"{path}: the session record it was saved in, {point.record}, is not there")
    return point


def same_state(a: dict[str, float], b: dict[str, float]) -> bool:
    """Whether two ``state_of`` values are one state (a re-simulation is exact: 1e-6 m,
    rad, m/s cover the last digits a JSON round trip keeps)."""
    return a.keys() == b.keys() and all(abs(a[k] - b[k]) <= 1e-6 for k in a)
