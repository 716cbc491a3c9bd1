"""``icebridge replay``: a logged voyage through the ice.

Track logs (NMEA 0183, AIS, CSV, GPX) drive the ship kinematically along the logged
positions and headings, and the hull breaks the ice along them as a driven ship does; the
field is placed under the track. A session record of a run is re-simulated from the
console orders it holds. The ship's state goes out on the configured links, the channels
render, and at the end a summary (distance, duration, cells broken, time in level ice, in
the broken channel and in open water, bad data) is printed and the track over the ice,
the speed and the heading are plotted to ``OUT/replay.png``.
"""
from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import math
from contextlib import ExitStack, nullcontext
from pathlib import Path

import numpy as np
from rich.console import Console

from bridge_node.control.save_point import FORK_FILE, read_save
from bridge_node.hil.run_console import LINK_NAME as RUN_CONSOLE_LINK
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import DEFAULT_CONFIG, NodeConfig, load_config
from bridge_node.common.errors import UserError
from bridge_node.node.bridges import bridges_summary, open_bridges
from bridge_node.node.render_processes import RenderProcesses, open_stream, wait_for_renderers
from bridge_node.node.world_setup import build_world, start_exercise, start_position, start_world, warm_up
from bridge_node.replay.console import KeyReader, ReplayProgress, logged_text
from bridge_node.replay.csv_track import parse_mapping
from bridge_node.replay.engine import MAX_SPEED, MIN_SPEED, Playback, ReplayStats, Source, run_replay
from bridge_node.replay.inputs import LOOKED_FOR, VesselChoice, check_span, load_inputs
from bridge_node.node.fork import resimulate_shown
from bridge_node.node.fleet_session import session_source
from bridge_node.replay.session import RecordedSession, SessionSource, recorded_config
from bridge_node.replay.track import Track, TrackLog, TrackPath, TrackSource, clean_for, origin_under
from bridge_node.reports.replay import gap_summary, plot_replay
from bridge_node.reports.summary import print_summary
from bridge_node.traffic.sources import replay_traffic
from sim_core.frames.units import KNOT
from sim_core.world import WorldData, WorldModel, new_world_data, snapshot


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("files", nargs="+", metavar="FILE",
                   help="track logs (NMEA 0183, AIS, CSV, GPX) of one voyage, or a session record (folder or files)")
    pace = p.add_mutually_exclusive_group()
    pace.add_argument("--speed", type=float, default=None, metavar="X",
                      help=f"times real time, {MIN_SPEED:g} to {MAX_SPEED:g} (default 1)")
    pace.add_argument("--max", action="store_true", help="as fast as possible")
    p.add_argument("--from", dest="start", default=None, metavar="T",
                   help="start: seconds from the log's start, HH:MM[:SS] UTC or an ISO 8601 time")
    p.add_argument("--to", dest="end", default=None, metavar="T", help="end, as --from")
    p.add_argument("--mmsi", type=int, default=None, help="the AIS vessel to replay (without it: list the vessels)")
    p.add_argument("--columns", default=None, metavar="MAP",
                   help="CSV columns by name: time=..,date=..,lat=..,lon=..,heading=..,course=..,speed=..,"
                        "speed_unit=kn|m/s|km/h,mmsi=..")
    p.add_argument("--field-origin", default=None, metavar="LAT,LON",
                   help="the ice field's south-west corner, deg (default: the first fix at the exercise's start)")
    p.add_argument("--render", choices=("local", "none"), default=None,
                   help="start local render processes (default: config render.processes)")
    p.add_argument("--record", default=None, metavar="DIR", help="record the replay's link traffic in DIR")
    p.add_argument("--json", action="store_true", help="end with one JSON summary")
    p.add_argument("--out", default="out", help="folder for the plot (default: out)")


