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
from bridge_node.links.messages import Listener, Traffic
from bridge_node.links.record_reader import complete_lines, record_time
from bridge_node.links.session_record import FLUSH_PERIOD, cut_torn_tail

TICKS_FILE = "ticks.log"
HEADER = "# icebridge ticks 1 period_s="
READS = {"nmea0183": "rx", "can": "rx", "modbus": "read"}  # protocol -> the direction of its inputs
PROTOCOLS = tuple(READS)
PERIOD_RANGE = (1e-3, 10.0)  # s: a tick log's period_s must lie in it (the node steps at 5 to 120 Hz)
MAX_SEQ = 2**53  # a step number at or above this is malformed (beyond any run, and exact in a float)
MAX_READS = 10**7  # inputs one tick read: more is malformed (a record file holds fewer lines)
_MAX_DIGITS = 16  # a count's or step number's digits: more is malformed, never parsed


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


def _period(line: str) -> float:
    """The step period (s) of a tick log's header; ValueError unless a finite number
    within PERIOD_RANGE."""
    text = line[len(HEADER):].strip()
    try:
        period = float(text)
    except ValueError:
        raise ValueError(f"its period_s {text!r} is not a number") from None
    if not PERIOD_RANGE[0] <= period <= PERIOD_RANGE[1]:  # NaN fails too
        raise ValueError(f"its period_s {text!r} is outside [{PERIOD_RANGE[0]:g}, {PERIOD_RANGE[1]:g}] s")
    return period


def _count(text: str, limit: int) -> int:
    """A non-negative integer field below ``limit``; ValueError otherwise (a long one is
    refused before it is parsed)."""
    if len(text) > _MAX_DIGITS or not text.isdigit() or not text.isascii() or int(text) >= limit:
        raise ValueError(f"count {text[:20]!r} out of range")
    return int(text)


def _tick(line: str) -> Tick:
    """One tick line; ValueError or IndexError when malformed: a step number, a finite
    monotonic time, a unix time in range and one read count per protocol, each in range."""
    parts = line.split()
    if len(parts) != 3 + len(PROTOCOLS):
        raise ValueError("wrong number of fields")
    monotonic = float(parts[1])
    if not abs(monotonic) <= 1e12:  # s: NaN and infinity too
        raise ValueError("monotonic time out of range")
    return Tick(_count(parts[0], MAX_SEQ), monotonic, record_time(parts[2]),
                tuple(_count(p, MAX_READS) for p in parts[3:]))


def read_ticks(path: Path) -> tuple[float, list[Tick], Counter]:
    """The step period (s) and ticks of a ``ticks.log``, and counts of torn and malformed
    lines. ValueError if it does not start with the header, its period is not a finite
    number within PERIOD_RANGE, or it holds more than one run."""
    lines, counts = complete_lines(path)
    if not lines or not lines[0].startswith(HEADER):
        raise ValueError(f"not a tick log (its first line is not {HEADER!r}...)")
    if any(line.startswith(HEADER) for line in lines[1:]):
        raise ValueError("it holds more than one run (two runs started in the same second?)")
    period = _period(lines[0])
    ticks = []
    for line in lines[1:]:
        try:
            ticks.append(_tick(line))
        except (ValueError, IndexError):
            counts["malformed"] += 1
    return period, ticks, counts
