"""The debrief of a session record: what the node sent the bridge instruments (``nmea.log``'s
tx sentences: RMC position, speed and course; HDT heading; RSA rudder; RPM shaft; XDR ice
resistance; ALR alarms) and the instructor's commands (``commands.log``, timed by
``ticks.log``; the areas where the instructor laid ice with them), as time series the page
plays back on the map, and as time plots (PNG). A record of several own ships adds each
other ship's track and heading from what its own instruments were sent (``ships/<k>/``)."""
from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pynmea2

from bridge_node.exercise.command_log import COMMANDS_FILE
from bridge_node.control.commands import CommandError, command_from_record
from bridge_node.links.record_reader import complete_lines, read_nmea_log
from bridge_node.common.errors import UserError
from bridge_node.exercise.tick_record import TICKS_FILE, read_ticks
from bridge_node.replay.session import FLEET_FOLDER
from bridge_node.station.events import describe
from bridge_node.station.wire import pack
from sim_core.frames.geodesy import geodetic_to_local
from sim_core.instructor import SetIce

# series name -> (sentence, what it is, unit): each is sampled at its sentence's own times
SERIES = {"sog": ("RMC", "speed over ground", "kn"), "heading": ("HDT", "heading", "deg"),
          "rudder": ("RSA", "rudder angle", "deg (+ stbd)"), "rpm": ("RPM", "shaft", "rpm"),
          "ice": ("XDR", "ice resistance", "kN")}


@dataclass
class Debrief:
    """A record's tx time series (unix s and values), positions (local east/north, m) and
    events (unix s, kind, text)."""

    folder: Path
    series: dict[str, tuple[list[float], list[float]]] = field(default_factory=lambda: {k: ([], []) for k in SERIES})
    position: tuple[list[float], list[float], list[float]] = field(default_factory=lambda: ([], [], []))
    events: list[dict] = field(default_factory=list)
    skipped: int = 0  # tx sentences that did not parse
    others: dict[int, Debrief] = field(default_factory=dict)  # k -> the k-th other own ship's (ships/<k>/)

    @property
    def start(self) -> float:
        times = [t[0] for t, _ in self.series.values() if t] + self.position[0][:1]
        return min(times) if times else 0.0

    @property
    def end(self) -> float:
        times = [t[-1] for t, _ in self.series.values() if t] + self.position[0][-1:]
        return max(times) if times else 0.0


def _add(d: Debrief, unix: float, sentence: str, origin: tuple[float, float]) -> None:
    """One tx sentence into the debrief (unknown kinds ignored)."""
    msg = pynmea2.parse(sentence)
    kind, data = msg.sentence_type, msg.data
    if kind == "RMC" and data[1] == "A":
        north, east = geodetic_to_local(math.radians(msg.latitude), math.radians(msg.longitude), *origin)
        for column, value in zip(d.position, (unix, east, north)):
            column.append(value)
        d.series["sog"][0].append(unix)
        d.series["sog"][1].append(float(data[6]))
    elif kind == "ALR":
        d.events.append({"t": unix, "kind": "alarm" if data[2] == "A" else "cleared", "text": data[4]})
    elif kind == "XDR" and len(data) >= 4 and data[3] == "ICE_RES":
        d.series["ice"][0].append(unix)
        d.series["ice"][1].append(float(data[1]) / 1e3)
    else:
        index = {"HDT": ("heading", 0), "RSA": ("rudder", 0), "RPM": ("rpm", 2)}.get(kind)
        if index is not None and data[index[1]]:
            d.series[index[0]][0].append(unix)
            d.series[index[0]][1].append(float(data[index[1]]))


def _commands(d: Debrief) -> None:
    """The instructor's commands of the record, at the unix time of their step."""
    path = d.folder / COMMANDS_FILE
    if not path.exists() or not (d.folder / TICKS_FILE).exists():
        return
    try:
        _, ticks, _ = read_ticks(d.folder / TICKS_FILE)
    except ValueError:
        return
    unix = {t.seq: t.unix for t in ticks}
    lines, _ = complete_lines(path)
    for line in lines:
        try:
            entry = json.loads(line)
            command = command_from_record(entry["command"])
            kind, text = describe(command)
            event = {"t": unix.get(entry["seq"], math.nan), "kind": kind, "text": text}
            if isinstance(command, SetIce):  # the map draws the area from then on
                event |= {"ice": command.ice, "area": [list(corner) for corner in command.polygon]}
            d.events.append(event)
        except (ValueError, KeyError, TypeError, CommandError):
            d.skipped += 1


