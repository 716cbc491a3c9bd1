"""The session record's tick log (``ticks.log``): which raw inputs each tick of the
real-time loop read, so a recorded run can be re-simulated step for step.

The loop writes one line per tick, right after the links were polled: the step number,
the monotonic time the tick polled at (the clock links and arbitration ran on), the unix
time, and how many lines of ``nmea.log``, ``can.log`` and ``modbus.csv`` that poll read
(received sentences, received frames, register reads). The raw files are written in the
order the traffic happened, so counting their lines gives each input its tick exactly.
A first line ``# icebridge ticks 1 period_s=<s>`` gives the step. Torn last lines are
skipped, as in every record file.
"""
from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from bridge_node.exercise.tick import StepListener
from bridge_node.links.base import Listener, Traffic
from bridge_node.links.record_reader import complete_lines
from bridge_node.links.session_record import FLUSH_PERIOD, cut_torn_tail

TICKS_FILE = "ticks.log"
HEADER = "# icebridge ticks 1 period_s="
READS = {"nmea0183": "rx", "can": "rx", "modbus": "read"}  # protocol -> the direction of its inputs
PROTOCOLS = tuple(READS)


@dataclass(frozen=True)
class Tick:
    """One recorded tick: step number, monotonic and unix time of its poll (s), and the
    inputs it read per protocol (``PROTOCOLS`` order)."""

    seq: int
    monotonic: float
    unix: float
    reads: tuple[int, ...]


class TickRecord(Listener, StepListener):
    """Writes ``ticks.log`` in a session folder; a listener of the hub, so that it counts
    every input the links report, and of the exercise's tick, so that it writes a line as
    each tick has polled."""

    def __init__(self, folder: Path, period: float) -> None:
        path = Path(folder) / TICKS_FILE
        cut_torn_tail(path)
        self._file = open(path, "a", encoding="ascii")
        self._file.write(f"{HEADER}{period!r}\n")
        self._reads: Counter = Counter()
        self._last_flush = time.monotonic()

    def on_traffic(self, traffic: Traffic) -> None:
        if READS.get(traffic.protocol) == traffic.direction:
            self._reads[traffic.protocol] += 1

    def on_polled(self, seq: int, now: float) -> None:
        """The tick of step ``seq`` has polled the links at ``now`` (monotonic s)."""
        counts = " ".join(str(self._reads[p]) for p in PROTOCOLS)
        self._file.write(f"{seq} {now:.6f} {time.time():.6f} {counts}\n")
        self._reads.clear()

    def flush(self) -> None:
        if time.monotonic() - self._last_flush >= FLUSH_PERIOD:
            self._file.flush()
            self._last_flush = time.monotonic()

    def stop(self) -> None:
        if not self._file.closed:
            self._file.close()


def read_ticks(path: Path) -> tuple[float, list[Tick], Counter]:
    """The step period (s) and ticks of a ``ticks.log``, and counts of torn and malformed
    lines. ValueError if it does not start with the header or holds more than one run."""
    lines, counts = complete_lines(path)
    if not lines or not lines[0].startswith(HEADER):
        raise ValueError(f"not a tick log (its first line is not {HEADER!r}...)")
    if any(line.startswith(HEADER) for line in lines[1:]):
        raise ValueError("it holds more than one run (two runs started in the same second?)")
    period = float(lines[0][len(HEADER):])
    ticks = []
    for line in lines[1:]:
        parts = line.split()
        try:
            ticks.append(Tick(int(parts[0]), float(parts[1]), float(parts[2]), tuple(int(p) for p in parts[3:])))
        except (ValueError, IndexError):
            counts["malformed"] += 1
            continue
        if len(ticks[-1].reads) != len(PROTOCOLS):
            ticks.pop()
            counts["malformed"] += 1
    return period, ticks, counts
