"""Scenario files (TOML): a timeline of console actions and link faults, and expectations
judged only from what comes back on the instrument outputs.

Times are seconds from the scenario's start (``at_s``, ``after_s``). Console links are named
by their role: ``primary`` and ``backup`` give orders (the node's first and second source),
``panel`` is the instrument and alarm panel (NMEA 0183, listen only). A scenario written for
some link kinds names them (``kinds``, one per link: can, nmea, modbus), and ``hil run``
gives it a bench of those kinds; without ``kinds`` it runs over ``--links``. Units as a bench tester
reads them: deg, rpm, deg/min, deg/s, percent; SI inside (``Expectation.bounds_si``).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from bridge_node.hil.toml_file import load_toml_model
from sim_core.params import Params
from sim_core.ship.particulars import TELEGRAPH_POSITIONS
from sim_core.ship.searchlights import MAX_SEARCHLIGHTS

ROLES = ("primary", "backup", "panel")
ORDER_ROLES = ("primary", "backup")
LINK_KINDS = ("can", "nmea", "modbus")  # what a console end can be (``hil run --links``)
# quantity -> (unit in scenario files, SI per unit)
QUANTITIES = {"rudder_angle": ("deg", math.radians(1.0)), "shaft_speed": ("rpm", 1.0 / 60.0),
              "heading": ("deg", math.radians(1.0)), "rate_of_turn": ("deg/min", math.radians(1.0) / 60.0),
              "rudder_rate": ("deg/s", math.radians(1.0))}
FAULT_KINDS = ("drop", "delay", "duplicate", "corrupt", "garbage", "disconnect", "bus_off")
CORRUPTIONS = ("format", "checksum", "dlc", "range")  # format: the link's framing (NMEA checksum, CAN DLC, MBAP)
Seconds = Annotated[float, Field(ge=0.0, le=3600.0)]


class SearchlightAction(Params):
    """A searchlight order: light 0..3 switched on or off and aimed, deg from the bow (+
    starboard) and above the horizontal (- down)."""

    light: int = Field(ge=0, le=MAX_SEARCHLIGHTS - 1)
    on: bool = True
    bearing_deg: float = Field(ge=-180.0, le=180.0)
    elevation_deg: float = Field(ge=-90.0, le=90.0)


class Action(Params):
    """One console action at ``at_s``: a helm order (deg, + starboard), a telegraph step,
    a lever order (percent), ramped linearly over ``ramp_s`` from the lever's last value, or
    a searchlight order."""

    at_s: Seconds
    link: Literal[ORDER_ROLES] = "primary"
    helm_deg: float | None = Field(None, ge=-90.0, le=90.0)
    telegraph: Literal[TELEGRAPH_POSITIONS] | None = None
    lever_pct: float | None = Field(None, ge=-100.0, le=100.0)
    ramp_s: float = Field(0.0, ge=0.0, le=600.0)
    searchlight: SearchlightAction | None = None

    @model_validator(mode="after")
    def _one_order(self) -> "Action":
        orders = ("helm_deg", "telegraph", "lever_pct", "searchlight")
        given = [k for k in orders if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"an action gives exactly one of {', '.join(orders)} (got {given or 'none'})")
        if self.ramp_s and self.lever_pct is None:
            raise ValueError("ramp_s applies to lever_pct only")
        return self


class Fault(Params):
    """A fault on one console link from ``at_s`` for ``duration_s``: ``drop``, ``delay``
    (``delay_s``), ``duplicate`` or ``corrupt`` (``corrupt``: checksum, dlc or range) each
    outgoing message with ``probability`` (``format``: the link's own framing error, a bad NMEA
    checksum, a short CAN frame, or a Modbus register server's reply with a malformed MBAP header); ``garbage``: ``count`` random frames or bytes at
    once; ``disconnect``: the console's end closed, then reopened; ``bus_off``: the CAN
    adapter's pty pair gone, then back (hil run only). Random draws come from the scenario's
    seed and the fault's index: a rerun injects the same faults."""

    at_s: Seconds
    link: Literal[ROLES] = "primary"
    kind: Literal[FAULT_KINDS]
    duration_s: float = Field(1.0, gt=0.0, le=600.0)
    probability: float = Field(1.0, gt=0.0, le=1.0)
    delay_s: float = Field(0.5, gt=0.0, le=30.0)
    corrupt: Literal[CORRUPTIONS] = "range"
    count: int = Field(20, ge=1, le=10000)

    @property
    def end_s(self) -> float:
        return self.at_s + self.duration_s


class Expectation(Params):
    """What must come back within ``within_s`` of ``after_s``: a ``quantity`` reaching
    [``min``, ``max``] (units in ``QUANTITIES``; ``rudder_rate``: the rudder's mean rate from
    ``from_deg`` to ``to_deg``), or ``alarm`` number ``state`` on ALR (raised, cleared, or
    absent: not raised in the window). ``hold``: every reading in the window must be in the
    band, not just one. ``link``: judge that console link's readings only (default: any)."""

    name: str = ""
    after_s: Seconds
    within_s: float = Field(gt=0.0, le=3600.0)
    quantity: Literal[tuple(QUANTITIES)] | None = None
    min: float | None = None
    max: float | None = None
    from_deg: float | None = Field(None, ge=-90.0, le=90.0)
    to_deg: float | None = Field(None, ge=-90.0, le=90.0)
    alarm: int | None = Field(None, ge=0, le=999)
    state: Literal["raised", "cleared", "absent"] = "raised"
    hold: bool = False
    link: Literal[ROLES] | None = None

    @model_validator(mode="after")
    def _checks(self) -> "Expectation":
        if (self.quantity is None) == (self.alarm is None):
            raise ValueError("an expectation names exactly one of quantity, alarm")
        if self.quantity is not None and self.min is None and self.max is None:
            raise ValueError(f"quantity = {self.quantity!r} needs min, max or both")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError(f"min = {self.min} is above max = {self.max}")
        if self.hold and (self.quantity is None or self.quantity == "rudder_rate"):
            raise ValueError("hold = true goes with a quantity other than rudder_rate")
        rate = self.quantity == "rudder_rate"
        if rate != (self.from_deg is not None and self.to_deg is not None) or (rate and self.from_deg == self.to_deg):
            raise ValueError("from_deg and to_deg (different) go with quantity = 'rudder_rate', and only with it")
        return self

    @property
    def end_s(self) -> float:
        return self.after_s + self.within_s

    @property
    def unit(self) -> str:
        return QUANTITIES[self.quantity][0] if self.quantity else ""

    def bounds_si(self) -> tuple[float, float]:
        """[min, max] in SI (rad, rad/s, rev/s); open ends infinite."""
        factor = QUANTITIES[self.quantity][1]
        lo = -math.inf if self.min is None else self.min * factor
        return lo, math.inf if self.max is None else self.max * factor

    def title(self) -> str:
        """The expectation's name, or one made from what it asks."""
        if self.name:
            return self.name
        if self.alarm is not None:
            return f"alarm {self.alarm:03d} {self.state} within {self.within_s:g} s of t={self.after_s:g} s"
        band = f"[{'' if self.min is None else f'{self.min:g}'}, {'' if self.max is None else f'{self.max:g}'}]"
        how = "holds" if self.hold else "in"
        return f"{self.quantity} {how} {band} {self.unit} within {self.within_s:g} s of t={self.after_s:g} s"


class Scenario(Params):
    """A scenario file: the console links it needs, its actions, faults and expectations."""

    name: str = Field(min_length=1, max_length=80)
    description: str = ""
    seed: int = Field(0, ge=0, le=2**32 - 1)
    links: list[Literal[ORDER_ROLES]] = Field(["primary"], min_length=1)
    kinds: list[Literal[LINK_KINDS]] | None = Field(None, min_length=1, max_length=2)  # per link; None: --links
    actions: list[Action] = Field(default_factory=list)
    faults: list[Fault] = Field(default_factory=list)
    expect: list[Expectation] = Field(min_length=1)

    @model_validator(mode="after")
    def _roles(self) -> "Scenario":
        if self.kinds is not None and len(self.kinds) != len(self.links):
            raise ValueError(f"kinds = {self.kinds}: give one link kind for each of links = {self.links}")
        for what, items in (("actions", self.actions), ("faults", self.faults)):
            for i, item in enumerate(items):
                if item.link in ORDER_ROLES and item.link not in self.links:
                    raise ValueError(f"{what}.{i}.link = {item.link!r} is not in links = {self.links}")
        return self

    @property
    def end_s(self) -> float:
        """When the last action, fault or expectation window is over, s."""
        return max([a.at_s + a.ramp_s for a in self.actions] + [f.end_s for f in self.faults]
                   + [e.end_s for e in self.expect])


def load_scenario(path: str | Path) -> Scenario:
    """A scenario file, validated; ConfigError naming the file, line and key otherwise."""
    return load_toml_model(path, Scenario, "scenario file")
