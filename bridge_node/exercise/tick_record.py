"""The session record's tick log (``ticks.log``): which raw inputs each tick of the
real-time loop read, so a recorded run can be re-simulated step for step.

The loop writes one line per tick, right after the links were polled: the step number,
the monotonic time the tick polled at (the clock links and arbitration ran on; written to
the last bit, so that a replay's output schedules and source timeouts decide at each tick
as the live run's did: rounded to the microsecond, an output due within a microsecond of a
tick could go out a tick early or late in the replay), the unix time, and how many inputs of each link kind that poll read (lines of ``nmea.log``,
``can.log``, ``modbus.csv``, ...: received sentences, received frames, register reads). The
raw files are written in the order the traffic happened, so counting their lines gives
each input its tick exactly. A first line ``# icebridge ticks 2 period_s=<s>
inputs=<kind>,<kind>,...`` gives the step and the kinds the counts are of, in order;
version 1 (no ``inputs``) counted nmea0183, can and modbus. Torn last lines are skipped, as
in every record file.
"""
from __future__ import annotations

import re
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from bridge_node.exercise.tick import StepListener
from bridge_node.links.kind import LINK_KINDS
from bridge_node.links.messages import Listener, Traffic
from bridge_node.links.record_reader import complete_lines, record_time
from bridge_node.links.session_record import FLUSH_PERIOD, cut_torn_tail

TICKS_FILE = "ticks.log"
HEADER = re.compile(r"# icebridge ticks (?P<version>[12]) period_s=(?P<period>\S*)(?: inputs=(?P<inputs>\S+))?")
VERSION_1_INPUTS = ("nmea0183", "can", "modbus")  # the kinds a version-1 tick log counted, in order
PERIOD_RANGE = (1e-3, 10.0)  # s: a tick log's period_s must lie in it (the node steps at 5 to 120 Hz)
MAX_SEQ = 2**53  # a step number at or above this is malformed (beyond any run, and exact in a float)
MAX_READS = 10**7  # inputs one tick read: more is malformed (a record file holds fewer lines)
_MAX_DIGITS = 16  # a count's or step number's digits: more is malformed, never parsed


@dataclass(frozen=True)
class Tick:
    """One recorded tick: step number, monotonic and unix time of its poll (s), and the
    inputs it read per link kind."""

    seq: int
    monotonic: float
    unix: float
    reads: dict[str, int]


def input_kinds() -> dict[str, str]:
    """Link kind -> the direction of its inputs, for every registered kind whose inputs a
    replay feeds back."""
    return {name: kind.record.input_direction for name, kind in LINK_KINDS.items()
            if kind.record.input_direction is not None}


class TickRecord(Listener, StepListener):
    """Writes ``ticks.log`` in a session folder; a listener of the hub, so that it counts
    every input the links report, and of the exercise's tick, so that it writes a line as
    each tick has polled."""

    def __init__(self, folder: Path, period: float) -> None:
        path = Path(folder) / TICKS_FILE
        cut_torn_tail(path)
        self._file = open(path, "a", encoding="ascii")
        self._inputs = input_kinds()
        self._file.write(f"# icebridge ticks 2 period_s={period!r} inputs={','.join(self._inputs)}\n")
        self._reads: Counter = Counter()
        self._last_flush = time.monotonic()

    def on_traffic(self, traffic: Traffic) -> None:
        if self._inputs.get(traffic.protocol) == traffic.direction:
            self._reads[traffic.protocol] += 1

    def on_polled(self, seq: int, now: float) -> None:
        """The tick of step ``seq`` has polled the links at ``now`` (monotonic s)."""
        counts = " ".join(str(self._reads[p]) for p in self._inputs)
        self._file.write(f"{seq} {now!r} {time.time():.6f} {counts}\n")  # the clock to the last bit
        self._reads.clear()

    def flush(self) -> None:
        if time.monotonic() - self._last_flush >= FLUSH_PERIOD:
            self._file.flush()
            self._last_flush = time.monotonic()

    def stop(self) -> None:
        if not self._file.closed:
            self._file.close()


def _header(line: str) -> tuple[float, tuple[str, ...]]:
    """The step period (s) and the input kinds of a tick log's header; ValueError unless a
    header whose period is a finite number within PERIOD_RANGE."""
    match = HEADER.fullmatch(line.strip())
    if match is None:
        raise ValueError("not a tick log (its first line is not '# icebridge ticks 1|2 period_s=...')")
    text = match["period"]
    try:
        period = float(text)
    except ValueError:
        raise ValueError(f"its period_s {text!r} is not a number") from None
    if not PERIOD_RANGE[0] <= period <= PERIOD_RANGE[1]:  # NaN fails too
        raise ValueError(f"its period_s {text!r} is outside [{PERIOD_RANGE[0]:g}, {PERIOD_RANGE[1]:g}] s")
    if match["version"] == "1":
        return period, VERSION_1_INPUTS
    if not match["inputs"]:
        raise ValueError("its header does not say which link kinds the counts are of (inputs=...)")
    return period, tuple(match["inputs"].split(","))


def _count(text: str, limit: int) -> int:
    """A non-negative integer field below ``limit``; ValueError otherwise (a long one is
    refused before it is parsed)."""
    if len(text) > _MAX_DIGITS or not text.isdigit() or not text.isascii() or int(text) >= limit:
        raise ValueError(f"count {text[:20]!r} out of range")
    return int(text)


def _tick(line: str, kinds: tuple[str, ...]) -> Tick:
    """One tick line; ValueError or IndexError when malformed: a step number, a finite
    monotonic time, a unix time in range and one read count per link kind, each in range."""
    parts = line.split()
    if len(parts) != 3 + len(kinds):
        raise ValueError("wrong number of fields")
    monotonic = float(parts[1])
    if not abs(monotonic) <= 1e12:  # s: NaN and infinity too
        raise ValueError("monotonic time out of range")
    return Tick(_count(parts[0], MAX_SEQ), monotonic, record_time(parts[2]),
                {kind: _count(p, MAX_READS) for kind, p in zip(kinds, parts[3:])})


def read_ticks(path: Path) -> tuple[float, list[Tick], Counter]:
    """The step period (s) and ticks of a ``ticks.log``, and counts of torn and malformed
    lines. ValueError if it does not start with the header, its period is not a finite
    number within PERIOD_RANGE, or it holds more than one run."""
    lines, counts = complete_lines(path)
    if not lines:
        raise ValueError("not a tick log (it is empty)")
    period, kinds = _header(lines[0])
    if any(HEADER.match(line) for line in lines[1:]):
        raise ValueError("it holds more than one run (two runs started in the same second?)")
    ticks = []
    for line in lines[1:]:
        try:
            ticks.append(_tick(line, kinds))
        except (ValueError, IndexError):
            counts["malformed"] += 1
    return period, ticks, counts
