"""Shared helpers: the configured ships, compiled."""
from functools import lru_cache

from bridge_node.node.config import load_ship
from sim_core.ship.model import ShipModel, compile_ship


@lru_cache(maxsize=None)
def ship(name: str) -> ShipModel:
    return compile_ship(load_ship(name))
