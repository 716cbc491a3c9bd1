"""``icebridge console``: a software bridge console. It speaks to the node as the reference
console does, over the ends of a console config (CAN frames of the DBC or PGN 127245, NMEA
0183 ROR/ETL/PRC, Modbus registers), and reads back the instrument outputs. With
``--script`` it plays scenario files and judges their expectations (exit 1 on a failure);
without, it is steered from the keyboard, faults included, with the echoed rudder angle, RPM,
heading, rate of turn and alarms shown live."""
from __future__ import annotations

import argparse
import json
import math
import random
import time
from pathlib import Path

from rich.console import Console as Terminal
from rich.live import Live

from bridge_node.hil.console_links import AlarmReading, ConsoleLink, Order, Reading
from bridge_node.hil.player import TICK_S, Console, ScenarioResult, play
from bridge_node.hil.report import result_lines, write_junit
from bridge_node.hil.scenario import Fault, load_scenario
from bridge_node.hil.settings import load_console_config
from bridge_node.node.config import DEFAULT_CONFIG
from bridge_node.common.errors import UserError
from bridge_node.common.output_files import write_output
from bridge_node.replay.console import KeyReader
from sim_core.ship.orders import OrderKind
from sim_core.ship.particulars import TELEGRAPH_POSITIONS

DEFAULT_CONSOLE = DEFAULT_CONFIG.parent / "console.toml"
HELM_STEP_DEG, HELM_LIMIT_DEG = 5.0, 35.0
KEYS_HELP = ("keys: a/d helm 5 deg port/starboard | 0 midships | w/s telegraph up/down | faults: u unplug/replug, "
             "x corrupt orders on/off, g garbage burst | q quit")
FAULT_KEYS = {"u": ("disconnect", "UNPLUGGED"), "x": ("corrupt", "CORRUPTING"), "g": ("garbage", "")}
GARBAGE_COUNT = 50  # frames or bytes of one burst
UNITS = {"rudder_angle": ("rudder", "deg", math.degrees(1.0)), "shaft_speed": ("shaft", "rpm", 60.0),
         "heading": ("heading", "deg", math.degrees(1.0)), "rate_of_turn": ("ROT", "deg/min", math.degrees(60.0))}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--script", action="append", default=[], metavar="SCENARIO",
                   help="play this scenario file (repeatable); without: steer from the keyboard")
    p.add_argument("--junit", default=None, metavar="FILE", help="with --script: write JUnit XML here")
    p.add_argument("--wait", type=float, default=30.0, metavar="S",
                   help="wait this long for the node's outputs on every end (default: 30 s)")
    p.add_argument("--hold", action="store_true",
                   help="with --script: after the scripts, keep sending the last orders until Ctrl-C or SIGTERM")
    p.add_argument("--results", default=None, metavar="FILE",
                   help="with --script: write the expectations met per scenario here (JSON) when the scripts end")


class _FaultKeys:
    """Faults toggled from the keyboard on one console end (seeded: a session is repeatable)."""

    def __init__(self, end: ConsoleLink) -> None:
        self.end = end
        self.rng = random.Random(0)
        self.active: dict[str, Fault] = {}
        self.note = ""  # why the last key did nothing

    def press(self, key: str) -> None:
        kind, _ = FAULT_KEYS[key]
        if key in self.active:
            self.end.clear(self.active.pop(key))
            return
        fault = Fault(at_s=0.0, link=self.end.role, kind=kind, duration_s=600.0, count=GARBAGE_COUNT)
        self.note = self.end.unsupported(fault) or ""
        if self.note:
            return
        self.end.inject(fault, self.rng)
        if kind == "garbage":  # a burst, not a state
            self.end.clear(fault)
        else:
            self.active[key] = fault

    def status(self) -> str:
        return "".join(f" | {FAULT_KEYS[k][1]}" for k in self.active) + (f" | {self.note}" if self.note else "")


