"""``icebridge links monitor``: commission a console without the ice scene.

Opens the configured links, shows each decoded order and each link's health live, runs the
exercise's one tick (``bridge_node.exercise.tick``) at 20 Hz with the ship in open water
(the configured exercise without its ice field) on the orders it receives, searchlights
included, and publishes that ship's state on the configured outputs. The session record
holds a tick log, as a run's does, so a commissioning session can be re-simulated.
``--json`` ends with one JSON object: orders per source (last value, count), errors by kind,
alarms raised, outputs sent.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from pathlib import Path

from rich.console import Console
from rich.live import Live
from rich.table import Table

from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import load_config, new_session_dir
from bridge_node.common.errors import UserError
from bridge_node.exercise.order_refusals import OrderRefusals
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import open_water_world
from sim_core.frames.units import KNOT
from sim_core.ship.model import ShipData
from sim_core.ship.orders import OrderKind
from sim_core.world import WorldEvents

RATE_HZ = 20.0  # the monitor's ticks per second


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--json", action="store_true", help="end with one JSON summary instead of the live view")
    p.add_argument("--record", default=None, help="session record folder (default: paths.session_dir/<time>)")
    p.add_argument("--no-record", action="store_true", help="do not record the session")


def _value(order) -> str:
    if order.kind == OrderKind.RUDDER:
        return f"{math.degrees(order.value):+.1f} deg"
    if order.kind == OrderKind.SEARCHLIGHT:
        v = order.value
        aim = [f"{what} {math.degrees(a):+.1f} deg" for what, a in (("bearing", v.bearing), ("elevation", v.elevation))
               if a is not None]
        return ", ".join([f"light {v.index}", *([] if v.on is None else ["on" if v.on else "off"]), *aim])
    return f"{order.value:+.0f} %" if order.kind == OrderKind.LEVER else str(order.value)


def _view(hub: LinkHub, ship: ShipData, now: float) -> Table:
    table = Table(title=f"icebridge links monitor: rudder {math.degrees(ship.rudder):+.1f} deg, "
                        f"shaft {ship.rps * 60:+.0f} rpm, speed {ship.nu[0] / KNOT:.1f} kn")
    for col in ("source/order/engine", "value", "age, s"):
        table.add_column(col)
    for key, order in sorted(hub.last_orders.items()):
        table.add_row(key, _value(order), f"{now - order.time:.1f}")
    for link in hub.links:
        h = link.health()
        errs = ", ".join(f"{k} {v}" for k, v in h.errors.items()) or "none"
        table.add_row(f"[b]{link.name}[/b]", "up" if h.connected else "[red]down[/red]",
                      f"in {h.inputs} out {h.outputs} errors: {errs}")
    for alarm in hub.active_alarms.values():
        table.add_row(f"[red]ALARM {alarm.number:03d}[/red]", alarm.text, "")
    return table


class _LiveView(StepListener):
    """The live table, four times a second; keeps the last events for the summary."""

    def __init__(self, hub: LinkHub, ship: ShipData, live: Live | None) -> None:
        self.hub, self.ship, self.live, self.last, self._shown = hub, ship, live, None, 0.0

    def on_step(self, outcome: TickOutcome) -> None:
        self.last = outcome.events
        if self.live is not None and outcome.now - self._shown >= 0.25:
            self._shown = outcome.now
            self.live.update(_view(self.hub, self.ship, outcome.now))


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    if args.duration is not None and not 0.0 < args.duration <= 86400.0:
        raise UserError(f"--duration {args.duration} s is outside the allowed range (0, 86400]")
    if not cfg.links:
        raise UserError(f"{args.config or 'default config'}: no [[links]] configured; nothing to monitor")
    console = Console(stderr=True)
    with console.status("loading the ship"):
        model, data = open_water_world(cfg, args.config)
    record = None
    if not args.no_record:
        record = Path(args.record) if args.record else new_session_dir(cfg, args.config)
    start = time.monotonic()
    with LinkHub(cfg.links, cfg.arbitration, record) as hub, \
            Live(console=console, refresh_per_second=4, transient=True) as live:
        view = _LiveView(hub, data.ship, None if args.json else live)
        stats = run_realtime(model, data, hub, RATE_HZ, args.duration, [view])
        summary = _summary(hub, data.ship, view.last, start, stats.refusals, record)
    if args.json:
        print(json.dumps(summary))
    else:
        console.print(_view(hub, data.ship, time.monotonic()))
        console.print(f"session record: {record}" if record else "not recorded")
    return 0


def _summary(hub: LinkHub, ship: ShipData, last: WorldEvents | None, start: float, refusals: OrderRefusals,
             record: Path | None) -> dict:
    lights = last.ship.searchlights if last is not None else ()
    return {
        "duration_s": round(time.monotonic() - start, 2),
        "orders": {key: {"last": dataclasses.asdict(o.value) if o.kind == OrderKind.SEARCHLIGHT else o.value,
                         "count": hub.order_counts[key]}
                   for key, o in sorted(hub.last_orders.items())},
        "orders_per_source": dict(hub.arbiter.counts),
        "errors": dict(hub.errors()),
        "alarms": [{"time_s": round(t - start, 2), "number": a.number, "text": a.text, "active": a.active}
                   for t, a in hub.alarm_log],
        "outputs": {link.name: link.health().outputs for link in hub.links},
        "links": [link.health().as_dict() for link in hub.links],
        "ship": {"rudder_deg": round(math.degrees(ship.rudder), 2), "shaft_rpm": round(ship.rps * 60, 1),
                 "speed_kn": round(ship.nu[0] / KNOT, 2)},
        "searchlights": [{"on": s.on, "bearing_deg": round(math.degrees(s.bearing), 2),
                          "elevation_deg": round(math.degrees(s.elevation), 2)} for s in lights],
        "orders_rejected": dict(refusals.counts),
        "record": str(record) if record else None,
    }
