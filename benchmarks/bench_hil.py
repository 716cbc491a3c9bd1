"""Benchmark: time from a console action to the expectation being met, per link kind.

For each console link kind (CAN on slcan over a pty pair, NMEA 0183 on a pty pair, Modbus
TCP on 127.0.0.1) the bench starts the node (``icebridge run``, render off) and plays one
scenario of REPS helm steps between -1 and +1 deg starboard, each expected to have moved
the rudder angle read back on the console's own link 0.2 deg towards the new side (0.08 s
of steering gear at 2.5 deg/s): the time is the transport delay console -> node -> ship ->
instrument output -> console, with the wait for the output's next period (10 Hz on CAN and
NMEA, the 20 Hz poll on Modbus) and a tick of the node (30 Hz). Prints median, p99 and max
per kind, and the steps not met within the 1.5 s window.
Run: .venv/bin/python benchmarks/bench_hil.py [REPS]
"""
from __future__ import annotations

import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np

from bridge_node.hil.bench import Bench
from bridge_node.hil.scenario import Scenario

STEP_S = 1.5  # s between helm steps
NODE = ('[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 400.0\nthickness = 0.3\n'
        '[paths]\ncache_dir = "{cache}"\n')


def steps(reps: int) -> Scenario:
    """REPS alternating helm steps, each with its expectation on the primary end."""
    actions, expect = [{"at_s": 0.0, "helm_deg": -1.0}], []
    for k in range(1, reps + 1):
        side = 1.0 if k % 2 else -1.0
        actions.append({"at_s": k * STEP_S, "helm_deg": side})
        expect.append({"after_s": k * STEP_S, "within_s": STEP_S, "quantity": "rudder_angle", "link": "primary",
                       "min": min(-0.8 * side, 1.5 * side), "max": max(-0.8 * side, 1.5 * side)})
    return Scenario.model_validate({"name": "helm steps", "actions": actions, "expect": expect})


def main() -> None:
    reps = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    with tempfile.TemporaryDirectory() as tmp:
        node = Path(tmp) / "node.toml"
        node.write_text(NODE.format(cache=Path(tmp) / "tiles"))
        for kind in ("can", "nmea0183", "modbus"):
            with Bench(Path(tmp) / kind, [kind], str(node)) as bench:
                result = bench.play(steps(reps), "helm steps")
            met = [o.elapsed_s * 1e3 for o in result.outcomes if o.passed]
            print(f"{kind:9s} {len(met)}/{reps} met: median {statistics.median(met):.0f} ms, "
                  f"p99 {np.percentile(met, 99):.0f} ms, max {max(met):.0f} ms", flush=True)


if __name__ == "__main__":
    main()
