"""Wall time of each stage of the last step, as MuJoCo keeps ``mjData.timer``: the data of a
step, not a report about it, so that a caller that finds a step slow can read where its time
went (the node keeps the stages of every tick over two periods, ``bridge_node.node.realtime_loop``).

A lap costs one clock read (about 0.1 us), a step takes some fifteen.
"""
from __future__ import annotations

import time


class StageTimer:
    """Each stage's wall time (ms) since ``start``: a lap ends the stage named and starts the
    next one; a stage lapped twice adds up."""

    __slots__ = ("ms", "_since")

    def __init__(self) -> None:
        self.ms: dict[str, float] = {}
        self._since = time.perf_counter()

    def start(self) -> None:
        """A new step: forget the last one's stages."""
        self.ms = {}
        self._since = time.perf_counter()

    def lap(self, stage: str) -> None:
        """The stage ``stage`` ends now."""
        now = time.perf_counter()
        self.ms[stage] = self.ms.get(stage, 0.0) + (now - self._since) * 1e3
        self._since = now
