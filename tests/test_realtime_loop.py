"""The node's real-time loop end to end: a console on virtual CAN steers the ship through the
ice world, and the instruments see the result. Asserts what the loop guarantees (no burst
catch-up, simulated time = ticks x period, orders arrive and are obeyed), never how many
ticks a wall-clock window holds on a loaded machine."""
import math
import os
import signal
import threading
import time

import can
import pytest
from links_helpers import console_frame
from nmea2000.decoder import NMEA2000Decoder

from bridge_node.hil.bench import PtyPair
from bridge_node.links.hub import LinkHub
from bridge_node.node.c_heap import heap_in_use_mib
from bridge_node.node.config import load_config
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import build_world, start_world
from sim_core.ice.floes import FloeStatus


def test_console_steers_the_ship_in_real_time(tmp_path):
    base = load_config()
    cfg = base.model_copy(update={
        "ice_field": base.ice_field.model_copy(update={"width": 400.0, "height": 400.0}),
        "links": [], "paths": base.paths.model_copy(update={"cache_dir": str(tmp_path / "tiles")}),
    })
    cfg = type(cfg).model_validate(cfg.model_dump() | {
        "links": [{"type": "can", "name": "helm", "channel": "icebridge-rt", "allowed_sources": [0x42]}],
        "arbitration": {"rudder": ["helm"], "engine": ["helm"]},
        "exercise": cfg.exercise.model_dump() | {"start_north": -60.0}})  # bow already in the ice
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    console = can.Bus(interface="virtual", channel="icebridge-rt")
    stop = threading.Event()

    def helm() -> None:
        while not stop.is_set():
            console.send(console_frame("HelmOrder", RudderOrder=35.0, Status=1, Counter=0))
            stop.wait(0.1)
    sender = threading.Thread(target=helm, daemon=True)
    seen = []
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        sender.start()
        try:
            psi0 = data.ship.eta[5]
            stats = run_realtime(model, data, hub, 30.0, None, [lambda outcome: seen.append(outcome.events)],
                                 should_stop=lambda: data.time >= 3.0 - 1e-9)  # 3 simulated seconds
        finally:
            stop.set()
            sender.join(2.0)
        orders = hub.order_counts["helm/rudder/0"]
    period = 1.0 / 30.0
    assert stats.ticks == len(seen) == 90
    assert stats.sim_s == pytest.approx(stats.ticks * period) == pytest.approx(data.time)  # one clock
    assert [e.seq for e in seen] == list(range(1, stats.ticks + 1))  # every step published, in order
    # no burst catch-up: tick k never starts before k periods have passed
    assert stats.ticks <= stats.wall_s / period + 1
    assert orders > 0  # the console's orders arrived
    assert data.ship.rudder > math.radians(5.0)  # the steering gear follows the console
    assert data.ship.eta[5] > psi0  # and the ship swings to starboard
    assert seen[-1].floes_free == data.ice.state.count(FloeStatus.FREE) > 0  # through ice it breaks
    heap_said = heap_in_use_mib() is not None  # glibc 2.33 and later
    assert len(stats.memory) == 3  # once a simulated second: resident memory and the C heap in use
    assert all(r[2] > 0 and (r[3] > 0 if heap_said else r[3] is None) for r in stats.memory)
    heading = None
    dec = NMEA2000Decoder()
    while (msg := console.recv(timeout=0.05)) is not None:
        m = dec.decode(msg)
        if m is not None and m.PGN == 127250:
            heading = {f.id: f.value for f in m.fields}["heading"]
    console.shutdown()
    assert heading == pytest.approx(data.ship.eta[5] % (2 * math.pi), abs=0.01)  # last published state


def test_the_loop_ticks_on_while_a_lost_slcan_adapter_reopens(tmp_path):
    """python-can's slcan sleeps 2 s after opening its port: the reopen after the adapter was
    unplugged happens on the opener's thread while the loop keeps stepping the world."""
    base = load_config()
    cfg = type(base).model_validate(base.model_dump() | {
        "ice_field": base.ice_field.model_dump() | {"width": 400.0, "height": 400.0},
        "paths": base.paths.model_dump() | {"cache_dir": str(tmp_path / "tiles")}, "console": None})
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    with PtyPair(tmp_path, "adapter") as pair:
        links = [{"type": "can", "name": "helm", "interface": "slcan", "channel": str(pair.node_end),
                  "allowed_sources": [0x42]}]
        cfg = type(cfg).model_validate(cfg.model_dump() | {"links": links})
        states = []  # the link's (opening, connected) at every tick

        def unplug_and_replug() -> None:
            pair.cut()
            stop.wait(0.5)
            pair.restore()
        stop = threading.Event()
        with LinkHub(cfg.links, cfg.arbitration) as hub:
            link = hub.links[0]
            link.await_open(None)  # the hub waits 5 s at most; a loaded machine may take longer
            assert link.health().connected
            threading.Thread(target=unplug_and_replug, daemon=True).start()

            def on_step(_) -> None:
                h = link.health()
                states.append((h.opening, h.connected))
            reopened = lambda: (True, False) in states and states[-1] == (False, True)  # noqa: E731
            stats = run_realtime(model, data, hub, 30.0, None, [on_step], should_stop=lambda: reopened()
                                 or len(states) > 900)
            stop.set()
            health = link.health()
    assert reopened(), f"the link did not come back: {health}"
    assert health.errors["bus_lost"] == 1 and health.reconnects >= 1
    opening = sum(1 for s in states if s == (True, False))
    assert opening > 1  # several ticks ran while the adapter opened (one tick would be a loop held up)
    assert stats.ticks == len(states)


