"""The own ship's searchlights as the console steers them: switched on or off, trained
(bearing from the bow) and tilted (elevation), within each light's mount limits. SI: rad.

The static half (``SearchlightMount``: limits and the aim the config gives) sits in the
world model, the commanded state (``SearchlightState``) in the world data; the step
publishes every light's state in ``ShipOutputs.searchlights``, the mount's index order.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from sim_core.ship.model import OrderRejection

SEARCHLIGHT = "searchlight"  # the order's name (``OrderRejection``, the links' order kinds)
MAX_SEARCHLIGHTS = 4  # lights 0..3: what the console's orders can name


@dataclass(frozen=True)
class SearchlightState:
    """One light as commanded: on, bearing rad from the bow (+ starboard), elevation rad
    above the horizontal (- down)."""

    on: bool
    bearing: float
    elevation: float


@dataclass(frozen=True)
class SearchlightMount:
    """One light's limits, rad: train (bearing) and tilt (elevation) ranges; ``default`` is
    its state before any console order."""

    default: SearchlightState
    train: tuple[float, float]
    tilt: tuple[float, float]


@dataclass(frozen=True)
class SearchlightOrder:
    """A console order for light ``index`` (0..3); a None field leaves that as it was."""

    index: int
    on: bool | None = None
    bearing: float | None = None  # rad, + starboard
    elevation: float | None = None  # rad, + up


def _outside(value: float, limits: tuple[float, float]) -> bool:
    return not (math.isfinite(value) and limits[0] <= value <= limits[1])


def order_searchlight(mounts: tuple[SearchlightMount, ...], states: list[SearchlightState],
                      order: SearchlightOrder) -> OrderRejection | None:
    """Apply ``order`` to ``states`` (one per mount). Returns None if taken, else why it was
    refused (the light's previous state held): no such light, or an aim outside its mount's
    train or tilt range."""
    if not 0 <= order.index < len(mounts):
        return OrderRejection(SEARCHLIGHT, True, f"searchlight {order.index} refused: this ship has "
                                                 f"{len(mounts)} searchlight(s)")
    mount, held = mounts[order.index], states[order.index]
    for value, limits, what in ((order.bearing, mount.train, "bearing"), (order.elevation, mount.tilt, "elevation")):
        if value is not None and _outside(value, limits):
            return OrderRejection(SEARCHLIGHT, True, f"searchlight {order.index} {what} {math.degrees(value):.1f} "
                                                     f"deg refused: outside {math.degrees(limits[0]):.0f}.."
                                                     f"{math.degrees(limits[1]):.0f} deg")
    states[order.index] = replace(held, **{k: v for k, v in (("on", order.on), ("bearing", order.bearing),
                                                              ("elevation", order.elevation)) if v is not None})
    return None
