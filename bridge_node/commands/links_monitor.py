"""``icebridge links monitor``: commission a console without the ice scene.

Opens the configured links, shows each decoded order and each link's health live, runs the
ship model in open water on the orders it receives, and publishes that ship's state on the
configured outputs. ``--json`` ends with one JSON object: orders per source (last value,
count), errors by kind, alarms raised, outputs sent.
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

from bridge_node.links.hub import LinkHub
from bridge_node.node.config import load_config, load_ship, new_session_dir
from bridge_node.node.errors import UserError
from bridge_node.node.order_refusals import OrderRefusals
from sim_core.frames.units import KNOT
from sim_core.ship.model import ShipData, ShipModel, compile_ship, new_ship_data, step
from sim_core.ship.orders import OrderKind
from sim_core.ship.outputs import ship_outputs
from sim_core.world import apply_controls

TICK_S = 0.05  # 20 Hz


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--json", action="store_true", help="end with one JSON summary instead of the live view")
    p.add_argument("--record", default=None, help="session record folder (default: paths.session_dir/<time>)")
    p.add_argument("--no-record", action="store_true", help="do not record the session")


def _value(order) -> str:
    if order.kind == "rudder":
        return f"{math.degrees(order.value):+.1f} deg"
    if order.kind == OrderKind.SEARCHLIGHT:
        v = order.value
        aim = [f"{what} {math.degrees(a):+.1f} deg" for what, a in (("bearing", v.bearing), ("elevation", v.elevation))
               if a is not None]
        return ", ".join([f"light {v.index}", *([] if v.on is None else ["on" if v.on else "off"]), *aim])
    return f"{order.value:+.0f} %" if order.kind == "lever" else str(order.value)


def _view(hub: LinkHub, ship, now: float) -> Table:
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


def _monitor(hub: LinkHub, ship: ShipModel, data: ShipData, origin: tuple[float, float], duration: float | None,
             live: Live | None, refusals: OrderRefusals) -> None:
    """Tick at 20 Hz until the duration: poll and decide, obey, step the ship, publish."""
    start = next_tick = time.monotonic()
    sim_time = 0.0
    while duration is None or time.monotonic() - start < duration:
        now = time.monotonic()
        decision = hub.poll(now)
        for alarm in refusals.note(tuple(apply_controls(ship, data, decision.controls)), now):
            hub.raise_alarm(alarm, now)
        step(ship, data, TICK_S)
        sim_time += TICK_S
        hub.publish(ship_outputs(data, sim_time, *origin, time.time()), now)
        if live is not None:
            live.update(_view(hub, data, now))
        next_tick += TICK_S
        time.sleep(max(0.0, next_tick - time.monotonic()))


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    if args.duration is not None and not 0.0 < args.duration <= 86400.0:
        raise UserError(f"--duration {args.duration} s is outside the allowed range (0, 86400]")
    if not cfg.links:
        raise UserError(f"{args.config or 'default config'}: no [[links]] configured; nothing to monitor")
    ship = compile_ship(load_ship(cfg.ship.name, args.config), cfg.ice_material)
    data = new_ship_data(ship, 0.0, rps=0.0)
    origin = math.radians(cfg.exercise.origin_latitude_deg), math.radians(cfg.exercise.origin_longitude_deg)
    record = None
    if not args.no_record:
        record = Path(args.record) if args.record else new_session_dir(cfg, args.config)
    console = Console(stderr=True)
    start = time.monotonic()
    refusals = OrderRefusals()
    with LinkHub(cfg.links, cfg.arbitration, record) as hub:
        try:
            with Live(console=console, refresh_per_second=4, transient=True) as live:
                _monitor(hub, ship, data, origin, args.duration, None if args.json else live, refusals)
        except KeyboardInterrupt:
            pass
        summary = _summary(hub, data, start, refusals, record)
    if args.json:
        print(json.dumps(summary))
    else:
        console.print(_view(hub, data, time.monotonic()))
        console.print(f"session record: {record}" if record else "not recorded")
    return 0


def _summary(hub: LinkHub, data: ShipData, start: float, refusals: OrderRefusals, record: Path | None) -> dict:
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
        "ship": {"rudder_deg": round(math.degrees(data.rudder), 2), "shaft_rpm": round(data.rps * 60, 1),
                 "speed_kn": round(data.nu[0] / KNOT, 2)},
        "orders_rejected": dict(refusals.counts),
        "record": str(record) if record else None,
    }
