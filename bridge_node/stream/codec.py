"""``WorldEvents`` as ZeroMQ multipart frames: a small JSON header for the scalars, then
each array as its raw bytes (no pickle, no JSON for bulk data).

Frames: ``[TOPIC, header, array, array, ..., traffic]``. The header names each array's
dtype and shape in frame order. Floe poses travel as float32 (what the renderer uses; 0.1 mm
at 1 km) and row numbers as int32; frozen floes as ``FROZEN_FLOE_EVENT`` records. ``input_time`` is the monotonic time (s) of the newest
console order that went into the step, or None. The last frame is the whole traffic picture
at the step (``TRAFFIC_DTYPE`` rows; a few vessels, so every message carries all of them).
The tiles given other ice (``RETILED`` records) are the last array; a recording made before
the instructor could lay ice lacks it, and reads as none. The other own ships' reports
(``WorldEvents.others``) travel in the header: a few ships.

A decoded message is checked against the bounds of a view before anyone applies it (render
PCs may read the stream off the bridge network): row, placement and tile numbers within
``MAX_ROWS``, arrays of one step of one length, poses and the ship's numbers finite, the
JSON header shallow and its numbers in range. Anything else is a ``CodecError``, which the
subscribers and the publisher count and drop.
"""
from __future__ import annotations

import dataclasses
import json
import math

import numpy as np

from bridge_node.control.commands import CommandError, command_from_record, command_record
from bridge_node.stream.world_view import TRAFFIC_DTYPE
from sim_core.environment import Environment
from sim_core.ice.bending import CRACK_EVENT
from sim_core.ice.floes import FROZEN_CRACK
from sim_core.ship.model import OrderRejection
from sim_core.ship.outputs import ShipOutputs
from sim_core.scene.scene import RETILED
from sim_core.scene.switches import FROZEN_FLOE_EVENT, PlacedTiles
from sim_core.fleet import ShipReport
from sim_core.ice.hull_bodies import MAX_HULLS
from sim_core.world import WorldEvents

MAX_ROWS = 1 << 24  # row, placement and tile numbers are below this: a view allocates per row
TOPIC = b"w"
HEARTBEAT = b"h"  # [HEARTBEAT, b"<seq>"]: the last sequence number published
_PLACED = [f.name for f in dataclasses.fields(PlacedTiles)]
_ARRAYS = ("thawed", "frozen", "broken_by_hull", "broken_by_contact", "floe_rows", "floe_pose", "floe_status",
           "ice_load", "frozen_floes", "cracked", "frozen_cracks", "retiled")
FRAME_NAMES = (*_PLACED, *_ARRAYS)  # the array frames, in order, after the header
_WIRE = {"floe_pose": np.float32, "floe_rows": np.int32, "broken_by_hull": np.int32,
         "broken_by_contact": np.int32, "frozen_floes": FROZEN_FLOE_EVENT,
         "cracked": CRACK_EVENT, "frozen_cracks": FROZEN_CRACK, "retiled": RETILED}


class CodecError(ValueError):
    """Frames that are not a state message of this version."""


def encode(events: WorldEvents, input_time: float | None = None, traffic: np.ndarray | None = None) -> list[bytes]:
    """Frames of one state message; ``traffic`` the other vessels (None: none)."""
    traffic = np.zeros(0, dtype=TRAFFIC_DTYPE) if traffic is None else np.ascontiguousarray(traffic, TRAFFIC_DTYPE)
    arrays = [np.ascontiguousarray(getattr(events.placed, name)) for name in _PLACED]
    arrays += [np.ascontiguousarray(getattr(events, name), dtype=_WIRE.get(name)) for name in _ARRAYS]
    header = {
        "seq": events.seq, "time": events.time, "snapshot": events.snapshot, "input_time": input_time,
        "ship": dataclasses.asdict(events.ship), "floes_free": events.floes_free,
        "floes_frozen": events.floes_frozen, "rejected": [dataclasses.asdict(r) for r in events.rejected],
        "environment": dataclasses.asdict(events.environment), "ice_offset": list(events.ice_offset),
        "commands": [command_record(c) for c in events.commands],
        "others": [{"outputs": dataclasses.asdict(o.outputs), "ice_load": [float(v) for v in o.ice_load],
                    "rejected": [dataclasses.asdict(r) for r in o.rejected]} for o in events.others],
        "arrays": [[a.dtype.str, list(a.shape)] for a in arrays],
    }
    return [TOPIC, json.dumps(header).encode(), *(a.tobytes() for a in arrays), traffic.tobytes()]


def _environment(fields: dict) -> Environment:
    """The environment a header carries; CodecError for a field missing, unknown or out of
    its range (a visibility that is no positive distance, a speed below zero, a non-finite
    number)."""
    environment = Environment(**fields)
    numbers = [v for k, v in fields.items() if k != "frozen"]
    if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in numbers) or \
            not isinstance(environment.frozen, bool) or environment.visibility <= 0.0 or \
            environment.wind_speed < 0.0 or environment.current_speed < 0.0:
        raise CodecError(f"malformed state message: environment {fields}")
    return environment


def _ice_offset(value: object) -> tuple[float, float]:
    """The ice frame's offset a header carries: two finite numbers (m); CodecError else."""
    if not (isinstance(value, list) and len(value) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)):
        raise CodecError(f"malformed state message: ice offset {value!r}")
    return float(value[0]), float(value[1])


def _other_ship(fields: dict) -> ShipReport:
    """Another own ship's report a header carries; CodecError for an ice load that is not
    three numbers."""
    load = np.array(fields["ice_load"], dtype=float)
    if load.shape != (3,):
        raise CodecError(f"malformed state message: another ship's ice load {fields['ice_load']!r}")
    return ShipReport(ShipOutputs.from_dict(fields["outputs"]), load,
                      tuple(OrderRejection(**r) for r in fields["rejected"]))


