"""``icebridge run``: the node. Links -> orders -> ship -> ice world -> outputs, in real time.

After every step the physics process publishes its events on the state stream
(``[stream]``); render processes (``icebridge render-node``, one per channel group, started
here unless ``--render none``) draw the channels from it, so physics never waits for
pictures. With a display they show the window channels; headless they write a video of
the run and a panorama PNG at the end. Shows a live status line; at the end prints a
summary (tick statistics, transport delays, the render processes' files) and writes the
ship's track and the tick times as plots. Ctrl-C (or SIGTERM) ends the run cleanly. With
``[console]`` (the default config's demo) the software console gives the orders from its own
process over a real link (``bridge_node.hil.run_console``); its result is in the summary.
"""
from __future__ import annotations

import argparse
import math
import time
from contextlib import ExitStack, nullcontext
from pathlib import Path

from rich.console import Console
from rich.live import Live
from rich.markup import escape

from bridge_node.charts.field_regions import regions_not_in_the_world
from bridge_node.control.endpoint import ControlEndpoint
from bridge_node.control.queue import CommandQueue
from bridge_node.control.status import exercise_status
from bridge_node.exercise.listeners import StreamOutput
from bridge_node.control.save_point import FORK_FILE, SavePoint, read_save
from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.hil.run_console import RunConsole
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import load_config, new_session_dir
from bridge_node.common.errors import UserError
from bridge_node.common.output_files import write_output
from bridge_node.node.bridges import bridges_summary, open_bridges
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.render_processes import RenderProcesses, open_stream, wait_for_renderers
from bridge_node.node.station_process import StationProcess
from bridge_node.node.world_setup import build_world, start_world, warm_up
from bridge_node.node.fork import resimulate_shown
from bridge_node.node.run_report import plot_run
from bridge_node.reports.summary import print_summary
from bridge_node.stream.publisher import StatePublisher
from bridge_node.links.traffic_picture import TrafficPicture
from bridge_node.node.traffic_setup import traffic_picture
from sim_core.frames.units import KNOT
from sim_core.world import WorldEvents, snapshot


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--rate", type=float, default=None, help="world steps per second (default: config)")
    p.add_argument("--no-record", action="store_true", help="do not record the link traffic")
    p.add_argument("--json", action="store_true", help="end with one JSON summary")
    p.add_argument("--out", default="out", help="folder for the plots and frames (default: out)")
    p.add_argument("--frames-every", type=float, default=None, metavar="S",
                   help="the render processes also write the PNG channels every S simulated seconds to OUT/frames/")
    p.add_argument("--render", choices=("local", "none"), default=None,
                   help="start local render processes (default: config render.processes)")
    p.add_argument("--fork", default=None, metavar="SAVE",
                   help="start from a save point (icebridge ctl save NAME wrote SAVE in its run's session record): "
                        "the record is re-simulated to it, then the run goes on live")


def status_line(events: WorldEvents, alarms: int, station: str | None = None) -> str:
    """One line of the live display: time, position, heading, speed, rudder, floes, alarms,
    and the instructor station's address where it runs."""
    s = events.ship
    return (f"t {events.time:7.1f} s{' FROZEN' if events.environment.frozen else ''} | N {s.north:8.1f} m E "
            f"{s.east:8.1f} m | hdg {math.degrees(s.heading):5.1f} deg | {s.speed_over_ground / KNOT:4.1f} kn | rudder "
            f"{math.degrees(s.rudder_angle):+5.1f} | live floes {events.floes_free} | frozen {events.floes_frozen} | "
            f"alarms {alarms}" + (f" | instructor {station}" if station else ""))


def _end_state(events: WorldEvents) -> dict:
    """The summary's picture of the last published state."""
    s = events.ship
    return {"live_floes": events.floes_free, "frozen_floes": events.floes_frozen, "north_m": round(s.north, 1),
            "east_m": round(s.east, 1), "speed_kn": round(s.speed_longitudinal / KNOT, 2),
            "ice_drift_m": [round(v, 1) for v in events.ice_offset],  # how far the field has drifted, east, north
            "other_ships": [{"north_m": round(o.outputs.north, 1), "east_m": round(o.outputs.east, 1),
                             "speed_kn": round(o.outputs.speed_longitudinal / KNOT, 2)} for o in events.others]}


def _check(args: argparse.Namespace, rate: float) -> None:
    if args.duration is not None and not 0.0 < args.duration <= 7 * 86400.0:
        raise UserError(f"--duration {args.duration} s is outside the allowed range (0, 604800]")
    if not 5.0 <= rate <= 120.0:
        raise UserError(f"--rate {rate} Hz is outside the allowed range [5, 120]")
    if args.frames_every is not None and not 0.1 <= args.frames_every <= 3600.0:
        raise UserError(f"--frames-every {args.frames_every} s is outside the allowed range [0.1, 3600]")


class _StatusLine(StepListener):
    """The live display's line, four times a second; keeps the last events for the summary."""

    def __init__(self, live: Live, hub: LinkHub, first: WorldEvents, station: str | None) -> None:
        self.live, self.hub, self.last, self.station, self._shown = live, hub, first, station, 0.0

    def on_step(self, outcome: TickOutcome) -> None:
        self.last = outcome.events
        if time.monotonic() - self._shown > 0.25:
            self._shown = time.monotonic()
            self.live.update(status_line(outcome.events, len(self.hub.active_alarms), self.station))


