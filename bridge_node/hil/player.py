"""Playing a scenario through the software console, and judging its expectations from the
instrument outputs read back.

All times are the console's monotonic clock, measured from the scenario's start: when an
expectation is met is when the console read the output that met it, as a bench tester
would see it on the instruments.
"""
from __future__ import annotations

import math
import random
import time
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field

from bridge_node.hil.console_links import AlarmReading, ConsoleLink, Order, Reading
from bridge_node.hil.console_registry import make_console_link
from bridge_node.hil.scenario import QUANTITIES, Expectation, Fault, Scenario
from bridge_node.hil.settings import ConsoleConfig
from bridge_node.common.errors import UserError
from sim_core.ship.orders import OrderKind
from sim_core.ship.searchlights import SearchlightOrder

TICK_S = 0.01  # the player's loop period, s
RAMP_STEP_PCT = 0.5  # a lever ramp sends a new order when the lever has moved this much
BusOff = Callable[[str, bool], None]  # (console role, True: adapter gone / False: back)


class Console:
    """Every end of a console config, opened and ticked together; a context manager."""

    def __init__(self, config: ConsoleConfig) -> None:
        self.ends: dict[str, ConsoleLink] = {s.role: make_console_link(s) for s in config.links}
        self._stack = ExitStack()

    def __enter__(self) -> Console:
        try:
            for end in self.ends.values():
                self._stack.enter_context(end)
        except BaseException:
            self._stack.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self._stack.close()

    def tick(self, now: float) -> list[Reading | AlarmReading]:
        """Tick every end (``now``: monotonic s); what came back."""
        return [r for end in self.ends.values() for r in end.tick(now)]

    def wait_ready(self, timeout: float, alive: Callable[[], str | None] = lambda: None) -> None:
        """Wait until the node's outputs come back on every end (it is up and publishing);
        UserError after ``timeout`` s, or as soon as ``alive()`` says why the node is gone."""
        heard: set[str] = set()
        deadline = time.monotonic() + timeout
        while heard != set(self.ends):
            heard |= {r.role for r in self.tick(time.monotonic()) if isinstance(r, Reading)}
            gone = alive()
            if gone:
                raise UserError(gone)
            if time.monotonic() > deadline:
                raise UserError(f"no instrument outputs from the node on console end(s) "
                                f"{sorted(set(self.ends) - heard)} within {timeout:g} s")
            time.sleep(TICK_S)


@dataclass
class Outcome:
    """One expectation judged: passed, what was measured (text, and the value in the
    scenario's unit), and when it was met (s after ``after_s``); ``pending`` while its
    window is still open."""

    expectation: Expectation
    passed: bool
    measured: str
    value: float | None = None
    elapsed_s: float | None = None
    pending: bool = False


@dataclass
class ScenarioResult:
    """A scenario played: its outcomes, how long it ran (s) and what each end sent in it."""

    name: str
    path: str
    outcomes: list[Outcome]
    duration_s: float
    sent: dict[str, dict] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return all(o.passed for o in self.outcomes)


def check_plan(scenario: Scenario, path: str, console: Console, bus_off: BusOff | None) -> None:
    """UserError if the console cannot play ``scenario``: a role it lacks, an order or fault
    an end cannot give, an alarm expectation without an NMEA 0183 end."""
    ends = console.ends
    for role in scenario.links:
        if role not in ends:
            raise UserError(f"{path}: links = {scenario.links}: the console has no {role!r} end "
                            f"(it has {sorted(ends)})")
    for i, a in enumerate(scenario.actions):
        kind = _order(a).kind
        if not ends[a.link].supports(kind):
            raise UserError(f"{path}: actions.{i}: the {a.link} end ({ends[a.link].kind}) has no {kind} register")
    for i, f in enumerate(scenario.faults):
        if f.link not in ends:
            raise UserError(f"{path}: faults.{i}.link = {f.link!r}: the console has no such end")
        end = ends[f.link]
        why = end.unsupported(f)
        if f.kind == "bus_off" and end.kind == "can" and bus_off is not None:
            why = None
        if why:
            raise UserError(f"{path}: faults.{i}.kind = {f.kind!r}: {why}")
    for i, e in enumerate(scenario.expect):
        if e.link is not None and e.link not in ends:
            raise UserError(f"{path}: expect.{i}.link = {e.link!r}: the console has no such end")
        if e.alarm is not None and not any(end.kind == "nmea0183" for end in ends.values()):
            raise UserError(f"{path}: expect.{i}.alarm: alarms come back on ALR only; the console needs an "
                            "nmea0183 end")


def _order(action) -> Order:
    if action.helm_deg is not None:
        return Order(OrderKind.RUDDER, math.radians(action.helm_deg))
    if action.searchlight is not None:
        light = action.searchlight
        return Order(OrderKind.SEARCHLIGHT, SearchlightOrder(light.light, light.on, math.radians(light.bearing_deg),
                                                   math.radians(light.elevation_deg)))
    if action.telegraph is not None:
        return Order(OrderKind.TELEGRAPH, action.telegraph)
    return Order(OrderKind.LEVER, action.lever_pct)


