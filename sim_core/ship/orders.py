"""The kinds of order the console gives the ship. A ``StrEnum``, so that a kind prints, logs
and serialises (JSON, TOML, the summaries) as its plain name."""
from __future__ import annotations

from enum import StrEnum


class OrderKind(StrEnum):
    """One kind of console order; each has one value type (``bridge_node.links.base.ORDER_VALUES``)."""

    RUDDER = "rudder"  # rudder angle, rad (+ to starboard)
    TELEGRAPH = "telegraph"  # a telegraph position name (``TELEGRAPH_POSITIONS``)
    LEVER = "lever"  # engine lever, percent of full ahead (-100..100)
    SEARCHLIGHT = "searchlight"  # a ``SearchlightOrder``