def parse_time(text: str, option: str, start: float, end: float, absolute: bool) -> float:
    """A --from/--to value as logged time (s): seconds from the start, HH:MM[:SS] UTC on the
    log's first day, or an ISO 8601 time (UTC unless given); UserError outside the log."""
    try:
        t = start + float(text)
    except ValueError:
        if not absolute:
            raise UserError(f"{option} {text!r}: this log has no date and time; give seconds from its start") from None
        try:
            moment = dt.datetime.fromisoformat(text)
        except ValueError:
            try:
                day = dt.datetime.fromtimestamp(start, dt.timezone.utc).date()
                moment = dt.datetime.combine(day, dt.time.fromisoformat(text))
            except ValueError:
                raise UserError(f"{option} {text!r}: not a time; give seconds from the log's start, HH:MM:SS "
                                "or an ISO 8601 time") from None
        t = (moment if moment.tzinfo else moment.replace(tzinfo=dt.timezone.utc)).timestamp()
    if not math.isfinite(t) or not start <= t <= end:
        raise UserError(f"{option} {text!r}: outside the log ({logged_text(start, absolute)} to "
                        f"{logged_text(end, absolute)})")
    return t


def _field_origin(text: str | None) -> tuple[float, float] | None:
    """--field-origin as (lat, lon) rad; UserError naming the value."""
    if text is None:
        return None
    try:
        lat, lon = (float(x) for x in text.split(","))
    except ValueError:
        raise UserError(f"--field-origin {text!r}: give LAT,LON in decimal degrees, e.g. 74.0,20.0") from None
    if not (-89.0 <= lat <= 89.0 and -180.0 <= lon <= 180.0):
        raise UserError(f"--field-origin {text!r}: latitude must be within [-89, 89], longitude [-180, 180]")
    return math.radians(lat), math.radians(lon)


def _check(args: argparse.Namespace) -> None:
    if args.speed is not None and not MIN_SPEED <= args.speed <= MAX_SPEED:
        raise UserError(f"--speed {args.speed}: outside the allowed range [{MIN_SPEED:g}, {MAX_SPEED:g}]")
    if args.mmsi is not None and not 100_000_000 <= args.mmsi <= 999_999_999:
        raise UserError(f"--mmsi {args.mmsi}: an MMSI has nine digits")


@dataclasses.dataclass
class _Prepared:
    """A replay ready to run: the world, its start, the source and what the summary tells."""

    model: WorldModel
    data: WorldData
    source: Source
    seek_to: int
    info: dict
    track: Track | None = None
    track_ne: np.ndarray | None = None  # the logged fixes on the field: north, east m


def _track_replay(cfg: NodeConfig, args: argparse.Namespace, log: TrackLog, origin: tuple | None,
                  model: WorldModel) -> _Prepared:
    """A track log cleaned, cut to --from/--to, the field placed under it."""
    r = cfg.replay
    track = clean_for(log, r)
    if track is None or len(track.t) < 2:
        raise UserError(f"{', '.join(log.files)}: no usable track: {0 if track is None else 1} fix left after "
                        f"cleaning (a track needs two; looked for {LOOKED_FOR})")
    t0 = parse_time(args.start, "--from", track.start, track.end, log.absolute) if args.start else track.start
    t1 = parse_time(args.end, "--to", track.start, track.end, log.absolute) if args.end else track.end
    if t1 <= t0:
        raise UserError(f"--from {args.start!r} is not before --to {args.end!r}")
    check_span(log.files, t0, t1, r.step_s, log.absolute)
    placed = "--field-origin" if origin else "first fix at the exercise's start"
    if origin is None:
        first = min(int(track.t.searchsorted(t0)), len(track.t) - 1)
        origin = origin_under(track.lat[first], track.lon[first], *start_position(model, cfg))
    model = dataclasses.replace(model, origin=origin)
    path = TrackPath(track, origin, r.max_gap_s)
    source = TrackSource(path, t0, t1, r.step_s)
    pose = path.pose(t0, r.step_s)
    data = new_world_data(model, pose.north, pose.east, pose.heading, pose.surge)
    start_exercise(model, data, cfg)
    if log.absolute:  # the outputs and the sky carry the logged UTC where the log has it
        data.epoch = t0
    info = {"kind": "track", "files": log.files, "vessel": log.vessel, "heading_from": track.heading_source,
            "records_read": dict(log.read), "records_ignored": dict(log.ignored), "bad_data": dict(log.bad),
            **gap_summary(track),
            "jumps_skipped": [{"at": logged_text(j.time, log.absolute), "distance_m": round(j.distance, 1),
                               "speed_kn": round(j.speed / KNOT, 1)} for j in track.jumps],
            "field_origin": {"latitude_deg": round(math.degrees(origin[0]), 7),
                             "longitude_deg": round(math.degrees(origin[1]), 7), "placed": placed}}
    return _Prepared(model, data, source, 0, info, track, np.column_stack([path.north.value, path.east.value]))


