"""The traffic picture: every other vessel the node knows of at one moment, one per MMSI.

The hub gathers it each tick from what its links hear (DIS), the vessels the instructor
steers in the world (``world``, set by ``bridge_node.exercise.listeners.WorldTraffic``), the
exercise's other own ships (``fleet``, set by ``bridge_node.exercise.fleet.FleetTraffic``) and
the picture's own sources (replayed AIS logs, scripted vessels); the NMEA links send it as ``!AIVDM`` and the
state stream carries it as ``TRAFFIC_DTYPE`` rows (``table``) for the render processes.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from bridge_node.links.messages import Vessel
from sim_core.frames.geodesy import geodetic_to_local

# The other vessels (AIS, DIS, scripted), one row each: MMSI; x east and y north in world m
# (the frame of ``ship.east``/``ship.north``); true heading in rad, clockwise from north (as
# ``ship.heading``); speed over ground m/s; length and beam m (0: unknown).
TRAFFIC_DTYPE = np.dtype([("id", np.int64), ("x", np.float64), ("y", np.float64), ("heading", np.float64),
                          ("speed", np.float64), ("length", np.float64), ("beam", np.float64)])


class VesselSource(Protocol):
    """Something that knows of other vessels (a DIS link, an AIS log, the script)."""

    def vessels(self, now: float) -> list[Vessel]:
        """The vessels as of ``now`` (monotonic s)."""


class TrafficPicture:
    """The other vessels from the links, the own fleet, the world and ``sources``; where two
    give the same MMSI, the links' (live simulators) win, then the fleet's, the world's, and
    the sources in their order."""

    def __init__(self, sources: Sequence[VesselSource] = ()) -> None:
        self.sources = list(sources)
        self.world: list[Vessel] = []  # the instructor's vessels as the last step left them
        self.fleet: list[Vessel] = []  # the exercise's other own ships as the last step left them
        self.current: list[Vessel] = []  # as last gathered

    def gather(self, heard: list[Vessel], now: float) -> list[Vessel]:
        """The picture at ``now`` (monotonic s): ``heard`` (the links' vessels), the fleet's,
        the world's and the sources' vessels, one per MMSI."""
        seen, self.current = set(), []
        for v in [*heard, *self.fleet, *self.world, *(v for source in self.sources for v in source.vessels(now))]:
            if v.mmsi not in seen:
                seen.add(v.mmsi)
                self.current.append(v)
        return self.current

    def table(self, origin: tuple[float, float]) -> np.ndarray:
        """The last gathered vessels as ``TRAFFIC_DTYPE`` rows, placed in the world frame of
        the field whose corner is at ``origin`` (latitude, longitude rad)."""
        rows = []
        for v in self.current:
            north, east = geodetic_to_local(v.latitude, v.longitude, *origin)
            rows.append((v.mmsi, east, north, v.heading, v.speed_over_ground, v.length, v.beam))
        return np.array(rows, dtype=TRAFFIC_DTYPE).reshape(-1)
