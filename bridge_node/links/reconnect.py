"""Reconnect back-off shared by the links: retry soon, then less often, capped."""
from __future__ import annotations

import math


class Backoff:
    """Delay before the next attempt: first ``first`` s, doubling per failure up to ``cap``."""

    def __init__(self, first: float = 0.1, cap: float = 1.0) -> None:
        self.first, self.cap = first, cap
        self.delay = first
        self.next_try = -math.inf

    def ready(self, now: float) -> bool:
        return now >= self.next_try

    def failed(self, now: float) -> None:
        self.next_try = now + self.delay
        self.delay = min(self.cap, 2.0 * self.delay)

    def succeeded(self) -> None:
        self.delay = self.first
        self.next_try = -math.inf