def _loop(cfg, args, rate: float, model, data, publisher: StatePublisher, renderers, record, console,
          traffic: TrafficPicture) -> tuple:
    """The real-time loop with its live status line; returns the statistics, the last
    events, the bridges' summary (``bridges_summary``), the control endpoint's counts and
    the station's summary."""
    first = snapshot(model, data)
    with LinkHub(cfg.links, cfg.arbitration, record, traffic, convoy=cfg.convoy) as hub, ExitStack() as bridges, \
            Live(console=console, refresh_per_second=4, transient=True) as live:
        fleet = open_bridges(cfg, hub, record, bridges)
        hubs = [b.hub for b in fleet] or [hub]
        publisher.publish(first)
        live.update("starting the render processes")
        wait_for_renderers(renderers, publisher, 300.0)
        station = StationProcess(cfg, args.config, Path(args.out)) if cfg.instructor.start else nullcontext()
        status = _StatusLine(live, hub, first, station.address if cfg.instructor.start else None)
        queue = CommandQueue(cfg.control.queue, cfg.control.per_tick)
        ice = {"ice": list(model.scene.class_names)}  # what set_ice may lay
        others = [(b.name, b.hub) for b in fleet[1:]]
        with ControlEndpoint(cfg.control, queue, lambda: exercise_status(status.last, data, hub, others) | ice,
                             [link.name for h in hubs for link in h.links], record,
                             model.scene.class_names, len(model.ships)) as control, station:
            stream = StreamOutput(publisher, traffic, model.origin, lambda: snapshot(model, data))
            stats = run_realtime(model, data, hub, rate, args.duration, [stream, status], commands=queue,
                                 scheduler=(cfg.realtime.scheduler, cfg.realtime.priority), fleet=fleet)
        return (stats, status.last, bridges_summary(hub, fleet),
                {"endpoint": cfg.control.endpoint, "requests": dict(control.counts)},
                station.stop() if isinstance(station, StationProcess) else None)


def _fork(model, data, cfg, point: SavePoint, record: Path | None, console: Console) -> None:
    """The world brought to the save point; the run's record names it (``fork.json``)."""
    resimulate_shown(model, data, cfg, point, console)
    if record is not None:
        record.mkdir(parents=True, exist_ok=True)
        write_output(record / FORK_FILE, point.as_json(), "fork point")
    console.print(f"forked from {point.record} at step {point.seq} ({point.time:.1f} s)")


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)
    rate = args.rate if args.rate is not None else cfg.realtime.rate_hz
    _check(args, rate)
    traffic = traffic_picture(cfg, args.config)
    console = Console(stderr=args.json)
    unlaid = regions_not_in_the_world(cfg.ice_field, cfg.exercise.origin_deg())
    if unlaid:
        console.print(escape(f"ice_field: {', '.join(unlaid)}: land or no data, which the ice world does not lay "
                             "out: the tiles under them keep the level ice of [ice_field]"), style="yellow")
    out = Path(args.out)
    record = None if args.no_record else new_session_dir(cfg, args.config)
    point = read_save(Path(args.fork).expanduser()) if args.fork else None
    local = args.render == "local" or (args.render is None and cfg.render.processes == "local")
    renderers = RenderProcesses(cfg, args.config, out, args.frames_every) if local else None
    rendered = []
    with RunConsole(cfg, args.config, out, record) as run_console, open_stream(cfg.stream) as publisher:
        cfg = run_console.cfg  # with the console's link, if the config has one
        try:
            if renderers:
                renderers.start()  # they load the exercise while this process does
            with console.status("loading the exercise"):
                model = build_world(cfg, args.config)
                data = start_world(model, cfg, args.config)
                warm_up(model, cfg)
            if point is not None:
                _fork(model, data, cfg, point, record, console)
            stats, last, bridges, control, station = _loop(cfg, args, rate, model, data, publisher, renderers, record,
                                                        console, traffic)
        finally:
            if renderers:  # before the stream closes, so that they draw the last state
                rendered = renderers.stop()
    summary = stats.summary() | _end_state(last) | {
        "rate_hz": rate, "late_tile_switches": data.late_switches, **bridges,
        "stream": {"sent": publisher.sent, "dropped": publisher.dropped, "snapshots": publisher.snapshots,
                   "malformed": publisher.malformed, "error": publisher.error},
        "render_processes": rendered, "frames_rendered": sum(r.get("png_frames", 0) for r in rendered),
        "video": [r["video"] for r in rendered if "video" in r],
        "panorama": [r["panorama"] for r in rendered if "panorama" in r],
        "record": str(record) if record else None, "console": run_console.summary(), "control": control,
        "instructor": station, "forked_from": {"record": point.record, "step": point.seq} if point else None,
    }
    try:  # a finished run's summary is never lost to a plotting error
        summary["plot"] = str(plot_run(stats, out / "run.png"))
    except (OSError, ValueError) as exc:
        summary["plot_error"] = str(exc)
    return print_summary(summary, args.json, console)