def _session_replay(cfg: NodeConfig, args: argparse.Namespace, session: RecordedSession,
                    model: WorldModel) -> _Prepared:
    """A session record re-simulated on its own exercise from the first tick; --from runs ahead."""
    if args.field_origin is not None:
        raise UserError("--field-origin: a session record is re-simulated on its own exercise; leave it out")
    if not session.ticks:
        raise UserError(f"{session.folder}: no usable track: the session record holds no tick and no input "
                        f"(looked for {LOOKED_FOR})")
    source = session_source(cfg, session)
    first, last = session.ticks[0].unix, session.ticks[-1].unix + session.period
    seek = 0
    if args.start:
        t = parse_time(args.start, "--from", first, last, True)
        seek = next(k for k, tick in enumerate(session.ticks) if tick.unix >= t - 0.5 * session.period)
    if args.end:
        t = parse_time(args.end, "--to", first, last, True)
        source.steps = next((k for k, tick in enumerate(session.ticks) if tick.unix > t), len(session.ticks))
        if source.steps <= seek:
            raise UserError(f"--from {args.start!r} is not before --to {args.end!r}")
    info = {"kind": "session", "files": [str(session.folder / f) for f in session.files],
            "ticks": len(session.ticks), "exact": session.exact, "inputs_read": dict(session.reads),
            "bad_data": dict(session.bad)}
    data = start_world(model, cfg, args.config)  # the recorded run's exercise clock and environment (its node.toml)
    return _Prepared(model, data, source, seek, info)


def _summary(prep: _Prepared, stats: ReplayStats, playback: Playback) -> dict:
    s = prep.source
    first = s.logged_time(0)
    rows = stats.samples()
    return {
        "input": prep.info,
        "logged_start": logged_text(first, s.absolute), "logged_end": logged_text(first + stats.sim_s, s.absolute),
        "shown_from": logged_text(s.logged_time(min(prep.seek_to, s.steps - 1)), s.absolute),
        "duration_s": round(stats.sim_s, 2), "steps": stats.steps, "step_s": s.dt,
        "distance_m": round(stats.distance, 1), "distance_nm": round(stats.distance / 1852.0, 3),
        "cells_broken": {"by_hull": stats.broken_by_hull, "by_contact": stats.broken_by_contact},
        "time_s": {k: round(v, 1) for k, v in sorted(stats.time_in.items())},
        "off_field": [{"from": logged_text(a - s.dt, s.absolute), "to": logged_text(b, s.absolute)}
                      for a, b in stats.off_field],
        "end": {"north_m": round(float(rows[-1, 1]), 1), "east_m": round(float(rows[-1, 2]), 1)} if len(rows) else {},
        "other_ships": [{"north_m": round(float(ship.eta[0]), 1), "east_m": round(float(ship.eta[1]), 1)}
                        for ship in prep.data.ships[1:]],
        "wall_s": round(stats.wall_s, 2), "speed_x": round(stats.sim_s / max(stats.wall_s, 1e-9), 2),
        "pace": "max" if playback.speed is None else playback.speed,
        "orders_rejected": dict(stats.refusals.counts), "console_orders_ignored": stats.console_orders_ignored,
    }


def _print_vessels(choice: VesselChoice, as_json: bool, console: Console) -> None:
    if as_json:
        print(json.dumps({"vessels": choice.vessels}))
        return
    console.print("Several vessels in the log; pick one with --mmsi:")
    for v in choice.vessels:
        span = f"{logged_text(v['first'], True)} to {logged_text(v['last'], True)}" if v["first"] else "no time"
        console.print(f"  {v['mmsi']:>9}  {v['name'] or '-':20}  {v['position_reports']:6d} positions  {span}")


