"""The end summary of a command, as people and programs read it."""
from __future__ import annotations

import json

from rich.console import Console


def print_summary(summary: dict, as_json: bool, console: Console) -> int:
    """Print a command's summary: one JSON line (``as_json``), or one line per key. Returns
    the command's exit status, 0."""
    if as_json:
        print(json.dumps(summary))
        return 0
    for key, value in summary.items():
        console.print(f"{key}: {value}")
    return 0
