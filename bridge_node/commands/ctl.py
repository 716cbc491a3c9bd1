"""``icebridge ctl``: command a running exercise from the command line (the instructor
station's commands, scriptable): exit 0 with the node's reply, or 2 with the error it gave.

    icebridge ctl freeze
    icebridge ctl reposition --lat 74.01 --lon 20.05 --heading 10 --speed 6
    icebridge ctl visibility 500
    icebridge ctl steering-failure 2
    icebridge ctl sensor-failure gnss lost
    icebridge ctl link-fault console drop --probability 0.5
    icebridge ctl save before-the-ridge
    icebridge ctl add-vessel 230000001 --name ODEN --length 108 --beam 31 --north 800 --east 400 --course 180 --speed 8
    icebridge ctl status --json
"""
from __future__ import annotations

import argparse
import json
import math

from bridge_node.control.client import request
from bridge_node.node.config import load_config
from bridge_node.common.errors import UserError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--connect", default=None, metavar="ENDPOINT",
                   help="the node's control endpoint (default: the config's control.endpoint)")
    p.add_argument("--token", default=None, help="access token (default: the config's, or ICEBRIDGE_TOKEN)")
    p.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for the node's reply (default 5)")
    p.add_argument("--json", action="store_true", help="print the node's reply as JSON")
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    actions.add_parser("freeze", help="hold the physics; the clock stops, the outputs go on")
    actions.add_parser("resume", help="run the physics again")
    actions.add_parser("status", help="the exercise's time, ship and environment")
    move = _placed(actions.add_parser("reposition", help="move an own ship"))
    move.add_argument("--heading", type=float, required=True, help="true heading, deg")
    move.add_argument("--speed", type=float, default=0.0, help="speed through the water, kn (default 0)")
    _ship_option(move)
    _vessel_actions(actions)
    actions.add_parser("visibility", help="meteorological visibility").add_argument("metres", type=float)
    actions.add_parser("clock", help="the exercise's time: HH:MM[:SS] (UTC, today) or an ISO 8601 date and "
                                     "time").add_argument("time")
    for name, (help_text, direction) in {"wind": ("true wind", "from_deg"),
                                         "current": ("surface current", "to_deg")}.items():
        one = actions.add_parser(name, help=help_text)
        one.add_argument("speed_kn", type=float)
        one.add_argument(direction, type=float, help="deg true (the wind: where from; the current: where to)")
    for name, (help_text, value, kind) in {
            "steering-failure": ("steering gear pumps failed: 0 (repaired), 1 (half rate), 2 (rudder stuck)",
                                 "pumps_failed", int),
            "engine-failure": ("engine power left, percent: 100 (repaired) .. 0 (blackout)", "power_percent",
                               float)}.items():
        failure = actions.add_parser(name, help=help_text)
        failure.add_argument(value, type=kind)
        _ship_option(failure)
    _failure_actions(actions)
    actions.add_parser("save", help="a save point of the exercise now, in its session record (icebridge run "
                                    "--fork it)").add_argument("name", help="letters, digits, - and _ (1-40)")
    actions.add_parser("send", help="send one command given as a JSON object").add_argument("command_json")


def _failure_actions(actions) -> None:
    """Sensor failures and link faults."""
    sensor = actions.add_parser("sensor-failure", help="gyro ok|frozen|offset, gnss ok|lost|jumping, log ok|frozen")
    sensor.add_argument("sensor", choices=("gyro", "gnss", "log"))
    sensor.add_argument("mode", choices=("ok", "frozen", "offset", "lost", "jumping"))
    sensor.add_argument("--offset", type=float, help="the gyro's offset, deg (mode offset)")
    sensor.add_argument("--jump", type=float, help="the GNSS position's jumps, m (mode jumping; default 200)")
    _ship_option(sensor)
    fault = actions.add_parser("link-fault", help="a fault on one of the node's links (none: cleared)")
    fault.add_argument("link", help="the link's name (icebridge ctl status lists them)")
    fault.add_argument("fault", choices=("none", "disconnect", "drop", "corrupt", "duplicate", "delay"))
    fault.add_argument("--probability", type=float, default=1.0, help="of each order (default 1)")
    fault.add_argument("--delay", type=float, help="s (fault delay)")


def _failure_command(args: argparse.Namespace) -> dict:
    if args.action == "sensor-failure":
        extra = {"offset_deg": args.offset, "jump_m": args.jump}
        return {"command": "sensor_failure", "sensor": args.sensor, "mode": args.mode, "ship": args.ship,
                **{k: v for k, v in extra.items() if v is not None}}
    fault = {"command": "link_fault", "link": args.link, "fault": args.fault, "probability": args.probability}
    return fault | ({"delay_s": args.delay} if args.delay is not None else {})


