"""The exercise's one tick, its pacer and typed orders: what every mode (run, links monitor,
track replay, session re-simulation) steps through."""
import math
import time

import pytest

from bridge_node.exercise.pacer import Pacer
from bridge_node.exercise.tick import ExerciseTick, StepListener
from bridge_node.links.arbiter import Decision
from bridge_node.links.messages import Alarm, ControlInput
from bridge_node.node.config import load_config
from bridge_node.node.world_setup import open_water_world
from sim_core.ship.orders import OrderKind
from sim_core.ship.searchlights import SearchlightOrder
from sim_core.world import Controls


def test_an_order_has_one_value_type_per_kind():
    assert ControlInput(0.0, "helm", "rudder", 0.1).kind is OrderKind.RUDDER
    assert ControlInput(0.0, "helm", OrderKind.LEVER, 50).value == 50.0  # an integer percent is a number
    with pytest.raises(TypeError, match="a rudder order's value is a float"):
        ControlInput(0.0, "helm", OrderKind.RUDDER, "hard_a_port")
    with pytest.raises(TypeError, match="searchlight"):
        ControlInput(0.0, "helm", OrderKind.SEARCHLIGHT, 1.0)
    with pytest.raises(ValueError):
        ControlInput(0.0, "helm", "bow_thruster", 1.0)
    assert ControlInput(0.0, "helm", OrderKind.SEARCHLIGHT, SearchlightOrder(0, True, None, None)).value.on
    assert f"{OrderKind.TELEGRAPH}" == "telegraph"  # prints and serialises as its name


def test_the_pacer_counts_an_overrun_and_restarts_rather_than_bursts():
    pacer = Pacer(0.5)
    pacer.due = time.monotonic() - 1.0  # a tick that ended a second late: two periods
    before = time.monotonic()
    pacer.wait()
    assert pacer.overruns == 1 and pacer.due >= before  # the schedule restarted from now: no burst
    restarted = pacer.due
    pacer.advance()
    assert pacer.due == restarted + 0.5  # the next tick is a period after the restarted one
    pacer.wait()
    assert pacer.slack() <= 0.0  # it slept until the tick was due
    late = Pacer(0.01, behind_s=5.0)
    late.due = time.monotonic() - 1.0
    late.wait()
    assert late.overruns == 1 and late.due < before  # within behind_s: it keeps its schedule


class _Orders:
    """An order source that gives a fixed order list, one per tick."""

    def __init__(self, controls: list[Controls]) -> None:
        self.controls = controls

    def poll(self, now: float) -> Decision:
        return Decision(self.controls.pop(0), [Alarm(1, f"polled at {now}", True)] if now == 0.0 else [], {}, now)


class _Recorder(StepListener):
    def __init__(self, log: list) -> None:
        self.log, self.stopped = log, 0

    def on_polled(self, seq: int, now: float) -> None:
        self.log.append(("polled", seq, now))

    def on_step(self, outcome) -> None:
        self.log.append(("step", outcome.events.seq, outcome.now))

    def stop(self) -> None:
        self.stopped += 1


def test_one_tick_steps_the_world_and_fans_the_outcome_out_in_order():
    model, data = open_water_world(load_config(), None)
    log, outcomes = [], []
    recorder = _Recorder(log)
    nan = [Controls(rudder=math.nan, telegraph="full_ahead")] * 3
    with ExerciseTick(model, data, _Orders(nan), [recorder, outcomes.append]) as tick:
        for k in range(3):
            tick(0.05, float(k))
    assert log == [("polled", 0, 0.0), ("step", 1, 0.0), ("polled", 1, 1.0), ("step", 2, 1.0),
                   ("polled", 2, 2.0), ("step", 3, 2.0)]
    assert [o.events.seq for o in outcomes] == [1, 2, 3] and data.time == pytest.approx(0.15)
    assert outcomes[0].alarms[0].text == "polled at 0.0"  # the source's alarm changes travel with the step
    assert outcomes[0].input_time == 0.0 and outcomes[0].controls.telegraph == "full_ahead"
    # three refused rudder orders within the window: the refused-orders alarm, in the step that made it
    assert [a.number for a in outcomes[2].alarms] == [121] and tick.refusals.counts["rudder refused"] == 3
    tick.stop()
    assert recorder.stopped == 1  # stopped once, though asked twice