def decode(frames: list) -> tuple[WorldEvents, float | None, np.ndarray]:
    """The events, input time and traffic of a state message; raises CodecError for
    anything else."""
    try:
        if bytes(frames[0]) != TOPIC:
            raise CodecError("not a state message")
        header = json.loads(bytes(frames[1]))
        specs = header["arrays"]
        if len(specs) not in (len(FRAME_NAMES), len(FRAME_NAMES) - 1) or len(frames) != 3 + len(specs):
            raise CodecError("wrong number of frames")
        dtypes = [np.dtype(d) for d, _ in specs]
        if any(d.kind not in "iufV" or d.hasobject for d in dtypes):  # numbers and raw records only
            raise CodecError("malformed state message: an array of a type the stream does not carry")
        arrays = [np.frombuffer(f, dtype=d).reshape(shape) for f, d, (_, shape) in zip(frames[2:-1], dtypes, specs)]
        traffic = np.frombuffer(frames[-1], dtype=TRAFFIC_DTYPE).copy()  # writable, as WorldView.traffic starts
        placed = PlacedTiles(*arrays[:len(_PLACED)])
        named = dict(zip(_ARRAYS, arrays[len(_PLACED):]))
        named["frozen_floes"] = named["frozen_floes"].view(FROZEN_FLOE_EVENT)  # records travel as raw bytes
        named["cracked"] = named["cracked"].view(CRACK_EVENT)
        named["frozen_cracks"] = named["frozen_cracks"].view(FROZEN_CRACK)
        named["retiled"] = named["retiled"].view(RETILED) if "retiled" in named else np.zeros(0, dtype=RETILED)
        events = WorldEvents(
            seq=int(header["seq"]), time=float(header["time"]), ship=ShipOutputs.from_dict(header["ship"]), placed=placed,
            floes_free=int(header["floes_free"]), floes_frozen=int(header["floes_frozen"]),
            rejected=tuple(OrderRejection(**r) for r in header["rejected"]), snapshot=bool(header["snapshot"]),
            environment=_environment(header["environment"]),
            ice_offset=_ice_offset(header.get("ice_offset", [0.0, 0.0])),  # none in recordings before the drift
            commands=tuple(command_from_record(c) for c in header["commands"]),
            others=tuple(_other_ship(o) for o in header.get("others", [])),  # none before several ships
            **{k: (v.astype(np.int64) if k in _WIRE and v.dtype.kind == "i" else v) for k, v in named.items()})
        input_time = header["input_time"]
    except CodecError:
        raise
    except CommandError as exc:
        raise CodecError(f"malformed state message: {exc}") from None
    except (ValueError, KeyError, TypeError, IndexError, OverflowError) as exc:
        raise CodecError(f"malformed state message: {exc}") from None
    except RecursionError:
        raise CodecError("malformed state message: JSON nested too deep") from None
    _check_bounds(events, input_time)
    return events, input_time, traffic


def _good_record(record: object) -> bool:
    """Every field of a ship's outputs (or a searchlight's state) of its type: bool flags
    true or false, numbers finite (not text, not a flag), the lights each good."""
    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if f.name == "searchlights":
            good = isinstance(value, tuple) and all(_good_record(light) for light in value)
        elif f.type in ("bool", bool):
            good = isinstance(value, bool)
        else:
            good = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        if not good:
            return False
    return True


def _check_bounds(events: WorldEvents, input_time: object) -> None:
    """CodecError unless the message fits a view: numbers in range, arrays consistent."""
    p = events.placed
    counts = {len(getattr(p, name)) for name in _PLACED}
    rows = [events.floe_rows, events.broken_by_hull, events.broken_by_contact, p.row_start, p.row_start + p.row_count,
            p.tile, p.placement, events.thawed, events.frozen, events.frozen_floes["placement"].astype(np.int64),
            events.cracked["row"].astype(np.int64), events.frozen_cracks["placement"].astype(np.int64),
            events.frozen_floes["cell"].astype(np.int64), events.frozen_cracks["cell"].astype(np.int64),
            events.retiled["tile"].astype(np.int64)]
    m = len(events.floe_rows)
    problems = [
        len(counts) != 1 and "placed tiles of different lengths",
        any(len(a) and (a.min() < 0 or a.max() > MAX_ROWS) for a in rows)
        and "a row, placement, tile or cell number out of range",
        (events.floe_pose.shape != (m, 6) or events.floe_status.shape != (m,)) and "floe arrays of different lengths",
        p.corner.shape != (len(p.tile), 2) and "tile corners of the wrong shape",
        not (np.isfinite(events.floe_pose).all() and np.isfinite(p.corner).all()
             and np.isfinite(events.frozen_floes["pose"]).all()) and "a pose that is not finite",
        not all(math.isfinite(v) for v in (events.time, *events.ice_load, *(v for o in events.others for v in o.ice_load)))
        and "a time or load that is not finite",
        not all(_good_record(s) for s in (events.ship, *(o.outputs for o in events.others)))
        and "a ship value that is not a finite number, or a flag not true or false",
        input_time is not None and not (isinstance(input_time, float) and math.isfinite(input_time))
        and "an input time that is not a finite number",
        events.ice_load.shape != (3,) and "an ice load of the wrong shape",
        len(events.others) >= MAX_HULLS and f"{len(events.others) + 1} ships, more than a world holds ({MAX_HULLS})",
    ]
    problem = next((found for found in problems if found), None)
    if problem:
        raise CodecError(f"malformed state message: {problem}")