def _ship_option(p: argparse.ArgumentParser) -> None:
    """The own ship a command is for: --ship K."""
    p.add_argument("--ship", type=int, default=0, metavar="K",
                   help="the K-th ship of [[ships]] (default 0: the first ship, [ship])")


def _placed(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """A position's options: --lat and --lon, or --north and --east."""
    p.add_argument("--lat", type=float, help="latitude, deg")
    p.add_argument("--lon", type=float, help="longitude, deg")
    p.add_argument("--north", type=float, help="m from the exercise origin (the field's south-west corner as laid)")
    p.add_argument("--east", type=float, help="m from the exercise origin (the field's south-west corner as laid)")
    return p


def _vessel_actions(actions) -> None:
    """The commands to other vessels: add, move, steer, remove (by MMSI)."""
    add = _placed(actions.add_parser("add-vessel", help="add another vessel (AIS, DIS, the channels show it)"))
    add.add_argument("mmsi", type=int)
    add.add_argument("--name", default="", help="AIS name (upper case, at most 20 characters)")
    add.add_argument("--length", type=float, required=True, help="m")
    add.add_argument("--beam", type=float, required=True, help="m")
    add.add_argument("--course", type=float, required=True, help="true course, deg")
    add.add_argument("--speed", type=float, default=0.0, help="kn over ground (default 0)")
    _placed(actions.add_parser("move-vessel", help="move another vessel")).add_argument("mmsi", type=int)
    steer = actions.add_parser("steer-vessel", help="another vessel's new course and speed")
    for name, kind in (("mmsi", int), ("course", float), ("speed", float)):
        steer.add_argument(name, type=kind)
    actions.add_parser("remove-vessel", help="another vessel leaves the exercise").add_argument("mmsi", type=int)


def _position(args: argparse.Namespace) -> dict:
    place = {"latitude_deg": args.lat, "longitude_deg": args.lon, "north_m": args.north, "east_m": args.east}
    return {k: v for k, v in place.items() if v is not None}


def _vessel_command(args: argparse.Namespace) -> dict:
    a = args.action
    if a == "add-vessel":
        return {"command": "add_vessel", "mmsi": args.mmsi, "name": args.name, "length_m": args.length,
                "beam_m": args.beam, **_position(args), "course_deg": args.course, "speed_kn": args.speed}
    if a == "move-vessel":
        return {"command": "move_vessel", "mmsi": args.mmsi, **_position(args)}
    if a == "steer-vessel":
        return {"command": "steer_vessel", "mmsi": args.mmsi, "course_deg": args.course, "speed_kn": args.speed}
    return {"command": "remove_vessel", "mmsi": args.mmsi}


def command_of(args: argparse.Namespace) -> dict:
    """The command object the arguments give (checked again, whole, by the node)."""
    a = args.action
    if a in ("freeze", "resume"):
        return {"command": a}
    if a == "reposition":
        return {"command": "reposition", **_position(args), "heading_deg": args.heading, "speed_kn": args.speed,
                "ship": args.ship}
    if a.endswith("-vessel"):
        return _vessel_command(args)
    if a == "visibility":
        return {"command": "visibility", "visibility_m": args.metres}
    if a == "clock":
        return {"command": "clock", ("time_of_day" if len(args.time) <= 8 else "utc"): args.time}
    if a == "wind":
        return {"command": "wind", "speed_kn": args.speed_kn, "from_deg": args.from_deg}
    if a == "current":
        return {"command": "current", "speed_kn": args.speed_kn, "to_deg": args.to_deg}
    if a == "steering-failure":
        return {"command": "steering_failure", "pumps_failed": args.pumps_failed, "ship": args.ship}
    if a == "engine-failure":
        return {"command": "engine_failure", "power_percent": args.power_percent, "ship": args.ship}
    if a in ("sensor-failure", "link-fault"):
        return _failure_command(args)
    if a == "save":
        return {"command": "save", "name": args.name}
    try:
        return json.loads(args.command_json)
    except ValueError:
        raise UserError(f"send {args.command_json!r}: not a JSON object") from None


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    if not (math.isfinite(args.timeout) and 0.1 <= args.timeout <= 600.0):
        raise UserError(f"--timeout {args.timeout}: outside the allowed range [0.1, 600] s")
    message = {"request": "status"} if args.action == "status" else {"command": command_of(args)}
    reply = request(args.connect or cfg.control.endpoint, message, args.token or cfg.control.access_token(),
                    args.timeout)
    if not reply.get("ok"):
        raise UserError(str(reply.get("error", "refused")))
    if args.json or args.action == "status":
        print(json.dumps(reply.get("status", reply)))
    else:
        print(f"{args.action}: queued" + (f"; the save point will be {reply['path']}" if "path" in reply else ""))
    return 0