def play(console: Console, scenario: Scenario, path: str, bus_off: BusOff | None = None) -> ScenarioResult:
    """Play ``scenario`` in real time through ``console``; stops as soon as every
    expectation is decided and every action and fault is over."""
    check_plan(scenario, path, console, bus_off)
    for role, end in console.ends.items():  # an end this scenario does not use stays silent
        if role not in scenario.links:
            end.held.clear()
    readings: list[Reading | AlarmReading] = []
    sent_before = {role: end.sent.copy() for role, end in console.ends.items()}
    actions = sorted(scenario.actions, key=lambda a: a.at_s)
    faults = [(f, random.Random(f"{scenario.seed}/{i}")) for i, f in enumerate(scenario.faults)]
    started: set[int] = set()
    ended: set[int] = set()
    ramps: dict[str, tuple[float, float, float, float]] = {}  # role -> (t0, from %, to %, t1)
    lever: dict[str, float] = {}  # role -> the last lever order sent, %
    last_event = max([a.at_s + a.ramp_s for a in actions] + [f.end_s for f, _ in faults] + [0.0])
    start = time.monotonic()
    next_judge = 0.0
    while True:
        now = time.monotonic()
        t = now - start
        while actions and actions[0].at_s <= t:
            a = actions.pop(0)
            if a.lever_pct is not None and a.ramp_s > 0:
                ramps[a.link] = (a.at_s, lever.get(a.link, 0.0), a.lever_pct, a.at_s + a.ramp_s)
                continue
            if a.lever_pct is not None:
                lever[a.link] = a.lever_pct
                ramps.pop(a.link, None)
            console.ends[a.link].order(_order(a), now)
        for role, (t0, lo, hi, t1) in list(ramps.items()):
            value = hi if t >= t1 else lo + (hi - lo) * (t - t0) / (t1 - t0)
            if abs(value - lever.get(role, math.nan)) >= RAMP_STEP_PCT or t >= t1:
                lever[role] = value
                console.ends[role].order(Order(OrderKind.LEVER, value), now)
            if t >= t1:
                del ramps[role]
        for i, (f, rng) in enumerate(faults):
            if i not in started and f.at_s <= t:
                started.add(i)
                _fault(console, f, rng, True, bus_off)
            if i in started and i not in ended and f.end_s <= t:
                ended.add(i)
                _fault(console, f, rng, False, bus_off)
        readings += console.tick(now)
        if t >= next_judge:
            next_judge = t + 0.25
            outcomes = judge(scenario.expect, readings, start, t)
            if t >= scenario.end_s or (t >= last_event and not any(o.pending for o in outcomes)):
                break
        time.sleep(TICK_S)
    for i, (f, rng) in enumerate(faults):  # faults never outlive their scenario
        if i in started and i not in ended:
            _fault(console, f, rng, False, bus_off)
    outcomes = [o if not o.pending else _unmet(o.expectation, readings, start) for o in outcomes]
    return ScenarioResult(scenario.name, path, outcomes, round(t, 2),
                          {role: dict(end.sent - sent_before[role]) for role, end in console.ends.items()})


def _fault(console: Console, fault: Fault, rng: random.Random, begin: bool, bus_off: BusOff | None) -> None:
    """Begin or end one fault on its console end (a bus-off through the bench)."""
    end = console.ends[fault.link]
    if fault.kind == "bus_off":
        bus_off(fault.link, begin)
    elif begin:
        end.inject(fault, rng)
    else:
        end.clear(fault)


def judge(expectations: list[Expectation], readings: list[Reading | AlarmReading], start: float,
          t: float) -> list[Outcome]:
    """Each expectation judged from the readings so far (``t``: s since ``start``): met,
    failed once its window has passed, else pending."""
    out = []
    for e in expectations:
        outcome = _met(e, readings, start)
        if outcome is None:
            outcome = (Outcome(e, False, "", pending=True) if t < e.end_s else _unmet(e, readings, start))
        out.append(outcome)
    return out


def _window(e: Expectation, readings: list, start: float, kind: type) -> list:
    return [r for r in readings if isinstance(r, kind) and e.after_s <= r.time - start <= e.end_s
            and (e.link is None or r.role == e.link)]


def _values(e: Expectation, readings: list, start: float) -> list[Reading]:
    quantity = "rudder_angle" if e.quantity == "rudder_rate" else e.quantity
    rows = [r for r in _window(e, readings, start, Reading) if r.quantity == quantity]
    if e.quantity == "rudder_rate" and rows:  # one end's readings: their times are comparable
        rows = [r for r in rows if r.role == rows[0].role]
    return rows


