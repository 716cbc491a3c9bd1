"""Link types by the settings' ``type``: each link module registers its class with
``@register_link``; importing them here fills ``LINK_TYPES``."""
from __future__ import annotations

from bridge_node.links import can_link, dis_link, modbus_link, nmea_link  # noqa: F401  (they register themselves)
from bridge_node.links.base import LINK_TYPES, Link
from bridge_node.links.settings import LinkSettings


def make_link(settings: LinkSettings) -> Link:
    """The link for one ``[[links]]`` table, not yet opened."""
    try:
        cls = LINK_TYPES[settings.type]
    except KeyError:
        raise ValueError(f"no link type {settings.type!r}; known: {', '.join(sorted(LINK_TYPES))}") from None
    return cls(settings)


def open_link(settings: LinkSettings) -> Link:
    """The link for one ``[[links]]`` table, opened (close it, or use it in a ``with``)."""
    link = make_link(settings)
    link.open()
    return link
