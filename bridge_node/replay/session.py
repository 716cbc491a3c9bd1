"""Re-simulation of a recorded run from its session record: the console orders it received
drive the ship model again, tick for tick.

The record's raw inputs (received NMEA 0183 sentences, received CAN frames, Modbus register
reads, those of any other link kind) are given back to the node's own link code, in the
order and at the ticks they were read (``ticks.log``, written by the real-time loop), with
each tick's recorded clock, by each kind's ``ReplayFeed``: an NMEA link reads them from a
``loop://`` serial port, a CAN link from python-can's virtual bus, and the Modbus reads go
through the link's register decoding. The links' orders are
arbitrated as the node did. The same orders at the same steps give the same track, the
same broken cells and the same outputs. A record without a tick log (an older one) is
re-simulated approximately: each input is given to the tick its unix time falls in.
"""
from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from bridge_node.exercise.command_log import COMMANDS_FILE, read_commands
from bridge_node.control.commands import NODE_COMMANDS
from bridge_node.links.faults import LinkFault
from bridge_node.links.hub import LinkHub
from bridge_node.links.kind import LINK_KINDS, ReplayFeed
from bridge_node.links.messages import Alarm
from bridge_node.links.record_reader import check_tick_count
from bridge_node.links.settings import ArbitrationSettings, LinkSettingsBase
from bridge_node.exercise.tick_record import TICKS_FILE, Tick, input_kinds, read_ticks
from sim_core.instructor import Command
from sim_core.world import Controls

NODE_CONFIG = "node.toml"  # the node config a run used, kept in its session record
FLEET_FOLDER = "ships"  # the other own ships' link traffic in a session record, one folder each (ships/1, ...)


def record_files() -> dict[str, str]:
    """Link kind -> its file in the session record, for every kind whose inputs are replayed."""
    return {name: LINK_KINDS[name].record.file for name in input_kinds()}


@dataclass
class RecordedSession:
    """A session record read back: the step period (s), the ticks (recorded, or made up
    from unix times when ``exact`` is False), each tick's inputs per link kind (the records
    its ``RecordFormat.read`` gives), and what was wrong with it."""

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
        """Inputs per link kind over the whole record."""
        return Counter({p: sum(len(t.get(p, ())) for t in self.inputs) for p in record_files()})


def _received(folder: Path, names: set[str], bad: Counter) -> tuple[dict[str, list], dict[str, list[float]]]:
    """The recorded inputs of each link kind in file order (files not chosen: none), and the
    unix times of every line, inputs and outputs, per kind."""
    files = record_files()
    inputs, times = {p: [] for p in files}, {p: [] for p in files}
    for name, file in files.items():
        record = LINK_KINDS[name].record
        if file in names and (folder / file).is_file():
            records, counts = record.read(folder / file)
            inputs[name] = [r for r in records if record.is_input(r)]
            times[name] = [record.unix_time(r) for r in records]
            bad.update({f"{file} {k}": n for k, n in counts.items() if n})
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
        inputs = _by_tick(ticks, received, bad)
        commands = {}
        if (folder / COMMANDS_FILE).is_file():
            commands, counts = read_commands(folder / COMMANDS_FILE)
            bad.update({f"{COMMANDS_FILE} {k}": n for k, n in counts.items() if n})
        return RecordedSession(folder, sorted(names), period, ticks, inputs, True, bad, commands)
    times = [t for p in line_times for t in line_times[p]]
    if not times:
        return RecordedSession(folder, sorted(names), period, [], [], False, bad)
    t0 = min(times)  # about the first tick: its outputs are the record's first lines
    n = check_tick_count(folder, times, period)
    ticks = [Tick(k, t0 + k * period, t0 + k * period, ()) for k in range(n)]
    inputs = [{p: [] for p in received} for _ in range(n)]
    for p, items in received.items():
        for item in items:
            inputs[min(n - 1, round((LINK_KINDS[p].record.unix_time(item) - t0) / period))][p].append(item)
    return RecordedSession(folder, sorted(names), period, ticks, inputs, False, bad)


def _by_tick(ticks: list[Tick], received: dict[str, list], bad: Counter) -> list[dict[str, list]]:
    """Each tick's inputs per link kind, taken in file order by the tick log's counts; what
    is missing or left over is counted in ``bad``. A kind the tick log does not count (a
    kind added since, or a file of a kind the node did not have) gives no inputs."""
    taken = {p: 0 for p in received}
    inputs = []
    for tick in ticks:
        row = {p: [] for p in received}
        for p, n in tick.reads.items():
            if p not in received:
                continue
            row[p] = received[p][taken[p]:taken[p] + n]
            if len(row[p]) < n:
                bad[f"{LINK_KINDS[p].record.file} lines missing"] += n - len(row[p])
            taken[p] += n
        inputs.append(row)
    for p in received:
        if len(received[p]) > taken[p]:  # recorded after the last tick line was written
            bad[f"{LINK_KINDS[p].record.file} after the last tick"] += len(received[p]) - taken[p]
    return inputs


class SessionSource:
    """A replay source: the recorded run's console links, fed its inputs tick by tick, polled
    and arbitrated by a ``LinkHub`` as the live run's were (link-down alarms included), give
    the orders of each step. Use as a context manager."""

    absolute = True  # logged times are the ticks' unix times

    def __init__(self, links: Sequence[LinkSettingsBase], arbitration: ArbitrationSettings,
                 session: RecordedSession) -> None:
        self.session = session
        self.dt, self.steps = session.period, len(session.ticks)
        self.feeds: dict[str, list[ReplayFeed]] = {}  # link kind -> a feed per link of the kind, config order
        for s in links:
            kind = LINK_KINDS[s.type]
            if kind.replay is not None:
                siblings = [other for other in links if other.type == s.type]
                self.feeds.setdefault(s.type, []).append(kind.replay(s, siblings))
        self.hub = LinkHub(links, arbitration, made=[f.link for feeds in self.feeds.values() for f in feeds])
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
        for feed in self._all_feeds():
            feed.close()

    def _all_feeds(self) -> list[ReplayFeed]:
        return [f for feeds in self.feeds.values() for f in feeds]

    def _feed(self, tick: Tick, inputs: dict[str, list]) -> None:
        for link in self.links:  # one reopened after a fault: opened before it is fed, as the run's was read
            if link.device is None:
                link.await_open(None)
        for kind, records in inputs.items():
            feeds = self.feeds.get(kind, [])
            for record in records:  # to the link that read it; one no link of the config owns is dropped
                feed = next((f for f in feeds if f.owns(record)), None)
                if feed is not None:
                    feed.feed(record, tick.monotonic, tick.unix)

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
        for feed in self._all_feeds():
            feed.after_poll()
        return decision.controls, decision.alarms, now

    def errors(self) -> dict[str, dict]:
        """Errors the links counted in the recorded inputs, by link and kind."""
        return {link.name: dict(link.health().errors) for link in self.links if link.health().errors}
