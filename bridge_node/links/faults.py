"""A fault the instructor puts on one of the node's links, as a faulty cable or console
would cause it (the kinds of the HIL bench's faults, ``bridge_node.hil.scenario``): the
link's device disconnected (closed, and not reopened while the fault lasts: the link-down
alarm is raised), or each order it reads dropped, corrupted (refused, as a checksum error
would refuse it), duplicated or delayed, each with a probability.

The random draws come from a generator seeded with the fault's seed (the step it was
applied at), one draw per order: a re-simulation of the session record, which gives the
links the same orders at the same ticks and applies the fault at the same step, draws the
same."""
from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass, field

from bridge_node.links.messages import ControlInput

LINK_FAULT_KINDS = ("none", "disconnect", "drop", "corrupt", "duplicate", "delay")


@dataclass(frozen=True)
class LinkFault:
    """A fault on the link named ``link``: ``kind`` from ``LINK_FAULT_KINDS`` ("none": the
    fault cleared), each order hit with ``probability``, a delayed one by ``delay_s``;
    ``seed`` for the draws (the step it was applied at)."""

    link: str
    kind: str
    probability: float = 1.0
    delay_s: float = 0.0
    seed: int = 0


@dataclass
class FaultyLine:
    """The orders of a link through its fault: what reaches the arbiter, and counts by
    kind of what the fault did."""

    fault: LinkFault
    rng: random.Random = field(init=False)
    held: list[tuple[float, ControlInput]] = field(default_factory=list)  # (release at s, order) while delayed

    def __post_init__(self) -> None:
        self.rng = random.Random(self.fault.seed)

    @property
    def disconnects(self) -> bool:
        return self.fault.kind == "disconnect"

    @property
    def over(self) -> bool:
        """Cleared, with no delayed order still on its way."""
        return self.fault.kind == "none" and not self.held

    def orders(self, got: list[ControlInput], now: float, count: Callable[[str], None]) -> list[ControlInput]:
        """The orders read at ``now`` (s) after the fault, with the delayed orders now due;
        ``count(kind)`` is told of each order the fault dropped or corrupted."""
        out = []
        for order in got:
            if self.fault.kind in ("none", "disconnect") or self.rng.random() >= self.fault.probability:
                out.append(order)
            elif self.fault.kind in ("drop", "corrupt"):
                count(f"fault_{self.fault.kind}")
            elif self.fault.kind == "duplicate":
                out += [order, order]
            else:
                self.held.append((now + self.fault.delay_s, order))
        due = [order for at, order in self.held if at <= now]
        self.held = [(at, order) for at, order in self.held if at > now]
        return due + out
