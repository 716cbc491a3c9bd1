"""The node's real-time loop: the exercise's one tick (``bridge_node.exercise.tick``) at a
fixed rate, paced by the one pacer, with the live links as its order source.

Each tick polls the links and arbitrates (``LinkHub.poll``), steps the world by the tick's
period with the decided orders, notes the orders the ship refused, and hands the outcome to
the listeners: first the session record's tick log (``tick_record``: what each tick read,
so that the run can be re-simulated), then the links (``LinkOutputs``: the alarm changes
and the new ship state), then the caller's (the state stream, the status display). The
delay from reading an order to the end of the tick that published the state made with it
is the input-to-outputs transport delay. Pacing (``Pacer``): a tick that overruns its
period is counted; the loop never catches up in a burst, so simulated time runs slower
than real time and the real-time factor reports it. Simulated time is always ticks x period.
Every few seconds, in a tick that has at least half a period left, the loop gives the C
heap's free pages back to the system (``c_heap``), so that the node's resident memory
follows what it keeps and not the free chunks its per-step temporaries leave. (A loop
that overruns has no such slack, and gives nothing back until it has.)
"""
from __future__ import annotations

import gc
import os
import signal
import threading
import time
from array import array
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from bridge_node.exercise.command_log import CommandLog
from bridge_node.exercise.fleet import Bridge, FleetOrders, fleet_listeners
from bridge_node.control.queue import CommandSource
from bridge_node.exercise.listeners import LinkOutputs, SaveWriter, WorldTraffic
from bridge_node.exercise.pacer import Pacer
from bridge_node.exercise.phase_times import PhaseTimes
from bridge_node.exercise.tick import ExerciseTick, StepListener, TickOutcome
from bridge_node.links.hub import LinkHub
from bridge_node.node.c_heap import give_back_free_pages, heap_in_use_mib
from bridge_node.exercise.order_refusals import OrderRefusals
from bridge_node.exercise.tick_record import TickRecord
from sim_core.world import WorldData, WorldModel

TRIM_EVERY_S = 5.0  # s of wall time between the C heap's page give-backs (c_heap.py)
TRIM_SLACK = 0.5  # periods a tick must have left over for a give-back to go in its slack
SLOW_TICKS_KEPT = 50  # ticks over two periods whose phases the loop keeps (the first ones)


class GcClock:
    """Wall time (ms) the garbage collector took since the last ``take``, from Python's
    ``gc.callbacks``; a collection runs inside whatever phase allocated, so a slow tick's
    record gives it beside the phases. A context manager: leaving it unhooks the clock."""

    def __init__(self) -> None:
        self._ms, self._start = 0.0, 0.0

    def _callback(self, phase: str, _info: dict) -> None:
        if phase == "start":
            self._start = time.perf_counter()
        else:
            self._ms += (time.perf_counter() - self._start) * 1e3

    def take(self) -> float:
        ms, self._ms = self._ms, 0.0
        return ms

    def __enter__(self) -> GcClock:
        gc.callbacks.append(self._callback)
        return self

    def __exit__(self, *exc) -> None:
        gc.callbacks.remove(self._callback)


@contextmanager
def thread_scheduling(scheduler: str, priority: int) -> Iterator[str]:
    """Run the calling thread in the given CPU scheduling class while in the block, then
    back in the normal one: ``fifo`` is Linux's SCHED_FIFO real-time class at ``priority``,
    before every normal process (render processes, the console, other jobs on the machine),
    so that the tick is not descheduled in the middle of its step. Threads it starts (a save
    point's writer, a link's reopening) do not inherit the class (``SCHED_RESET_ON_FORK``):
    they would otherwise run before the render processes, and hold the core against the loop
    itself until they block. Gives what it got: ``normal``, ``fifo N``, or the refusal (no
    permission, not Linux); a refusal leaves the thread as it was. After the block the thread
    has its class and priority of before."""
    if scheduler != "fifo":
        yield "normal"
        return
    try:
        before = os.sched_getscheduler(0), os.sched_getparam(0)  # 0: the calling thread
        os.sched_setscheduler(0, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK, os.sched_param(priority))
    except (AttributeError, OSError) as exc:
        yield f"normal (fifo refused: {getattr(exc, 'strerror', None) or exc})"
        return
    try:
        yield f"fifo {priority}"
    finally:
        os.sched_setscheduler(0, *before)


# the memory records' measured columns: (summary key, column in LoopStats.memory, label)
MEMORY_SERIES = (("rss", 2, "resident"), ("heap_in_use", 3, "C heap in use"))


