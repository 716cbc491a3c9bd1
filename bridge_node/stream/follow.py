"""The state stream seen from another own ship's bridge (issue 31: each ship its own render
groups and eyes). The node publishes the world from its first ship: ``WorldEvents.ship``
is that ship, ``others`` the other own ships, and the traffic picture holds every other
vessel, the other own ships among them. A render process of the k-th ship's bridge swaps
the first ship and the k-th ship in both the model (``followed_model``: its hull, eyes and
lights are the k-th ship's) and every message (``FollowedShip``): the k-th ship becomes the
one the eyes ride on, and the first ship a vessel in the traffic picture, drawn as the
others are.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from bridge_node.links.traffic_picture import TRAFFIC_DTYPE
from sim_core.fleet import ShipReport
from sim_core.world import WorldEvents, WorldModel


def followed_model(model: WorldModel, k: int) -> WorldModel:
    """``model`` with its first ship and its k-th (0: the first; 1 is the first of
    ``[[ships]]``) swapped; ValueError for a ship the world lacks."""
    if not 0 <= k < len(model.ships):
        raise ValueError(f"the world has {len(model.ships)} ships (0 to {len(model.ships) - 1}); ship {k} is none")
    order = list(range(len(model.ships)))
    order[0], order[k] = k, 0
    return dataclasses.replace(model, ships=tuple(model.ships[i] for i in order),
                               contours=tuple(model.contours[i] for i in order))


@dataclasses.dataclass(frozen=True)
class FollowedShip:
    """Turns the node's messages into the k-th ship's (k >= 1): ``mmsi`` is the k-th ship's
    (its row leaves the traffic), ``first`` the first ship's MMSI, length and beam (m), for
    the row it becomes."""

    k: int
    mmsi: int
    first: tuple[int, float, float]

    def __call__(self, events: WorldEvents, traffic: np.ndarray) -> tuple[WorldEvents, np.ndarray]:
        """The message as the k-th ship's bridge sees it; ValueError where the message has
        fewer ships (a node run with another config)."""
        if len(events.others) < self.k:
            raise ValueError(f"the stream carries {len(events.others) + 1} ships; ship {self.k} is none")
        me = events.others[self.k - 1]
        others = list(events.others)
        others[self.k - 1] = ShipReport(events.ship, events.ice_load, events.rejected)
        seen = dataclasses.replace(events, ship=me.outputs, ice_load=me.ice_load, rejected=me.rejected,
                                   others=tuple(others))
        s = events.ship
        mmsi, length, beam = self.first
        row = np.array([(mmsi, s.east, s.north, s.heading, s.speed_over_ground, length, beam)], dtype=TRAFFIC_DTYPE)
        kept = traffic[(traffic["id"] != self.mmsi) & (traffic["id"] != mmsi)]
        return seen, np.concatenate([kept, row])
