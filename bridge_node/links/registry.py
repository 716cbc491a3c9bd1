"""The link kinds the node knows: importing each kind's module registers it (``links.kind``).
A new link kind is added here, by one import, and in its own folder."""
from __future__ import annotations

from typing import Annotated

from bridge_node.links.base import Link
from bridge_node.links.can import kind as _can  # noqa: F401  (the kinds register themselves)
from bridge_node.links.dis import kind as _dis  # noqa: F401
from bridge_node.links.kind import OneOfTheKinds, link_kind
from bridge_node.links.modbus import kind as _modbus  # noqa: F401
from bridge_node.links.nmea0183 import kind as _nmea0183  # noqa: F401
from bridge_node.links.settings import LinkSettingsBase

LinkSettings = Annotated[LinkSettingsBase, OneOfTheKinds()]  # one ``[[links]]`` table, by its ``type``


def make_link(settings: LinkSettingsBase) -> Link:
    """The link for one ``[[links]]`` table, not yet opened."""
    return link_kind(settings.type).link(settings)


def open_link(settings: LinkSettingsBase) -> Link:
    """The link for one ``[[links]]`` table, opened (close it, or use it in a ``with``)."""
    link = make_link(settings)
    link.open()
    return link