@dataclass
class LoopStats:
    """What the loop measured: per-tick wall times (ms), overruns, refused orders, and the
    ship's track. Per-tick figures are float32 arrays (4 bytes a tick, where a list of
    Python floats took 32: 7 MB an hour at 60 Hz, which the memory figure took for the
    frozen floes')."""

    ticks: int = 0
    overruns: int = 0
    wall_s: float = 0.0
    sim_s: float = 0.0
    step_ms: array = field(default_factory=lambda: array("f"))
    track: list = field(default_factory=list)  # (sim time s, north m, east m, speed m/s, live floes)
    # (sim time s, frozen floes, resident MiB, C heap in use MiB), once a second
    memory: list = field(default_factory=list)
    trim_ms: array = field(default_factory=lambda: array("f"))  # wall times of the heap's page give-backs
    refusals: OrderRefusals = field(default_factory=OrderRefusals)
    input_to_outputs_ms: array = field(default_factory=lambda: array("f"))
    slow_ticks: list = field(default_factory=list)  # the first SLOW_TICKS_KEPT ticks over two periods: where time went
    phases: PhaseTimes = field(default_factory=PhaseTimes)  # every tick's phases: where time goes over the run
    world_stages: PhaseTimes = field(default_factory=PhaseTimes)  # every world step's stages (``IceData.timer``)
    scheduling: str = "normal"  # the loop thread's CPU scheduling, as it got it (``thread_scheduling``)

    def summary(self) -> dict:
        ms = np.array(self.step_ms, dtype=float) if self.step_ms else np.zeros(1)
        return {"ticks": self.ticks, "overruns": self.overruns, "wall_s": round(self.wall_s, 2),
                "sim_s": round(self.sim_s, 2), "real_time_factor": round(self.sim_s / max(self.wall_s, 1e-9), 3),
                "tick_ms_median": round(float(np.median(ms)), 2), "tick_ms_p99": round(float(np.percentile(ms, 99)), 2),
                "tick_ms_max": round(float(ms.max()), 2), "orders_rejected": dict(self.refusals.counts),
                "input_to_outputs_ms": distribution(self.input_to_outputs_ms), "memory": self.memory_summary(),
                "slow_ticks": self.slow_ticks, "phase_ms": self.phases.summary(),
                "world_stage_ms": self.world_stages.summary(), "scheduling": self.scheduling}

    def memory_summary(self) -> dict:
        """Resident memory and the C heap's bytes in use at the start and end (MiB), and
        the growth of each per 1000 frozen floes over the last two thirds of the run (after
        the live-floe count has levelled off), by a least-squares line; None where the
        platform does not say or no floes froze; and how often the heap's free pages were
        given back (``trims``) and the longest of those in ms."""
        out = {"trims": len(self.trim_ms), "trim_ms_max": round(max(self.trim_ms), 2) if self.trim_ms else None}
        for key, col, _ in MEMORY_SERIES:
            m = np.array([(r[1], r[col]) for r in self.memory if r[col] is not None]).reshape(-1, 2)
            out[f"{key}_mib_start"] = out[f"{key}_mib_end"] = out[f"{key}_mib_per_1000_frozen"] = None
            if len(m):
                out[f"{key}_mib_start"], out[f"{key}_mib_end"] = round(float(m[0, 1]), 1), round(float(m[-1, 1]), 1)
                late = m[len(m) // 3:]
                if len(late) > 2 and np.ptp(late[:, 0]) >= 1000:
                    out[f"{key}_mib_per_1000_frozen"] = round(float(np.polyfit(late[:, 0], late[:, 1], 1)[0] * 1000), 3)
        return out


def resident_mib() -> float | None:
    """This process's resident memory, MiB (Linux /proc; None elsewhere)."""
    try:
        with open("/proc/self/statm", encoding="ascii") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError, IndexError):
        return None


def distribution(ms: Sequence[float]) -> dict:
    """Count, median and p99 of delays (ms); None where there are none."""
    a = np.array(ms, dtype=float)
    return {"count": len(a), "median": round(float(np.median(a)), 2) if len(a) else None,
            "p99": round(float(np.percentile(a, 99)), 2) if len(a) else None}


@dataclass
class _StopRequest:
    """Set by Ctrl-C or SIGTERM; the loop looks at it between ticks."""

    requested: bool = False


@contextmanager
def _stop_between_ticks() -> Iterator[_StopRequest]:
    """Ctrl-C and SIGTERM, while inside, set a flag the loop checks between ticks rather
    than raise where the tick happens to be: a tick cut in the middle of a link's poll would
    leave frames in the session record that the link's counts never took in. (A flag, not
    a lock-based event: a handler runs in the main thread, which may hold the lock.) A
    second signal raises KeyboardInterrupt at once, so a hung tick can still be left.
    Outside the main thread, where Python delivers no signals, the handlers stay as they are."""
    stop = _StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def request(*_) -> None:
        if stop.requested:  # asked again: a tick that hangs (a blocked device) is left at once
            raise KeyboardInterrupt
        stop.requested = True
    before = {sig: signal.signal(sig, request) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)


