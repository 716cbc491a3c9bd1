"""Where the time goes: the tick's phases over a run (histograms whose quantiles stay within a bin
of the samples'), and the world step's stages."""
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


def test_the_step_timer_keeps_each_stage_of_the_last_step(monkeypatch):
    """Laps on a clock that moves by known amounts: each stage keeps its own time, a stage
    lapped twice adds up, and a new step forgets the last one's stages."""
    from sim_core import stage_timer
    clock = iter([0.0, 1.0, 1.002, 1.005, 1.006, 2.0, 2.004])
    monkeypatch.setattr(stage_timer.time, "perf_counter", lambda: next(clock))
    timer = stage_timer.StageTimer()  # 0.0
    timer.start()  # 1.0
    timer.lap("ships")  # 2 ms
    timer.lap("ice: engine")  # 3 ms
    timer.lap("ships")  # 1 ms more
    assert list(timer.ms) == ["ships", "ice: engine"]
    assert timer.ms["ships"] == pytest.approx(3.0) and timer.ms["ice: engine"] == pytest.approx(3.0)
    timer.start()  # 2.0
    timer.lap("publish")
    assert timer.ms == {"publish": pytest.approx(4.0)}
