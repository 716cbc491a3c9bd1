"""The generated reference pages of the documentation site, by their path in it."""
from __future__ import annotations

from collections.abc import Callable

from bridge_node.commands.cli import build_parser
from bridge_node.node.config import NodeConfig
from bridge_node.reference.cli_reference import cli_reference
from bridge_node.reference.config_reference import config_reference
from bridge_node.reference.interfaces import interfaces_reference
from bridge_node.reference.stream_format import stream_reference

REFERENCE_PAGES: dict[str, Callable[[], str]] = {
    "reference/config.md": lambda: config_reference(NodeConfig, "Config reference"),
    "reference/cli.md": lambda: cli_reference(build_parser()),
    "reference/interfaces.md": interfaces_reference,
    "reference/stream.md": stream_reference,
}
