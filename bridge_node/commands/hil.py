"""``icebridge hil run``: hardware-in-the-loop acceptance tests. Starts the node as its own
process (``icebridge run``, render off, on a generated config whose links are loopback and
pty endpoints), plays the scenarios through the software console in this process, prints
pass or fail per expectation with the measured values, writes JUnit XML, and exits 1 on a
failure. ``--attach`` plays them against a node already running instead (real hardware),
through the console ends of a console config."""
from __future__ import annotations

import argparse
from datetime import datetime, timezone
from pathlib import Path

from bridge_node.hil.bench import Bench, parse_kinds
from bridge_node.hil.player import Console, ScenarioResult, play
from bridge_node.hil.report import node_lines, result_lines, write_junit
from bridge_node.hil.scenario import Scenario, load_scenario
from bridge_node.hil.settings import load_console_config
from bridge_node.common.errors import UserError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenarios", nargs="+", metavar="SCENARIO", help="scenario files (TOML), played in order")
    p.add_argument("--node-config", dest="config", default=None,
                   help="the node config the generated one starts from (same as --config; default: built-in)")
    p.add_argument("--links", default="can", metavar="PRIMARY[,BACKUP]",
                   help="link kinds of the console's order ends: can (slcan on a pty), nmea (a pty), modbus "
                        "(TCP on 127.0.0.1); default: can. An NMEA 0183 panel end (alarms) is always added. "
                        "A scenario that names its own kinds runs on a bench of those")
    p.add_argument("--attach", default=None, metavar="CONSOLE_CONFIG",
                   help="play against a node already running, through the ends of this console config")
    p.add_argument("--junit", default=None, metavar="FILE", help="write JUnit XML here")
    p.add_argument("--out", default="out/hil", help="run folders (generated configs, node log) go here")
    p.add_argument("--startup-timeout", type=float, default=180.0, metavar="S",
                   help="wait this long for the node's first outputs (default: 180 s)")


def _scenarios(args: argparse.Namespace, backups: int, own_kinds: bool) -> list[tuple[str, Scenario]]:
    """The scenario files, read; UserError for one that needs a backup end its console lacks
    (``backups``: the console's; ``own_kinds``: a scenario naming its link kinds gets a bench
    of them)."""
    out = [(path, load_scenario(path)) for path in args.scenarios]
    for path, s in out:
        ends = len(s.kinds) - 1 if own_kinds and s.kinds is not None else backups
        if "backup" in s.links and not ends:
            raise UserError(f"{path}: links = {s.links}: the scenario needs a backup end; give --links "
                            "PRIMARY,BACKUP (e.g. --links can,nmea), or kinds in the scenario")
    return out


def _benches(scenarios: list[tuple[str, Scenario]], links: list[str]) -> dict[tuple[str, ...], list]:
    """The scenarios by the link kinds of the bench each needs (its own ``kinds``, else
    ``--links``), in the order they first come."""
    groups: dict[tuple[str, ...], list] = {}
    for path, s in scenarios:
        kinds = tuple(parse_kinds(",".join(s.kinds))) if s.kinds is not None else tuple(links)
        groups.setdefault(kinds, []).append((path, s))
    return groups


def _play_on_benches(args: argparse.Namespace) -> list[ScenarioResult]:
    """Each group of scenarios played on a bench of its link kinds (a node process each)."""
    links = parse_kinds(args.links)
    scenarios = _scenarios(args, len(links) - 1, own_kinds=True)
    results = []
    for n, (kinds, group) in enumerate(_benches(scenarios, links).items()):
        folder = Path(args.out) / (datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ") + f"-{n}")
        print(f"starting the node ({', '.join(kinds)} console; run folder {folder})", flush=True)
        with Bench(folder, list(kinds), args.config, args.startup_timeout) as bench:
            results += [_report(bench.play(s, path)) for path, s in group]
        print("\n".join(node_lines(bench.node_summary)))
    return results


def _report(result: ScenarioResult) -> ScenarioResult:
    print("\n".join(result_lines(result)), flush=True)
    return result


def run(args: argparse.Namespace) -> int:
    if not 1.0 <= args.startup_timeout <= 3600.0:
        raise UserError(f"--startup-timeout {args.startup_timeout} s is outside the allowed range [1, 3600]")
    if args.attach:
        scenarios = _scenarios(args, 1, own_kinds=False)
        with Console(load_console_config(args.attach)) as console:
            console.wait_ready(args.startup_timeout)
            results = [_report(play(console, s, path)) for path, s in scenarios]
        print("\n".join(node_lines(None)))
    else:
        results = _play_on_benches(args)
    if args.junit:
        write_junit(results, Path(args.junit))
    failed = sum(not o.passed for r in results for o in r.outcomes)
    total = sum(len(r.outcomes) for r in results)
    print(f"{total - failed} of {total} expectations met in {len(results)} scenario(s)")
    return 1 if failed else 0
