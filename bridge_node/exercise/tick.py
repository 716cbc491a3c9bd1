"""One tick for every mode, fanned out as python-can's ``Notifier`` fans out to ``Listener``.

A tick takes the instructor's commands from one ``CommandSource`` (the control endpoint's
queue, a session record) and the orders of its step from one ``OrderSource`` (the live
links and their arbiter, a session record's links fed from the record, a track log); the
commands to the node act first (a fault put on a link before it is polled, a save point
asked for), then the world steps by dt (its commands applied at the step's start), notes
the orders the ship refused, and hands one ``TickOutcome`` (the step's ``WorldEvents``, the
orders, every alarm change of the step, the tick's clock) to its listeners: link outputs,
the state stream, the session record, the status line, the traffic picture. ``run``, ``links monitor``, ``replay`` of a track and of a session all
step through ``ExerciseTick``; they differ only in the source, the listeners and the
pacing (``bridge_node.exercise.pacer``).
"""
from __future__ import annotations

import resource
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Protocol

from bridge_node.control.queue import CommandSource
from bridge_node.links.arbiter import Decision
from bridge_node.control.commands import NODE_COMMANDS, NodeCommand
from bridge_node.control.save_point import SaveRequest
from bridge_node.links.messages import Alarm
from bridge_node.links.faults import LinkFault
from bridge_node.exercise.order_refusals import OrderRefusals
from sim_core.world import Controls, WorldData, WorldEvents, WorldModel, step


class OrderSource(Protocol):
    """Where a tick's orders come from (``LinkHub``, a replay's source)."""

    def poll(self, now: float) -> Decision:
        """The orders for the step about to be taken at ``now`` (the source's clock, s), and
        the alarm changes they bring (not yet raised)."""

    def fault_link(self, fault: LinkFault, now: float) -> None:
        """Put the instructor's fault on a link (only the live links are given one: a
        replay's source applies the recorded faults itself)."""


@dataclass(frozen=True)
class TickOutcome:
    """What one tick published: the step's events, the orders it obeyed, every alarm change
    of the step (the source's and the refused orders'), the tick's clock (s: monotonic in a
    live run, the source's in a replay), when the newest order in it was read (monotonic s,
    or None), and whether its outputs go out (False while a replay runs ahead to a seek);
    all of the first ship's, the other own ships' orders in ``others``."""

    events: WorldEvents
    controls: Controls
    alarms: tuple[Alarm, ...]
    now: float
    input_time: float | None
    send: bool = True
    node_commands: tuple[NodeCommand, ...] = ()  # the instructor's commands to the node applied at the tick
    others: tuple[Decision, ...] = ()  # the other own ships' orders and alarm changes, as ``events.others``

    @property
    def saves(self) -> list[SaveRequest]:
        """The save points asked for at this tick."""
        return [c for c in self.node_commands if isinstance(c, SaveRequest)]


class StepListener:
    """Gets every tick's outcome, like python-can's ``Listener`` gets every message;
    ``stop`` when the exercise ends (called once by ``ExerciseTick.stop``)."""

    def on_polled(self, seq: int, now: float) -> None:
        """The tick of step ``seq`` has taken its orders at ``now`` (s)."""

    def on_step(self, outcome: TickOutcome) -> None:
        """One step done; ``outcome`` is what it published."""

    def stop(self) -> None:
        """The exercise ended: release what the listener holds."""


class _Callback(StepListener):
    """A plain function as a listener (python-can's ``Notifier`` takes callables too)."""

    def __init__(self, function: Callable[[TickOutcome], None]) -> None:
        self.on_step = function
        self.phase_name = getattr(function, "__qualname__", type(function).__name__)


def as_listener(listener: StepListener | Callable[[TickOutcome], None]) -> StepListener:
    """``listener`` itself, or a function given every outcome wrapped as a listener."""
    return listener if isinstance(listener, StepListener) else _Callback(listener)


class ExerciseTick:
    """The one tick: orders from ``orders``, the world stepped, the outcome to ``listeners``
    (``StepListener`` objects or functions of the outcome) in the order given. A context
    manager: leaving it stops the listeners (once). ``phase_ms`` holds the last tick's wall
    time (ms) by phase: the orders (commands and polling), the world step, and each kind of
    listener: where a slow tick's time went; and ``world_off_cpu``, the part of the world
    step's wall time that the loop's thread did not run (preempted, or waiting: for the
    interpreter lock, for a page from disk); ``world_waits`` says what it waited for: a slow
    step that computed, or one that waited."""

    def __init__(self, model: WorldModel, data: WorldData, orders: OrderSource,
                 listeners: Iterable[StepListener | Callable[[TickOutcome], None]] = (),
                 commands: CommandSource | None = None) -> None:
        self.model, self.data, self.orders, self.commands = model, data, orders, commands
        self.listeners = [as_listener(listener) for listener in listeners]
        self.refusals = OrderRefusals()
        self.phase_ms: dict[str, float] = {}
        self._world_usage = (resource.getrusage(resource.RUSAGE_THREAD),) * 2  # the thread's, about the last step
        self._stopped = False

    def __call__(self, dt: float, now: float, send: bool = True) -> TickOutcome:
        """One tick of dt s at ``now`` (the source's clock, s); ``send`` False: a step run
        ahead, whose outputs do not go out (its alarm changes still do)."""
        t0 = time.perf_counter()
        taken = self.commands.take(self.model, self.data) if self.commands is not None else ()
        node = tuple(c for c in taken if isinstance(c, NODE_COMMANDS))
        for fault in (c for c in node if isinstance(c, LinkFault)):
            self.orders.fault_link(fault, now)
        decision = self.orders.poll(now)
        for listener in self.listeners:
            listener.on_polled(self.data.seq, now)
        t1, cpu1, use1 = time.perf_counter(), time.thread_time(), resource.getrusage(resource.RUSAGE_THREAD)
        events = step(self.model, self.data, dt, decision.every_ships_controls(),
                      tuple(c for c in taken if not isinstance(c, NODE_COMMANDS)))
        alarms = (*decision.alarms, *self.refusals.note(events.rejected, now))
        outcome = TickOutcome(events, decision.controls, alarms, now, decision.input_time, send, node,
                              decision.others)
        # The thread's CPU time from its clock: getrusage's lags by up to a scheduler tick
        t2, cpu2, use2 = time.perf_counter(), time.thread_time(), resource.getrusage(resource.RUSAGE_THREAD)
        phases = self.phase_ms = {"orders": (t1 - t0) * 1e3, "world": (t2 - t1) * 1e3,
                                  "world_off_cpu": max(0.0, t2 - t1 - (cpu2 - cpu1)) * 1e3}
        self._world_usage = use1, use2
        for listener in self.listeners:
            listener.on_step(outcome)
            t3 = time.perf_counter()
            name = getattr(listener, "phase_name", type(listener).__name__)
            phases[name] = phases.get(name, 0.0) + (t3 - t2) * 1e3
            t2 = t3
        return outcome

    @property
    def world_waits(self) -> dict[str, int]:
        """The loop thread's context switches in the last world step (``waited``: it blocked;
        ``preempted``) and its major page faults."""
        before, after = self._world_usage
        return {"waited": after.ru_nvcsw - before.ru_nvcsw, "preempted": after.ru_nivcsw - before.ru_nivcsw,
                "major_faults": after.ru_majflt - before.ru_majflt}

    def stop(self) -> None:
        """Stop every listener; safe to call twice."""
        if self._stopped:
            return
        self._stopped = True
        for listener in self.listeners:
            listener.stop()

    def __enter__(self) -> ExerciseTick:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
