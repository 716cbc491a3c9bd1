"""Commands waiting for the tick that applies them: bounded, taken a few at a tick, so that
a flood of commands can neither grow the node's memory nor slow its physics."""
from __future__ import annotations

import threading
from collections import deque
from collections.abc import Sequence
from typing import Protocol

from bridge_node.control.commands import NodeCommand, WireCommand
from sim_core.instructor import Command
from sim_core.world import WorldData, WorldModel

QUEUE_CAPACITY = 64  # commands waiting at most; more are refused ("busy")
PER_TICK = 4  # commands a tick applies at most; the rest wait for the next


class CommandSource(Protocol):
    """Where a tick's instructor commands come from (the control endpoint's queue, a
    session record in a replay)."""

    def take(self, model: WorldModel, data: WorldData) -> tuple[Command | NodeCommand, ...]:
        """The world's and the node's commands for the step about to be taken."""


class CommandQueue:
    """Checked commands from the control endpoint's thread, for the loop's ticks."""

    def __init__(self, capacity: int = QUEUE_CAPACITY, per_tick: int = PER_TICK) -> None:
        self.capacity, self.per_tick = capacity, per_tick
        self._waiting: deque[WireCommand] = deque()
        self._lock = threading.Lock()

    def put(self, command: WireCommand) -> bool:
        """Queue a checked command; False (refused) when the queue is full."""
        with self._lock:
            if len(self._waiting) >= self.capacity:
                return False
            self._waiting.append(command)
            return True

    def take(self, model: WorldModel, data: WorldData) -> tuple[Command | NodeCommand, ...]:
        """At most ``per_tick`` commands, oldest first, as world (or node) commands made against the
        world as it is now (a time of day keeps today's date; a position is placed on the
        field)."""
        with self._lock:
            taken: Sequence[WireCommand] = [self._waiting.popleft()
                                            for _ in range(min(self.per_tick, len(self._waiting)))]
        return tuple(c.to_world(model, data) for c in taken)