def _play(cfg: NodeConfig, args: argparse.Namespace, prep: _Prepared, playback: Playback,
          console: Console) -> tuple[ReplayStats, dict]:
    """Run the replay with its outputs: links, state stream, render processes, the
    terminal; returns the statistics and what the outputs report."""
    out = Path(args.out)
    local = args.render == "local" or (args.render is None and cfg.render.processes == "local")
    renderers = RenderProcesses(cfg, args.config, out, None) if local else None
    session = prep.source if isinstance(prep.source, SessionSource) else nullcontext()
    rendered = []
    with open_stream(cfg.stream) as publisher:
        try:
            if renderers:
                renderers.start()
            traffic = replay_traffic(prep.source, prep.seek_to, prep.model.origin, cfg.replay, cfg.links)
            # the run's software console was another process, gone now: its orders come from the record
            links = [s for s in cfg.links if not (args.recorded and s.name == RUN_CONSOLE_LINK)]
            record = Path(args.record) if args.record else None
            with LinkHub(links, cfg.arbitration, record, traffic, convoy=cfg.convoy) as hub, ExitStack() as others, \
                    session, KeyReader() as keys, ReplayProgress(console, prep.source, keys) as progress:
                fleet = open_bridges(cfg, hub, record, others)
                publisher.publish(snapshot(prep.model, prep.data))
                wait_for_renderers(renderers, publisher, 300.0)
                stats = run_replay(prep.model, prep.data, prep.source, playback, hub, publisher, progress, fleet)
                bridges = bridges_summary(hub, fleet)
        finally:
            if renderers:
                rendered = renderers.stop()
    return stats, {**bridges,
                   "stream": {"sent": publisher.sent, "dropped": publisher.dropped, "error": publisher.error},
                   "render_processes": rendered, "video": [r["video"] for r in rendered if "video" in r],
                   "record": args.record}


def run(args: argparse.Namespace) -> int:
    args.recorded = args.config is None and recorded_config(args.files) is not None
    args.config = args.config or recorded_config(args.files)  # a record's own node.toml: an exact replay
    cfg = load_config(args.config)
    _check(args)
    console = Console(stderr=args.json)
    origin = _field_origin(args.field_origin)
    loaded = load_inputs(args.files, args.mmsi, parse_mapping(args.columns), 1.0 / cfg.realtime.rate_hz)
    if isinstance(loaded, VesselChoice):
        _print_vessels(loaded, args.json, console)
        return 0
    with console.status("loading the exercise"):
        model = build_world(cfg, args.config)
    prep = _session_replay(cfg, args, loaded, model) if isinstance(loaded, RecordedSession) else \
        _track_replay(cfg, args, loaded, origin, model)
    if isinstance(loaded, RecordedSession) and (loaded.folder / FORK_FILE).is_file():  # a forked run's start
        resimulate_shown(prep.model, prep.data, cfg, read_save(loaded.folder / FORK_FILE), console)
    playback = Playback(None if args.max else (args.speed or 1.0), seek_to=prep.seek_to)
    if playback.speed is not None:
        with console.status("compiling the ice kernels"):
            warm_up(prep.model, cfg)
    stats, outputs = _play(cfg, args, prep, playback, console)
    summary = _summary(prep, stats, playback) | outputs | {"config": str(args.config or DEFAULT_CONFIG)}
    if isinstance(prep.source, SessionSource):
        summary["input"] |= {"orders": dict(prep.source.orders), "console_errors": prep.source.errors()}
    title = prep.info.get("vessel") or ", ".join(Path(f).name for f in prep.info["files"])
    out = Path(args.out)
    try:  # a finished replay's summary is never lost to a plotting error
        summary["track_csv"] = str(stats.write_csv(out / "replay_track.csv", prep.model.origin))
        summary["plot"] = str(plot_replay(prep.model, prep.data, stats, prep.track, prep.track_ne,
                                          f"replay of {title}", out / "replay.png"))
    except (OSError, ValueError) as exc:
        summary["plot_error"] = str(exc)
    return print_summary(summary, args.json, console)
