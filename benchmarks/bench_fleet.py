"""Benchmark: the world step with ships in line through 1.0 m level ice, against one.

The default ship's world on a 400 m wide field of 1.0 m level ice. The same ship leads at
full ahead and follows two ship lengths astern, keeping that distance on its engine lever
(in the channel it would otherwise run into the leader and collide with it), every ship under its own model, stepped at the given rate (60 Hz; issue 31's
second case is four ships at 30 Hz) for the given simulated time; the baseline, in the same
run, is the leader alone. Printed:
step median, p99 and max (ms), steps over one and two periods, the ratio of two ships to
one, the live and frozen floes at the end, the core count; and a plot of step time against
simulated time for both (``out/bench_fleet.png``; ``bench_fleet_4x30.png`` for four ships at 30 Hz).

Run: .venv/bin/python benchmarks/bench_fleet.py [--minutes 15] [--ships 2] [--rate 60]
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from rich.progress import Progress  # noqa: E402

from bridge_node.node.config import load_config  # noqa: E402
from bridge_node.node.world_setup import build_world  # noqa: E402
from sim_core.ice.floes import FloeStatus  # noqa: E402
from sim_core.world import Controls, ShipStart, compile_world, new_world_data, step  # noqa: E402

KNOT = 1852.0 / 3600.0


def keep_station(data, gap: float) -> list[Controls | None]:
    """Orders that keep each ship after the first ``gap`` m (reference points) astern of the
    one ahead: engine lever in proportion to the distance too many, 2 % per metre."""
    return [None] + [Controls(lever=float(np.clip(2.0 * (ahead.eta[0] - ship.eta[0] - gap), -20.0, 100.0)))
                     for ahead, ship in zip(data.ships, data.ships[1:])]


def fleet_steps(base, ships: int, minutes: float, rate: float, progress: Progress) -> tuple[np.ndarray, str]:
    """Step times (ms) of ``ships`` in line, the leader at full ahead and the others keeping
    station two ship lengths astern, for ``minutes`` at ``rate`` Hz; and a line on the end state."""
    model = compile_world(base.ship, base.ice, base.scene, base.origin, (), base.rubble,
                          others=(base.ship,) * (ships - 1))
    length = base.ship.particulars.length
    lead = -0.5 * length - 5.0
    others = tuple(ShipStart(lead - 2.0 * length * k, 200.0, 0.0, 4.0 * KNOT) for k in range(1, ships))
    data = new_world_data(model, lead, 200.0, 0.0, 4.0 * KNOT, "full_ahead", others)
    starts = [s.eta[0] for s in data.ships]
    steps = int(minutes * 60.0 * rate)
    times = np.empty(steps)
    task = progress.add_task(f"{ships} ship(s)", total=steps)
    orders = None
    for k in range(steps):
        if k % int(rate) == 0 and ships > 1:  # the station keeping's orders, once a second
            orders = keep_station(data, 2.0 * length)
        t0 = time.perf_counter()
        step(model, data, 1.0 / rate, orders)
        orders = None
        times[k] = (time.perf_counter() - t0) * 1e3
        if k % 600 == 0:
            progress.update(task, completed=k)
    progress.update(task, completed=steps)
    st = data.ice.state
    end = (f"made good {', '.join(f'{s.eta[0] - n:.0f} m' for s, n in zip(data.ships, starts))}; live floes "
           f"{st.count(FloeStatus.FREE)}, frozen {data.ice.frozen.count}"
           + "".join(f"; {a.eta[0] - b.eta[0]:.0f} m between ships" for a, b in zip(data.ships, data.ships[1:])))
    return times, end


def _line(name: str, ms: np.ndarray, period: float) -> str:
    return (f"{name}: median {np.median(ms):.2f} ms, p99 {np.percentile(ms, 99):.2f} ms, max {ms.max():.2f} ms, "
            f"over one period {int((ms > period).sum())}, over two {int((ms > 2 * period).sum())}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=15.0, help="simulated minutes per run")
    ap.add_argument("--ships", type=int, default=2, choices=range(2, 17), metavar="2..16", help="ships in line")
    ap.add_argument("--rate", type=float, default=60.0, help="steps per simulated second (default 60)")
    args = ap.parse_args()
    cfg = load_config()
    cfg = cfg.model_copy(update={"ice_field": cfg.ice_field.model_copy(
        update={"width": 400.0, "height": 4000.0, "thickness": 1.0})})
    base = build_world(cfg, None)
    with Progress() as progress:
        one, end_one = fleet_steps(base, 1, args.minutes, args.rate, progress)
        fleet, end_fleet = fleet_steps(base, args.ships, args.minutes, args.rate, progress)
    period, name = 1e3 / args.rate, f"{args.ships} ships"
    print(f"cores: {os.cpu_count()}; {args.minutes:g} simulated minutes at {args.rate:g} Hz each")
    print(_line("one ship ", one, period) + f"; {end_one}")
    print(_line(name, fleet, period) + f"; {end_fleet}")
    print(f"{name} / one (same run): median {np.median(fleet) / np.median(one):.2f}, "
          f"p99 {np.percentile(fleet, 99) / np.percentile(one, 99):.2f}")
    out = Path("out")
    out.mkdir(exist_ok=True)
    fig, ax = plt.subplots(figsize=(9, 4))
    for ms, label in ((one, "one ship"), (fleet, f"{name} in line")):
        t = np.arange(len(ms)) / args.rate / 60.0
        ax.plot(t, ms, lw=0.3, alpha=0.6, label=f"{label} (p99 {np.percentile(ms, 99):.1f} ms)")
    ax.axhline(period, color="k", lw=0.8, ls="--", label=f"one period ({args.rate:g} Hz)")
    ax.set_xlabel("simulated minutes")
    ax.set_ylabel("world step, ms")
    ax.set_title(f"World step, 1.0 m level ice ({os.cpu_count()} cores)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    plot = out / ("bench_fleet.png" if (args.ships, args.rate) == (2, 60.0) else
                  f"bench_fleet_{args.ships}x{args.rate:g}.png")
    fig.savefig(plot, dpi=120)
    print(f"plot: {plot}")


if __name__ == "__main__":
    main()
