"""The command-line reference, from the argparse parsers themselves: each command's help as
``icebridge COMMAND --help`` prints it."""
from __future__ import annotations

import argparse
import os
from collections.abc import Iterator


def _commands(parser: argparse.ArgumentParser, prefix: str) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    """(name, parser) of ``parser`` and every sub-command under it, depth first."""
    yield prefix, parser
    for action in parser._actions:  # argparse keeps its sub-parsers only here
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _commands(sub, f"{prefix} {name}")


def cli_reference(parser: argparse.ArgumentParser) -> str:
    """The Markdown reference of a command line: one section per command with its help."""
    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps at the terminal's width: the same page everywhere
    try:
        sections = [f"## `{name}`\n\n```text\n{sub.format_help().rstrip()}\n```\n" for name, sub in
                    _commands(parser, parser.prog)]
    finally:
        if previous is None:
            os.environ.pop("COLUMNS")
        else:
            os.environ["COLUMNS"] = previous
    return "# Command-line reference\n\nMade from the command line's own parsers when the site is built.\n\n" + \
        "\n".join(sections)