def _steer(console: Console, terminal: Terminal) -> None:
    """Keyboard steering and faults on the first order end until q (or Ctrl-C), with a live line."""
    end = console.ends.get("primary") or next(iter(console.ends.values()))
    faults = _FaultKeys(end)
    keys = KeyReader()
    if not keys.interactive:
        raise UserError("standard input is not a terminal: give --script SCENARIO to play a scenario instead")
    helm, telegraph = 0.0, TELEGRAPH_POSITIONS.index("stop")
    shown: dict[str, str] = {}
    alarms: dict[int, str] = {}
    terminal.print(KEYS_HELP)
    with keys, Live(console=terminal, refresh_per_second=8, transient=True) as live:
        end.order(Order(OrderKind.RUDDER, 0.0), time.monotonic())
        end.order(Order(OrderKind.TELEGRAPH, TELEGRAPH_POSITIONS[telegraph]), time.monotonic())
        while True:
            for key in keys.keys():  # noqa: SIM118 (KeyReader.keys: the keys pressed)
                if key == "q":
                    return
                if key in "ad0":
                    helm = 0.0 if key == "0" else max(-HELM_LIMIT_DEG, min(HELM_LIMIT_DEG, helm + (
                        HELM_STEP_DEG if key == "d" else -HELM_STEP_DEG)))
                    end.order(Order(OrderKind.RUDDER, math.radians(helm)), time.monotonic())
                elif key in "ws":
                    telegraph = max(0, min(len(TELEGRAPH_POSITIONS) - 1, telegraph + (1 if key == "w" else -1)))
                    end.order(Order(OrderKind.TELEGRAPH, TELEGRAPH_POSITIONS[telegraph]), time.monotonic())
                elif key in FAULT_KEYS:
                    faults.press(key)
            for r in console.tick(time.monotonic()):
                if isinstance(r, Reading):
                    label, unit, factor = UNITS[r.quantity]
                    shown[r.quantity] = f"{label} {r.value * factor:+.1f} {unit}"
                elif isinstance(r, AlarmReading):
                    alarms.pop(r.number, None) if not r.active else alarms.__setitem__(r.number, r.text)
            live.update(f"helm {helm:+.0f} deg | {TELEGRAPH_POSITIONS[telegraph]} | " + " | ".join(
                shown[q] for q in UNITS if q in shown) + "".join(f" | ALARM {n:03d} {t}" for n, t in alarms.items())
                + faults.status())
            time.sleep(0.02)


def run(args: argparse.Namespace) -> int:
    if not 0.0 < args.wait <= 3600.0:
        raise UserError(f"--wait {args.wait} s is outside the allowed range (0, 3600]")
    if (args.hold or args.results) and not args.script:
        raise UserError("--hold and --results go with --script")
    config = load_console_config(args.config or DEFAULT_CONSOLE)
    scripts = [(path, load_scenario(path)) for path in args.script]
    terminal = Terminal(highlight=False)
    with Console(config) as console:
        console.wait_ready(args.wait)
        if not scripts:
            _steer(console, terminal)
            return 0
        results = []
        for path, scenario in scripts:
            results.append(play(console, scenario, path))
            print("\n".join(result_lines(results[-1])), flush=True)
        if args.junit:
            write_junit(results, Path(args.junit))
        if args.results:
            _write_results(results, Path(args.results))
        if args.hold:
            _hold(console)
    return 1 if any(not r.passed for r in results) else 0


def _write_results(results: list[ScenarioResult], path: Path) -> None:
    """Expectations met per scenario, as JSON (written whole, then renamed into place; only
    over a regular file)."""
    rows = [{"name": r.name, "path": r.path, "passed": r.passed, "met": sum(o.passed for o in r.outcomes),
             "total": len(r.outcomes), "duration_s": r.duration_s} for r in results]
    write_output(path, json.dumps(rows), "--results")


def _hold(console: Console) -> None:
    """Keep every end ticking (its last orders repeated, outputs read) until Ctrl-C or SIGTERM."""
    print("scripts played; holding the last orders", flush=True)
    try:
        while True:
            console.tick(time.monotonic())
            time.sleep(TICK_S)
    except KeyboardInterrupt:
        pass
