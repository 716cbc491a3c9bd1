"""The ``icebridge`` command: argument parsing and user-facing errors.

Each subcommand lives in its own module with ``add_arguments(parser)`` and ``run(args)``.
A user's mistake (bad config, bad argument) prints one clear message and exits with status
2; it never shows a traceback.
"""
from __future__ import annotations

import argparse
import signal
import sys

from bridge_node import (experiment_command, links_command, prefracture_command, render_snapshot_command, run_command,
                         trial_command)
from bridge_node.errors import UserError

COMMANDS = {
    "run": (run_command, "run the node in real time: console links, ship, ice world, instrument outputs"),
    "prefracture": (prefracture_command, "build the pre-fractured tile templates (paper §2.1)"),
    "trial": (trial_command, "run a standard manoeuvring trial (turning, zig-zag, crash stop)"),
    "experiment": (experiment_command, "run the paper's ice experiments (breaking, transit)"),
    "render-snapshot": (render_snapshot_command, "render the projector channels of the exercise to PNGs"),
    "links": (links_command, "commission the console links: show orders and health, publish a ship"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="icebridge", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (module, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.add_argument("--config", default=None, help="TOML config file (default: config/default.toml)")
        module.add_arguments(p)
        p.set_defaults(handler=module.run)
    return parser


def _interrupt(*_) -> None:
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    # SIGTERM ends a command as Ctrl-C does: the long-running ones close their links and
    # flush their session record on the way out
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        return int(args.handler(args) or 0)
    except UserError as exc:
        print(f"icebridge {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"icebridge {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
