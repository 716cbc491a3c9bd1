"""The one pacer of every mode: ticks at a fixed wall-clock period, never in a burst.

Tick k is due ``period`` after tick k-1 was due. A tick that ends after the next one was
due is an overrun; a pacer more than ``behind_s`` behind restarts its schedule from now
rather than catch up in a burst, so simulated time runs slower than real time and the
real-time factor says so. A live run paces at the step's period and restarts after one
period behind; a replay at the step's period over its speed factor, restarting after a
second behind (``retime`` when the speed changes, ``restart`` after a pause or a seek).
"""
from __future__ import annotations

import time


class Pacer:
    """Sleeps between ticks so that they come every ``period`` wall seconds."""

    def __init__(self, period: float, behind_s: float | None = None) -> None:
        self.period = period
        self.behind_s = period if behind_s is None else behind_s
        self.overruns = 0
        self.due = time.monotonic()  # when the next tick is due, monotonic s

    def restart(self) -> None:
        """The next tick is due now (after a pause, a seek, or the exercise's start)."""
        self.due = time.monotonic()

    def retime(self, period: float) -> None:
        """Tick every ``period`` wall seconds from now on."""
        self.period = period
        self.restart()

    def advance(self) -> None:
        """A tick has been taken: the next one is due a period after it was."""
        self.due += self.period

    def slack(self) -> float:
        """Wall seconds left until the next tick is due (negative: late)."""
        return self.due - time.monotonic()

    def wait(self) -> None:
        """Sleep until the next tick is due; count an overrun where it is already past,
        and restart the schedule where it is more than ``behind_s`` past."""
        late = -self.slack()
        if late <= 0.0:
            time.sleep(-late)
            return
        self.overruns += 1
        if late > self.behind_s:
            self.restart()
