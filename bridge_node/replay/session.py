"""Re-simulation of a recorded run from its session record: the console orders it received
drive the ship model again, tick for tick.

The record's raw inputs (received NMEA 0183 sentences, received CAN frames, Modbus register
reads) are given back to the node's own link code, in the order and at the ticks they were
read (``ticks.log``, written by the real-time loop), with each tick's recorded clock: an
NMEA link reads them from a ``loop://`` serial port, a CAN link from python-can's virtual
bus, and the Modbus reads go through the link's register decoding. The links' orders are
arbitrated as the node did. The same orders at the same steps give the same track, the
same broken cells and the same outputs. A record without a tick log (an older one) is
re-simulated approximately: each input is given to the tick its unix time falls in.
"""
from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import can

from bridge_node.control.command_log import COMMANDS_FILE, read_commands
from bridge_node.control.commands import NODE_COMMANDS
from bridge_node.links.base import Link
from bridge_node.links.messages import Alarm, ControlInput
from bridge_node.links.can_link import CanLink
from bridge_node.links.faults import LinkFault
from bridge_node.links.hub import LinkHub
from bridge_node.links.modbus_link import register_order
from bridge_node.links.nmea_link import NmeaLink
from bridge_node.links.record_reader import check_tick_count, read_can_log, read_modbus_csv, read_nmea_log
from bridge_node.node.config import NodeConfig
from bridge_node.node.tick_record import PROTOCOLS, TICKS_FILE, Tick, read_ticks
from sim_core.instructor import Command
from sim_core.world import Controls

RECORD_FILES = {"nmea0183": "nmea.log", "can": "can.log", "modbus": "modbus.csv"}  # protocol -> file
NODE_CONFIG = "node.toml"  # the node config a run used, kept in its session record
_channels = itertools.count()


@dataclass
class RecordedSession:
    """A session record read back: the step period (s), the ticks (recorded, or made up
    from unix times when ``exact`` is False), each tick's inputs per protocol (NMEA
    ``NmeaRecord``, CAN ``can.Message``, Modbus row dicts), and what was wrong with it."""

    folder: Path
    files: list[str]
    period: float
    ticks: list[Tick]
    inputs: list[dict[str, list]]
    exact: bool
    bad: Counter = field(default_factory=Counter)
    commands: dict[int, list] = field(default_factory=dict)  # step -> instructor commands applied (world's, node's)

    @property
    def reads(self) -> Counter:
        """Inputs per protocol over the whole record."""
        return Counter({p: sum(len(t[p]) for t in self.inputs) for p in PROTOCOLS})


_READERS = {"nmea0183": (read_nmea_log, lambda r: r.direction == "rx", lambda r: r.unix_time),
            "can": (read_can_log, lambda m: m.is_rx, lambda m: m.timestamp),
            "modbus": (read_modbus_csv, lambda row: row.get("op") == "read", lambda row: float(row["unix_time"]))}


def _received(folder: Path, names: set[str], bad: Counter) -> tuple[dict[str, list], dict[str, list[float]]]:
    """The recorded inputs of each protocol in file order (files not chosen: none), and the
    unix times of every line, inputs and outputs, per protocol."""
    inputs, times = {p: [] for p in PROTOCOLS}, {p: [] for p in PROTOCOLS}
    for protocol, (reader, is_input, unix_time) in _READERS.items():
        path = folder / RECORD_FILES[protocol]
        if RECORD_FILES[protocol] in names and path.is_file():
            records, counts = reader(path)
            inputs[protocol] = [r for r in records if is_input(r)]
            times[protocol] = [unix_time(r) for r in records]
            bad.update({f"{RECORD_FILES[protocol]} {k}": n for k, n in counts.items() if n})
    return inputs, times


def recorded_config(paths: list[str]) -> Path | None:
    """The node config kept in the session record that ``paths`` name (the record's folder
    or files in it: one folder with a tick log), or None where there is none."""
    folders = {path if path.is_dir() else path.parent for path in (Path(p).expanduser() for p in paths)}
    if len(folders) != 1:
        return None
    folder = folders.pop()
    config = folder / NODE_CONFIG
    return config if config.is_file() and (folder / TICKS_FILE).is_file() else None


def read_session(folder: Path, names: set[str], period: float) -> RecordedSession:
    """The session record in ``folder`` (its files ``names``); ``period`` (s) is the step
    when it has no tick log. ValueError for a tick log that cannot be used."""
    bad: Counter = Counter()
    received, line_times = _received(folder, names, bad)
    ticks_path = folder / TICKS_FILE
    if ticks_path.is_file():
        period, ticks, counts = read_ticks(ticks_path)
        bad.update({f"{TICKS_FILE} {k}": n for k, n in counts.items() if n})
        taken = {p: 0 for p in PROTOCOLS}
        inputs = []
        for tick in ticks:
            row = {}
            for p, n in zip(PROTOCOLS, tick.reads):
                row[p] = received[p][taken[p]:taken[p] + n]
                if len(row[p]) < n:
                    bad[f"{RECORD_FILES[p]} lines missing"] += n - len(row[p])
                taken[p] += n
            inputs.append(row)
        for p in PROTOCOLS:
            if len(received[p]) > taken[p]:  # recorded after the last tick line was written
                bad[f"{RECORD_FILES[p]} after the last tick"] += len(received[p]) - taken[p]
        commands = {}
        if (folder / COMMANDS_FILE).is_file():
            commands, counts = read_commands(folder / COMMANDS_FILE)
            bad.update({f"{COMMANDS_FILE} {k}": n for k, n in counts.items() if n})
        return RecordedSession(folder, sorted(names), period, ticks, inputs, True, bad, commands)
    times = [t for p in PROTOCOLS for t in line_times[p]]
    if not times:
        return RecordedSession(folder, sorted(names), period, [], [], False, bad)
    t0 = min(times)  # about the first tick: its outputs are the record's first lines
    n = check_tick_count(folder, times, period)
    ticks = [Tick(k, t0 + k * period, t0 + k * period, ()) for k in range(n)]
    inputs = [{p: [] for p in PROTOCOLS} for _ in range(n)]
    for p in PROTOCOLS:
        for item in received[p]:
            inputs[min(n - 1, round((_READERS[p][2](item) - t0) / period))][p].append(item)
    return RecordedSession(folder, sorted(names), period, ticks, inputs, False, bad)