def _rudder_rate(e: Expectation, rows: list[Reading], start: float) -> tuple[float, float, float] | None:
    """(mean rate rad/s, when the rudder got furthest towards ``to_deg`` s after ``after_s``,
    the angle it got to, rad) from its first crossing of ``from_deg``; None if it never
    crossed it. The angle reached is ``to_deg`` once it got there."""
    a, b = math.radians(e.from_deg), math.radians(e.to_deg)
    d = 1.0 if b > a else -1.0
    first = next((i for i, r in enumerate(rows) if d * (r.value - a) >= 0.0), None)
    if first is None:
        return None
    later = rows[first + 1:]
    reached = next((r for r in later if d * (r.value - b) >= 0.0), None)
    end = reached or max(later, key=lambda r: d * r.value, default=None)
    if end is None or end.time <= rows[first].time:
        return None
    angle = b if reached else end.value
    return abs(angle - a) / (end.time - rows[first].time), end.time - start - e.after_s, angle


def _met(e: Expectation, readings: list, start: float) -> Outcome | None:
    """The outcome if the expectation has been met by the readings, else None."""
    if e.alarm is not None and e.state == "absent":
        return None  # decided when its window has passed
    if e.alarm is not None:
        want = e.state == "raised"
        hit = next((r for r in _window(e, readings, start, AlarmReading) if r.number == e.alarm and r.active == want),
                   None)
        if hit is None:
            return None
        elapsed = hit.time - start - e.after_s
        return Outcome(e, True, f"ALR {e.alarm:03d} {e.state} after {elapsed:.2f} s ({hit.text!r})", None, elapsed)
    lo, hi = e.bounds_si()
    factor = QUANTITIES[e.quantity][1]
    rows = _values(e, readings, start)
    if e.quantity == "rudder_rate":
        got = _rudder_rate(e, rows, start)
        if got is None or got[2] != math.radians(e.to_deg) or not lo <= got[0] <= hi:
            return None
        return Outcome(e, True, f"{got[0] / factor:.2f} {e.unit} from {e.from_deg:g} to {e.to_deg:g} deg",
                       got[0] / factor, got[1])
    if e.hold:  # decided when its window has passed
        return None
    hit = next((r for r in rows if lo <= r.value <= hi), None)
    if hit is None:
        return None
    elapsed = hit.time - start - e.after_s
    return Outcome(e, True, f"{hit.value / factor:.2f} {e.unit} after {elapsed:.2f} s", hit.value / factor, elapsed)


def _unmet(e: Expectation, readings: list, start: float) -> Outcome:
    """An expectation whose window has passed unmet: failed with what was measured instead
    (or, for ``hold`` and ``absent``, judged on the whole window)."""
    if e.alarm is not None and e.state == "absent":
        raised = [r for r in _window(e, readings, start, AlarmReading) if r.number == e.alarm and r.active]
        if not raised:
            return Outcome(e, True, f"no ALR {e.alarm:03d} raised in the window")
        return Outcome(e, False, f"ALR {e.alarm:03d} raised at {raised[0].time - start - e.after_s:.2f} s "
                                 f"({raised[0].text!r})", None, raised[0].time - start - e.after_s)
    if e.alarm is not None:
        seen = sorted({f"{r.number:03d}{'+' if r.active else '-'}" for r in _window(e, readings, start, AlarmReading)})
        return Outcome(e, False, f"no ALR {e.alarm:03d} {e.state} in the window "
                                 f"(ALR seen: {', '.join(seen) or 'none'})")
    rows = _values(e, readings, start)
    factor = QUANTITIES[e.quantity][1]
    if not rows:
        return Outcome(e, False, f"no {e.quantity} reading in the window")
    if e.quantity == "rudder_rate":
        got = _rudder_rate(e, rows, start)
        if got is None:
            return Outcome(e, False, f"rudder never passed {e.from_deg:g} deg (last "
                                     f"{math.degrees(rows[-1].value):.1f} deg)")
        return Outcome(e, False, f"{got[0] / factor:.2f} {e.unit} from {e.from_deg:g} to "
                                 f"{math.degrees(got[2]):.1f} deg", got[0] / factor, got[1])
    lo, hi = e.bounds_si()
    if e.hold:
        out = [r for r in rows if not lo <= r.value <= hi]
        span = f"{min(r.value for r in rows) / factor:.2f}..{max(r.value for r in rows) / factor:.2f} {e.unit}"
        if not out:
            return Outcome(e, True, f"held: {span} over {len(rows)} readings")
        return Outcome(e, False, f"left the band: {out[0].value / factor:.2f} {e.unit} at "
                                 f"{out[0].time - start - e.after_s:.2f} s ({span})", out[0].value / factor)
    closest = min(rows, key=lambda r: max(lo - r.value, r.value - hi))
    return Outcome(e, False, f"closest {closest.value / factor:.2f} {e.unit} at "
                             f"{closest.time - start - e.after_s:.2f} s", closest.value / factor)