def live_tick(model: WorldModel, data: WorldData, hub: LinkHub, rate_hz: float,
              listeners: Sequence[StepListener | Callable[[TickOutcome], None]] = (),
              commands: CommandSource | None = None, fleet: Sequence[Bridge] = ()) -> ExerciseTick:
    """The tick of a live exercise: orders from the hub's links, the instructor's
    ``commands``, outcomes to the session record's tick and command logs and its save
    points (where the hub records), the links, then ``listeners``. With ``fleet`` (every
    own ship's bridge, the first's hub ``hub``), each ship obeys its own bridge's links and
    sends on them (``bridge_node.exercise.fleet``)."""
    hubs = [b.hub for b in fleet] or [hub]
    records = [_tick_record(h, rate_hz) for h in hubs if h.record is not None]  # each ship's in its own folder
    if hub.record is not None:
        records += [CommandLog(hub.record.folder), SaveWriter(hub.record.folder)]
    ships = fleet_listeners(model, hub, fleet)
    return ExerciseTick(model, data, FleetOrders(fleet) if fleet else hub,
                        [*records, *(WorldTraffic(h.traffic, model.origin) for h in hubs), *ships, LinkOutputs(hub),
                         *listeners], commands)


def _tick_record(hub: LinkHub, rate_hz: float) -> TickRecord:
    """The tick log of a hub's session record: a listener of the hub too, counting its links'
    reads (stopped with the hub's other listeners)."""
    ticks = TickRecord(hub.record.folder, 1.0 / rate_hz)
    hub.add_listener(ticks)
    return ticks


def _rounded(ms: dict[str, float]) -> dict[str, float]:
    """Times (ms) to 0.01 ms, as the summary gives them."""
    return {k: round(v, 2) for k, v in ms.items()}


def run_realtime(model: WorldModel, data: WorldData, hub: LinkHub, rate_hz: float, duration: float | None,
                 listeners: Sequence[StepListener | Callable[[TickOutcome], None]] = (),
                 should_stop: Callable[[], bool] = lambda: False,
                 commands: CommandSource | None = None, scheduler: tuple[str, int] = ("normal", 0),
                 fleet: Sequence[Bridge] = ()) -> LoopStats:
    """Run the live tick (``live_tick``) at ``rate_hz`` until ``duration`` wall seconds
    have passed (None: until should_stop(), Ctrl-C or SIGTERM, which end the loop after
    the tick in hand); ``listeners`` get every tick's outcome; ``commands`` are the
    instructor's; ``scheduler``: the loop thread's CPU scheduling and real-time priority
    (``thread_scheduling``); ``fleet``: every own ship's bridge (``live_tick``)."""
    period = 1.0 / rate_hz
    tick = live_tick(model, data, hub, rate_hz, listeners, commands, fleet)
    stats = LoopStats(refusals=tick.refusals)
    # Everything made so far (modules, models, kernels) lives for the whole run. Moved out of
    # the collector's generations, a full collection no longer walks it: that walk, some
    # hundred thousand objects, was a tick of a tenth of a second every few minutes.
    gc.collect()
    gc.freeze()
    pacer = Pacer(period)
    start = last_trim = time.monotonic()
    with _stop_between_ticks() as stop, GcClock() as gc_clock, thread_scheduling(*scheduler) as stats.scheduling:
        while (duration is None or time.monotonic() - start < duration) and not should_stop() and not stop.requested:
            t0 = time.monotonic()
            outcome = tick(period, t0)
            tick_ms = (time.monotonic() - t0) * 1e3
            _note(stats, outcome, rate_hz, tick_ms)
            gc_ms = gc_clock.take()
            stats.phases.add(tick.phase_ms)
            stats.world_stages.add(data.ice.timer.ms)
            if tick_ms > 2e3 * period and len(stats.slow_ticks) < SLOW_TICKS_KEPT:
                stats.slow_ticks.append({"sim_s": round(stats.sim_s, 3), "tick_ms": round(tick_ms, 2),
                                         "gc_ms": round(gc_ms, 2), **_rounded(tick.phase_ms),
                                         "world_waits": tick.world_waits, "world_stages": _rounded(data.ice.timer.ms)})
            pacer.advance()
            if time.monotonic() - last_trim >= TRIM_EVERY_S and pacer.slack() >= TRIM_SLACK * period:
                last_trim = time.monotonic()
                if give_back_free_pages():
                    stats.trim_ms.append((time.monotonic() - last_trim) * 1e3)
            pacer.wait()
    stats.overruns = pacer.overruns
    stats.wall_s = time.monotonic() - start
    return stats


def _note(stats: LoopStats, outcome: TickOutcome, rate_hz: float, tick_ms: float) -> None:
    """Count one tick: its wall time, its transport delay, and once a simulated second the
    ship's track and the memory."""
    stats.ticks += 1
    stats.sim_s = stats.ticks / rate_hz
    stats.step_ms.append(tick_ms)
    if outcome.input_time is not None:
        stats.input_to_outputs_ms.append((time.monotonic() - outcome.input_time) * 1e3)
    if stats.ticks % max(1, round(rate_hz)) == 0:
        events, s = outcome.events, outcome.events.ship
        stats.track.append((events.time, s.north, s.east, s.speed_over_ground, events.floes_free))
        stats.memory.append((events.time, events.floes_frozen, resident_mib(), heap_in_use_mib()))
