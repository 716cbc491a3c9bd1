"""Order arbitration on an explicit clock, no hardware: orders are fed as ``ControlInput``
rows with their times, and ``decide`` is asked at chosen instants."""
import math

import pytest

from bridge_node.links.arbiter import ALARM_NUMBERS, OrderArbiter
from bridge_node.links.messages import ControlInput
from bridge_node.links.settings import ArbitrationSettings
from sim_core.ship.orders import OrderKind

TIMEOUTS = {"can": 1.0, "nmea": 1.0}  # s
STALE, FAIL_SAFE = ALARM_NUMBERS["rudder"]


def arbiter(fail_safe: str = "midships_stop", **channels) -> OrderArbiter:
    sources = channels or {"rudder": ["can", "nmea"]}
    return OrderArbiter(ArbitrationSettings(fail_safe=fail_safe, fail_safe_after_s=2.0, **sources), TIMEOUTS)


def rudder(t: float, source: str, deg: float) -> ControlInput:
    return ControlInput(t, source, OrderKind.RUDDER, math.radians(deg))


def changes(decision) -> set[tuple[int, bool]]:
    return {(a.number, a.active) for a in decision.alarms}


def test_hands_over_when_the_first_source_goes_stale_and_back_when_it_returns():
    arb = arbiter()
    arb.feed([rudder(0.0, "can", 10.0), rudder(0.0, "nmea", -5.0)])
    d = arb.decide(0.0)
    assert d.active["rudder"] == "can" and d.controls.rudder == pytest.approx(math.radians(10.0))
    assert not d.alarms
    arb.feed([rudder(0.9, "nmea", -6.0)])
    d = arb.decide(1.0)  # can's order is 1.0 s old: still fresh, and already passed on
    assert d.active["rudder"] == "can" and d.controls.rudder is None and not d.alarms
    d = arb.decide(1.5)  # can silent for 1.5 s: stale; nmea (0.6 s) takes over with its latest order
    assert d.active["rudder"] == "nmea" and d.controls.rudder == pytest.approx(math.radians(-6.0))
    assert changes(d) == {(STALE, True)}
    arb.feed([rudder(1.8, "nmea", -7.0)])
    d = arb.decide(1.8)
    assert d.active["rudder"] == "nmea" and d.controls.rudder == pytest.approx(math.radians(-7.0)) and not d.alarms
    arb.feed([rudder(2.0, "can", 12.0)])  # can is back, nmea still fresh: can wins again
    d = arb.decide(2.0)
    assert d.active["rudder"] == "can" and d.controls.rudder == pytest.approx(math.radians(12.0))
    assert changes(d) == {(STALE, False)}
    assert not arb.decide(2.1).alarms  # nothing more to say


def test_fail_safe_after_every_source_is_stale_then_cleared():
    arb = arbiter(engine=["can"], rudder=["can", "nmea"])
    arb.feed([rudder(0.0, "can", 10.0), rudder(0.0, "nmea", -5.0),
              ControlInput(0.0, "can", OrderKind.TELEGRAPH, "half_ahead")])
    d = arb.decide(0.0)
    assert d.controls.rudder == pytest.approx(math.radians(10.0)) and d.controls.telegraph == "half_ahead"
    d = arb.decide(1.5)  # every source stale from now on
    assert d.active == {"rudder": None, "engine": None}
    assert changes(d) == {(STALE, True), (ALARM_NUMBERS["engine"][0], True)}
    assert d.controls.rudder is None and d.controls.telegraph is None  # nothing new, no fail-safe yet
    d = arb.decide(3.4)  # 1.9 s of silence: still waiting
    assert not d.alarms and d.controls.rudder is None
    d = arb.decide(3.5)  # 2.0 s: midships and stop
    assert d.controls.rudder == 0.0 and d.controls.telegraph == "stop"
    assert changes(d) == {(FAIL_SAFE, True), (ALARM_NUMBERS["engine"][1], True)}
    d = arb.decide(4.0)  # applied once, not again
    assert not d.alarms and d.controls.rudder is None and d.controls.telegraph is None
    arb.feed([rudder(5.0, "nmea", 3.0)])  # one source back: its order, the rudder's alarms cleared
    d = arb.decide(5.0)
    assert d.active["rudder"] == "nmea" and d.controls.rudder == pytest.approx(math.radians(3.0))
    assert changes(d) == {(STALE, False), (FAIL_SAFE, False)}
    assert d.controls.telegraph is None  # the engine stays as the fail-safe left it


def test_hold_fail_safe_gives_no_order():
    arb = arbiter(fail_safe="hold")
    arb.feed([rudder(0.0, "can", 10.0)])
    arb.decide(0.0)
    arb.decide(1.5)
    d = arb.decide(3.5)
    assert changes(d) == {(FAIL_SAFE, True)} and d.controls.rudder is None  # the last order holds


def test_a_source_not_in_the_list_is_counted_but_never_obeyed():
    arb = arbiter()
    arb.feed([rudder(0.0, "wing", 30.0)])
    d = arb.decide(0.0)
    assert arb.counts == {"wing": 1} and d.active["rudder"] is None and d.controls.rudder is None