def load_debrief(folder: Path, origin: tuple[float, float]) -> Debrief:
    """The debrief of a session record folder, with the other own ships' tracks where it has
    them; UserError if it is no record or holds no position sent. ``origin``: the
    exercise's (latitude, longitude), rad."""
    folder = Path(folder)
    if not (folder / "nmea.log").is_file():
        raise UserError(f"--record {folder}: no nmea.log there (is it a session record folder?)")
    d = _sent(folder, origin)
    if not d.position[0]:
        raise UserError(f"--record {folder}: its nmea.log holds no position the node sent (RMC); was an NMEA "
                        "0183 output link configured?")
    _commands(d)
    d.events.sort(key=lambda e: e["t"] if math.isfinite(e["t"]) else math.inf)
    ships = folder / FLEET_FOLDER
    for path in sorted(ships.iterdir() if ships.is_dir() else [], key=lambda p: p.name):
        if path.name.isdigit() and (path / "nmea.log").is_file():  # a ship without NMEA outputs has no track here
            other = _sent(path, origin)
            d.others[int(path.name)] = other
            d.skipped += other.skipped
    return d


def _sent(folder: Path, origin: tuple[float, float]) -> Debrief:
    """What the node sent on the NMEA links recorded in ``folder``."""
    d = Debrief(folder)
    records, _ = read_nmea_log(folder / "nmea.log")
    for r in records:
        if r.direction != "tx":
            continue
        try:
            _add(d, r.unix_time, r.sentence, origin)
        except (pynmea2.ParseError, ValueError, TypeError, IndexError, AttributeError):
            d.skipped += 1
    return d


def debrief_message(d: Debrief, fleet: dict[int, tuple[str, float, float]] | None = None) -> bytes:
    """The page's ``debrief`` message: times relative to the record's start (s). ``fleet``:
    the other own ships' names, lengths and beams (m) by k, as the exercise's config gives
    them; a ship it lacks is "ship k", drawn at the map's default size."""
    fleet = fleet or {}
    t0 = d.start
    arrays = {"pos_t": np.array(d.position[0]) - t0, "pos_east": d.position[1], "pos_north": d.position[2]}
    for name, (t, v) in d.series.items():
        arrays[f"{name}_t"], arrays[name] = np.array(t) - t0, np.array(v, dtype=float)
    for k, other in d.others.items():  # "ship<k>_t", "ship<k>_east"...: its positions and headings
        arrays |= {f"ship{k}_t": np.array(other.position[0]) - t0, f"ship{k}_east": other.position[1],
                   f"ship{k}_north": other.position[2], f"ship{k}_heading_t": np.array(other.series["heading"][0]) - t0,
                   f"ship{k}_heading": other.series["heading"][1], f"ship{k}_sog": other.series["sog"][1]}
    events = [{**e, "t": e["t"] - t0} for e in d.events if math.isfinite(e["t"])]
    return pack({"type": "debrief", "record": str(d.folder), "start_unix": t0, "duration": d.end - t0,
                 "events": events, "skipped": d.skipped,
                 "ships": [dict(zip(("k", "name", "length", "beam"), (k, *fleet.get(k, (f"ship {k}", 0.0, 0.0)))))
                           for k in sorted(d.others)]},
                {k: np.asarray(v, dtype=np.float64) for k, v in arrays.items()})


def plot_png(d: Debrief) -> bytes:
    """The time plots of speed, heading, rudder, RPM and ice resistance, with the commands
    and alarms as lines, as PNG bytes."""
    from bridge_node.reports.figures import plt

    t0 = d.start
    fig, axes = plt.subplots(len(SERIES), 1, figsize=(10, 9), sharex=True)
    for ax, (name, (_, what, unit)) in zip(axes, SERIES.items()):
        t, v = d.series[name]
        v = np.degrees(np.unwrap(np.radians(v))) if name == "heading" and v else v  # no jumps at north
        ax.plot(np.array(t) - t0, v, lw=1.2, color="#1f5f9f")
        ax.set_ylabel(f"{what}\n{unit}", fontsize=8)
        ax.grid(alpha=0.3)
        for e in d.events:
            if math.isfinite(e["t"]):
                ax.axvline(e["t"] - t0, color="#d0452b" if e["kind"] in ("failure", "alarm") else "#888", lw=0.7,
                           alpha=0.7)
    for e in d.events:
        if math.isfinite(e["t"]):
            axes[0].annotate(e["text"], (e["t"] - t0, 1.0), xycoords=("data", "axes fraction"), rotation=90,
                             fontsize=6, va="top", ha="right", color="#555")
    axes[-1].set_xlabel("time since the record's first sentence, s")
    axes[0].set_title(f"session {d.folder.name}: what the bridge instruments were sent", fontsize=10)
    fig.tight_layout()
    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, dpi=100, format="png")
    finally:
        plt.close(fig)
    return buffer.getvalue()
