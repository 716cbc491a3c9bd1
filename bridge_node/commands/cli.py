"""The ``icebridge`` command: argument parsing and user-facing errors.

Each subcommand lives in its own module with ``add_arguments(parser)`` and ``run(args)``.
A user's mistake (bad config, bad argument) prints one clear message and exits with status
2; it never shows a traceback.
"""
from __future__ import annotations

import argparse
import importlib.metadata
import signal
import sys
from types import ModuleType

from bridge_node.commands import (
    console,
    ctl,
    experiment_breaking,
    experiment_transit,
    field,
    hil,
    instructor,
    links_monitor,
    prefracture,
    render_node,
    render_snapshot,
    replay,
    run,
    trial,
)
from bridge_node.common.children import end_with_parent
from bridge_node.common.errors import UserError
from bridge_node.common.paths import writable_dir, writable_file

# name -> (module, help) or (help, {sub-name: (module, help)})
COMMANDS: dict[str, tuple] = {
    "run": (run, "run the node in real time: console links, ship, ice world, instrument outputs"),
    "prefracture": (prefracture, "build the pre-fractured tile templates (paper §2.1)"),
    "replay": (replay, "replay a logged voyage through the ice: track logs driven, session records re-simulated"),
    "trial": (trial, "run a standard manoeuvring trial (turning, zig-zag, crash stop)"),
    "experiment": ("run the paper's ice experiments", {
        "breaking": (experiment_breaking, "channel and conduction-band widths per thickness, colliders, speed"),
        "transit": (experiment_transit, "a straight transit: live and frozen fragments, step time (Fig. 18, 19)"),
    }),
    "field": (field, "lay out the ice regions of a SIGRID-3 chart or a config and report them against it"),
    "render-snapshot": (render_snapshot, "render the projector channels of the exercise to PNGs"),
    "render-node": (render_node, "render projector channels from a running node's state stream"),
    "links": ("commission the console links", {
        "monitor": (links_monitor, "show orders and link health live, publish an open-water ship"),
    }),
    "console": (console, "a software bridge console: play scenario scripts or steer from the keyboard"),
    "instructor": (instructor, "the instructor station: a web page to watch and command a running exercise"),
    "ctl": (ctl, "command a running exercise: freeze, reposition, weather, failures (the instructor's commands)"),
    "hil": ("hardware-in-the-loop tests", {
        "run": (hil, "start the node, play scenarios through the software console, judge the outputs"),
    }),
}


def _add(sub, name: str, module: ModuleType, help_text: str) -> None:
    p = sub.add_parser(name, help=help_text, description=help_text)
    p.add_argument("--config", default=None, help="TOML config file (default: config/default.toml)")
    module.add_arguments(p)
    p.set_defaults(handler=module.run)


INTRODUCTION = """IceBridge: a ship-bridge integration node for full-mission ice-navigation simulators. It
reads the bridge console's helm and engine orders (CAN, NMEA 0183, Modbus), steers a ship
model through sea ice that breaks as in the reference paper, sends the ship's state to the
bridge instruments and renders the projector channels. Start with `icebridge run`; the
documentation is in docs/ (build the site with `mkdocs build`) and README.md."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="icebridge", description=INTRODUCTION,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (first, second) in COMMANDS.items():
        if isinstance(second, dict):
            group = sub.add_parser(name, help=first, description=first)
            inner = group.add_subparsers(dest="action", required=True, metavar="ACTION")
            for action, (module, help_text) in second.items():
                _add(inner, action, module, help_text)
        else:
            _add(sub, name, first, second)
    return parser


def _version() -> str:
    """The installed package's version (the source tree's when it is not installed)."""
    try:
        return importlib.metadata.version("icebridge")
    except importlib.metadata.PackageNotFoundError:
        return "(not installed)"


# options naming where a command writes: checked before any work starts
OUTPUT_DIRS = {"out": "--out", "record": "--record", "cache_dir": "--cache-dir"}
OUTPUT_FILES = {"export": "--export", "video": "--video", "panorama": "--panorama", "summary": "--summary",
                "junit": "--junit", "results": "--results"}


def check_outputs(args: argparse.Namespace) -> None:
    """UserError unless every output folder and file the arguments name can be written."""
    for name, option in OUTPUT_DIRS.items():
        if getattr(args, name, None) is not None:
            writable_dir(getattr(args, name), option)
    for name, option in OUTPUT_FILES.items():
        if getattr(args, name, None) is not None:
            writable_file(getattr(args, name), option)


def _interrupt(*_) -> None:
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    end_with_parent()  # a child of a node (a console, a render process) ends with it
    args = build_parser().parse_args(argv)
    # SIGTERM ends a command as Ctrl-C does: the long-running ones close their links and
    # flush their session record on the way out
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        check_outputs(args)
        return int(args.handler(args) or 0)
    except UserError as exc:
        print(f"icebridge {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"icebridge {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