class _RecordedModbus(Link):
    """A Modbus link whose register reads come from the record: each read row becomes the
    order its register holds, timed at its read (the tick's clock, less the time between
    the read and the tick's poll)."""

    def __init__(self, settings) -> None:
        super().__init__(settings)
        self.pending: list[tuple[float, dict]] = []  # (monotonic time of the read, row)
        self._specs = {(r.table, r.address): r for r in settings.registers}

    def _open_device(self) -> object:
        return self.pending

    def _close_device(self, device) -> None:
        pass

    def _poll_device(self, now: float) -> Iterator[ControlInput]:
        rows, self.pending = self.pending, []
        for when, row in rows:
            spec = self._specs.get((row["table"], int(row["address"])))
            if spec is None:
                continue  # a register this config does not read as an order
            order = register_order(spec, int(row["raw"]), when, self.name)
            if isinstance(order, str):
                self._count_error(order)
            else:
                yield order

    def publish(self, state, now: float) -> None:
        pass


class SessionSource:
    """A replay source: the recorded run's console links, fed its inputs tick by tick, polled
    and arbitrated by a ``LinkHub`` as the live run's were (link-down alarms included), give
    the orders of each step. Use as a context manager."""

    absolute = True  # logged times are the ticks' unix times

    def __init__(self, cfg: NodeConfig, session: RecordedSession) -> None:
        self.session = session
        self.dt, self.steps = session.period, len(session.ticks)
        links: list[Link] = []
        self.feeds: dict[str, can.BusABC] = {}  # CAN link name -> the bus its recorded frames are sent on
        self._can_channels: dict[str, Link] = {}  # recorded channel -> CAN link
        for s in cfg.links:
            if s.type == "nmea0183":
                links.append(NmeaLink(s.model_copy(update={"port": "loop://", "udp_output": False})))
            elif s.type == "can":
                channel = f"icebridge-replay-{next(_channels)}"
                links.append(CanLink(s.model_copy(update={"interface": "virtual", "channel": channel})))
                self.feeds[s.name] = can.Bus(interface="virtual", channel=channel)
                self._can_channels[s.channel] = links[-1]
            elif s.type == "modbus":
                links.append(_RecordedModbus(s))
        self.hub = LinkHub(cfg.links, cfg.arbitration, made=links)
        self.links = self.hub.links

    @property
    def orders(self) -> Counter:
        """Orders decoded, by "link/kind/engine"."""
        return self.hub.order_counts

    def __enter__(self) -> SessionSource:
        for link in self.links:  # in-process ports and buses: fed at once, so opened before the first tick
            link.open(wait=None)
        return self

    def __exit__(self, *exc) -> None:
        self.hub.close()
        for bus in self.feeds.values():
            bus.shutdown()

    def _feed(self, tick: Tick, inputs: dict[str, list]) -> None:
        by_name = {link.name: link for link in self.links}
        for link in self.links:  # one reopened after a fault: opened before it is fed, as the run's was read
            if link.device is None:
                link.await_open(None)
        for record in inputs["nmea0183"]:
            link = by_name.get(record.link)
            if isinstance(link, NmeaLink) and link.device is not None:
                link.device.port.write((record.sentence + "\r\n").encode("ascii", errors="replace"))
        for msg in inputs["can"]:  # the frame's link by its recorded channel, else the first CAN link
            link = self._can_channels.get(str(msg.channel), next(iter(self._can_channels.values()), None))
            if link is not None:
                self.feeds[link.name].send(msg)
        for row in inputs["modbus"]:
            link = by_name.get(row["link"])
            if isinstance(link, _RecordedModbus):
                link.pending.append((tick.monotonic - (tick.unix - float(row["unix_time"])), row))

    def logged_time(self, k: int) -> float:
        """Unix time of tick k's poll, s."""
        return self.session.ticks[k].unix

    def commands(self, k: int) -> tuple[Command, ...]:
        """The instructor's commands the recorded run's world applied at tick k's step."""
        return tuple(c for c in self._applied(k) if not isinstance(c, NODE_COMMANDS))

    def _applied(self, k: int) -> list:
        return self.session.commands.get(self.session.ticks[k].seq + 1, [])

    def inputs(self, k: int) -> tuple[Controls, list[Alarm], float]:
        """Tick k: its inputs read by the links, the orders arbitrated; returns the
        controls for the step, the alarm changes and the tick's clock (monotonic s)."""
        tick = self.session.ticks[k]
        now = tick.monotonic
        for fault in (c for c in self._applied(k) if isinstance(c, LinkFault)):  # as the run put them, before its poll
            self.hub.fault_link(fault, now)
        self._feed(tick, self.session.inputs[k])
        decision = self.hub.poll(now)
        for bus in self.feeds.values():  # what the CAN links sent (address claims): not needed
            while bus.recv(0.0) is not None:
                pass
        return decision.controls, decision.alarms, now

    def errors(self) -> dict[str, dict]:
        """Errors the links counted in the recorded inputs, by link and kind."""
        return {link.name: dict(link.health().errors) for link in self.links if link.health().errors}
