"""The tick's phases over a run: histograms whose quantiles stay within a bin of the samples'."""
import numpy as np
import pytest

from bridge_node.exercise.phase_times import BIN_MS, PhaseTimes


def test_quantiles_lie_within_a_bin_of_the_samples():
    rng = np.random.default_rng(3)
    world = rng.gamma(4.0, 1.0, 20_000)  # ms, a long tail
    orders = rng.uniform(0.0, 0.3, 20_000)
    times = PhaseTimes()
    for w, o in zip(world, orders):
        times.add({"orders": float(o), "world": float(w)})
    times.add({"world": 250.0})  # beyond the last bin: counted there, and as the longest
    s = times.summary()
    assert list(s) == ["orders", "world"]
    assert s["orders"]["ticks"] == 20_000 and s["world"]["ticks"] == 20_001
    for name, samples in (("orders", orders), ("world", np.append(world, 250.0))):
        for key, q in (("median", 50), ("p99", 99)):
            assert s[name][key] == pytest.approx(np.percentile(samples, q), abs=BIN_MS + 0.01)
    assert s["world"]["max"] == 250.0
    assert s["orders"]["max"] == pytest.approx(orders.max(), abs=0.01)