def _small_world(tmp_path):
    """The default config on a 400 m x 400 m field without links, its world built and started."""
    base = load_config()
    cfg = base.model_copy(update={
        "ice_field": base.ice_field.model_copy(update={"width": 400.0, "height": 400.0}),
        "links": [], "paths": base.paths.model_copy(update={"cache_dir": str(tmp_path / "tiles")})})
    model = build_world(cfg, None)
    return cfg, model, start_world(model, cfg)


def test_sigterm_ends_the_loop_after_the_tick_in_hand(tmp_path):
    """SIGTERM (as Ctrl-C) in the middle of a tick does not cut the tick: the loop ends after
    it, with every tick counted and published, and the process's handlers back as they were
    (a signal raised inside a link's poll used to leave recorded frames uncounted)."""
    cfg, model, data = _small_world(tmp_path)
    seen = []

    def on_step(outcome) -> None:
        seen.append(outcome.events)
        if len(seen) == 5:
            os.kill(os.getpid(), signal.SIGTERM)  # delivered now, inside the tick
            seen.append("after the signal")  # the tick goes on: nothing was raised

    before = signal.getsignal(signal.SIGTERM)
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        stats = run_realtime(model, data, hub, 30.0, None, [on_step])
    assert seen[5] == "after the signal" and len(seen) == 6  # ended after that tick, not in it
    assert stats.ticks == 5 and data.time == pytest.approx(5 / 30.0)
    assert signal.getsignal(signal.SIGTERM) is before


def test_a_tick_over_two_periods_is_kept_with_where_its_time_went(tmp_path):
    """A listener that holds the tick three periods: the loop keeps that tick's record, with
    the time by phase (the orders, the world step, each listener) and the collector's, and
    no record of the ticks within their period; and every tick's phases in the run's summary."""
    cfg, model, data = _small_world(tmp_path)
    period = 1.0 / 30.0

    def stall(outcome) -> None:
        if outcome.events.seq == 4:
            time.sleep(3.0 * period)

    with LinkHub(cfg.links, cfg.arbitration) as hub:
        stats = run_realtime(model, data, hub, 30.0, None, [stall], should_stop=lambda: data.time >= 0.3 - 1e-9)
    slow = [t for t in stats.slow_ticks if t["sim_s"] == pytest.approx(4 * period, abs=1e-3)]
    assert len(slow) == 1, stats.slow_ticks
    assert slow[0]["tick_ms"] >= 3e3 * period
    assert slow[0][stall.__qualname__] >= 3e3 * period  # the stalling listener's phase
    assert {"orders", "world", "world_off_cpu", "gc_ms"} <= set(slow[0])
    assert slow[0]["world_off_cpu"] <= slow[0]["world"]
    assert set(slow[0]["world_waits"]) == {"waited", "preempted", "major_faults"}
    stages = slow[0]["world_stages"]  # the slow tick's world step, by stage (the world's, the ice's)
    assert {"ships", "tile switches", "ice: engine", "ice: contacts", "publish"} <= set(stages)
    assert sum(stages.values()) <= slow[0]["world"] + 0.1
    assert all(t["tick_ms"] > 2e3 * period for t in stats.slow_ticks)  # only ticks over two periods
    assert stats.summary()["slow_ticks"] == stats.slow_ticks
    phases = stats.summary()["phase_ms"]  # every tick's phases, over the run
    assert {"orders", "world", stall.__qualname__} <= set(phases)
    assert phases["world"]["ticks"] == stats.ticks
    assert stats.summary()["world_stage_ms"]["ice: engine"]["ticks"] == stats.ticks  # every step's stages
    assert phases[stall.__qualname__]["max"] >= 3e3 * period > phases[stall.__qualname__]["median"]


def test_the_loop_thread_runs_in_the_real_time_class_where_allowed_and_says_what_it_got():
    from bridge_node.node.realtime_loop import thread_scheduling
    with thread_scheduling("normal", 10) as got:
        assert got == "normal" and os.sched_getscheduler(0) == os.SCHED_OTHER
    with thread_scheduling("fifo", 10) as got:  # a refusal is reported, not raised
        inside = os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK, os.sched_getparam(0).sched_priority
        started = []
        worker = threading.Thread(target=lambda: started.append(os.sched_getscheduler(0)))
        worker.start()
        worker.join()
    if got == "fifo 10":
        assert inside == (os.SCHED_FIFO, 10)
        assert started == [os.SCHED_OTHER]  # a thread the loop starts runs in the normal class
    else:  # a machine that does not allow it (no root, no CAP_SYS_NICE): the loop says why and runs normal
        assert got.startswith("normal (fifo refused: ") and inside[0] == os.SCHED_OTHER
    assert os.sched_getscheduler(0) == os.SCHED_OTHER  # back to normal after the loop
    with thread_scheduling("fifo", 0) as got:  # a priority the class refuses
        assert got.startswith("normal (fifo refused: ") and os.sched_getscheduler(0) == os.SCHED_OTHER
