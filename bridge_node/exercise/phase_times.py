"""Where the tick's time goes over a whole run: each phase's wall times (the orders, the world
step, each kind of listener: ``ExerciseTick.phase_ms``) counted in a fixed histogram.

A run of days at 60 Hz keeps no per-tick list per phase: each phase has 2000 bins of 0.05 ms
(the last one takes everything from 100 ms up), so memory stays the same however long the
run, and a median or p99 read from the bins is within a bin's width (0.05 ms) below 100 ms.
numpy's histogram wants the samples at hand; the tick adds one at a time, in Python.
"""
from __future__ import annotations

BIN_MS = 0.05  # width of a bin, ms
BINS = 2000  # bins per phase: 0..100 ms, the last one open-ended


class PhaseTimes:
    """Histograms of each phase's wall time (ms) per tick, and each phase's longest."""

    def __init__(self) -> None:
        self._bins: dict[str, list[int]] = {}
        self._max: dict[str, float] = {}

    def add(self, phase_ms: dict[str, float]) -> None:
        """Count one tick's phases (phase name -> wall time, ms)."""
        for name, ms in phase_ms.items():
            bins = self._bins.get(name)
            if bins is None:
                bins = self._bins[name] = [0] * BINS
                self._max[name] = 0.0
            bins[min(int(ms / BIN_MS), BINS - 1)] += 1
            if ms > self._max[name]:
                self._max[name] = ms

    def quantile(self, name: str, q: float) -> float:
        """The q-quantile (0..1) of a phase's times, ms: the upper edge of the bin it falls in
        (the phase's longest where that is less)."""
        bins = self._bins[name]
        need, seen = q * sum(bins), 0
        for k, count in enumerate(bins):
            seen += count
            if count and seen >= need:
                return min((k + 1) * BIN_MS, self._max[name])
        return self._max[name]

    def summary(self) -> dict[str, dict[str, float]]:
        """Per phase: ticks counted, median, p99 and max (ms), in the order the phases came."""
        return {name: {"ticks": sum(bins), "median": round(self.quantile(name, 0.5), 2),
                       "p99": round(self.quantile(name, 0.99), 2), "max": round(self._max[name], 2)}
                for name, bins in self._bins.items()}
