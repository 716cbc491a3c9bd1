"""The state stream's message format, from the codec itself: a message is encoded from an
empty step (no floes) and its frames described, so the page shows what goes on the wire."""
from __future__ import annotations

import dataclasses
import json

import numpy as np

from bridge_node.stream.codec import FRAME_NAMES, MAX_ROWS, TOPIC, encode
from bridge_node.stream.world_view import TRAFFIC_DTYPE
from sim_core.ice.bending import CRACK_EVENT
from sim_core.scene.scene import RETILED
from sim_core.scene.switches import FROZEN_FLOE_EVENT, PlacedTiles
from sim_core.ship.outputs import ShipOutputs
from sim_core.world import WorldEvents

_NO_ROWS = np.zeros(0, dtype=np.int64)


def _empty_events() -> WorldEvents:
    """A step that placed nothing and moved no floe."""
    placed = PlacedTiles(*[np.zeros((0, 2)) if f.name == "corner" else _NO_ROWS for f in dataclasses.fields(PlacedTiles)])
    ship = ShipOutputs(**{f.name: 0.0 for f in dataclasses.fields(ShipOutputs) if f.name not in ("searchlights",
                                                                                                  "fix_valid")})
    return WorldEvents(seq=1, time=0.0, ship=ship, placed=placed, thawed=_NO_ROWS, frozen=_NO_ROWS,
                       broken_by_hull=_NO_ROWS, broken_by_contact=_NO_ROWS, floe_rows=_NO_ROWS,
                       floe_pose=np.zeros((0, 6)), floe_status=np.zeros(0, np.uint8), floes_free=0, floes_frozen=0,
                       ice_load=np.zeros(3), rejected=())


def _dtype_text(dtype: np.dtype) -> str:
    return ", ".join(f"`{name}` {dtype.fields[name][0].str}" for name in dtype.names) if dtype.names else \
        f"`{dtype.str}`"


def stream_reference() -> str:
    """The Markdown page of the state stream's message."""
    frames = encode(_empty_events())
    header = json.loads(frames[1])
    names = FRAME_NAMES
    lines = ["# State stream message", "", "Made from the codec (`bridge_node/stream/codec.py`) when the site is "
             "built. One ZeroMQ multipart message per step (the Clone pattern: a late joiner asks the snapshot "
             "socket for the whole state, then follows the updates):", "",
             "| frame | content |", "|---|---|", f"| 0 | the topic `{TOPIC.decode()}` |",
             "| 1 | the header, JSON (below) |"]
    lines += [f"| {2 + i} | `{name}`: raw array, dtype and shape in the header's `arrays` |"
              for i, name in enumerate(names)]
    lines += [f"| {2 + len(names)} | the traffic: records of {_dtype_text(TRAFFIC_DTYPE)} |", "",
              f"`frozen_floes` records: {_dtype_text(FROZEN_FLOE_EVENT)}. `cracked` records (intact cells "
              f"cracked, with their crack labels): {_dtype_text(CRACK_EVENT)}. `retiled` records (tiles the "
              f"instructor gave other ice, and their classes; the last array, which a recording made before it "
              f"lacks): {_dtype_text(RETILED)}. Row, placement and tile numbers are "
              f"below {MAX_ROWS}; a message outside a view's bounds is refused and counted.", "",
              "| header key | JSON type | example (an empty step) |", "|---|---|---|"]
    lines += [f"| `{key}` | {type(value).__name__} | `{json.dumps(value)[:80]}` |" for key, value in header.items()]
    lines += ["", "`ship` keys (SI: m, m/s, rad, rad/s, rev/s, N; `utc` unix s): "
              + ", ".join(f"`{k}`" for k in header["ship"]) + ".",
              "`environment` keys: " + ", ".join(f"`{k}`" for k in header["environment"]) + ".",
              "`ice_offset`: where the ice's own frame lies in the world (m, x east, y north; it moves where "
              "the whole field drifts): floe poses, tile corners and frozen floes are in that frame."]
    return "\n".join(lines) + "\n"
