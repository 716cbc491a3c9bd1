"""A link kind defined here, from the public interface alone (``links.kind``, ``links.base``,
``links.settings``), with no edit anywhere else: the node's config takes its table, the
config reference lists its keys, the real-time loop steers the ship by its orders, the
session record writes its traffic and the tick log counts its inputs, and a replay of the
record feeds them back to the same link code and gives the same track (issue 29, item 3)."""
from __future__ import annotations

import collections
import math
import threading
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.links.base import Link
from bridge_node.links.hub import LinkHub
from bridge_node.links.kind import LINK_KINDS, LinkKind, RecordFormat, ReplayFeed, TextLineWriter, register_kind
from bridge_node.links.messages import ControlInput, Traffic
from bridge_node.links.record_reader import complete_lines, record_time
from bridge_node.links.settings import LinkSettingsBase
from bridge_node.node.config import NodeConfig
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.exercise.tick_record import TICKS_FILE
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.reference.config_reference import config_reference
from bridge_node.replay.engine import Playback, run_replay
from bridge_node.replay.inputs import load_inputs
from bridge_node.replay.session import RecordedSession, SessionSource
from sim_core.ship.orders import OrderKind

RATE = 30.0
WIRES: dict[str, collections.deque] = {}  # the toy's "wire": lines in flight, by channel


class ToySettings(LinkSettingsBase):
    """A toy wheel on an in-process wire."""

    type: Literal["toy"]
    channel: str = "toy"


class ToyLink(Link):
    """Reads ``RUDDER <deg>`` lines as rudder orders; sends ``HDG <deg>`` each tick."""

    def _open_device(self) -> collections.deque:
        return WIRES.setdefault(self.settings.channel, collections.deque())

    def _close_device(self, device) -> None:
        pass

    def _poll_device(self, now: float) -> Iterator[ControlInput]:
        while self.device:
            line = self.device.popleft()
            self._report("rx", line)
            word, _, value = line.partition(" ")
            if word != "RUDDER":
                self._count_error("malformed")
                continue
            yield ControlInput(now, self.name, OrderKind.RUDDER, math.radians(float(value)))

    def publish(self, state, now: float) -> None:
        self._report("tx", f"HDG {math.degrees(state.heading):.1f}")


@dataclass(frozen=True)
class ToyRecord:
    unix_time: float
    link: str
    direction: str
    text: str


def read_toy_log(path: Path) -> tuple[list[ToyRecord], Counter]:
    lines, counts = complete_lines(path)
    records = []
    for line in lines:
        parts = line.split(" ", 3)
        try:
            records.append(ToyRecord(record_time(parts[0]), parts[1], parts[2], parts[3]))
        except (ValueError, IndexError):
            counts["malformed"] += 1
    return records, counts


class ToyReplay(ReplayFeed):
    def __init__(self, settings: ToySettings, siblings: Sequence[ToySettings]) -> None:
        self.link = ToyLink(settings.model_copy(update={"channel": f"replay-{settings.name}"}))

    def owns(self, record: ToyRecord) -> bool:
        return record.link == self.link.name

    def feed(self, record: ToyRecord, tick_monotonic: float, tick_unix: float) -> None:
        WIRES.setdefault(self.link.settings.channel, collections.deque()).append(record.text)


def _line(t: Traffic) -> str:
    return f"{t.unix_time:.6f} {t.link} {t.direction} {t.data}"


@pytest.fixture
def toy_kind():
    kind = register_kind(LinkKind("toy", ToySettings, ToyLink,
                                  RecordFormat("toy.log", lambda path: TextLineWriter(path, _line), read_toy_log,
                                               lambda r: r.direction, lambda r: r.unix_time, input_direction="rx"),
                                  ToyReplay))
    try:
        yield kind
    finally:
        LINK_KINDS.pop("toy")
        WIRES.clear()


def _wheel(stop: threading.Event, clock) -> None:
    """The helmsman: starboard 20 from 0.3 s, one bad line, 10 from 1.2 s; repeated."""
    wire = WIRES.setdefault("toy-test", collections.deque())
    wire.append("NONSENSE")
    while not stop.is_set():
        if clock() >= 0.3:
            wire.append("RUDDER 20" if clock() < 1.2 else "RUDDER 10")
        stop.wait(0.1)


def test_a_link_kind_defined_in_a_test_runs_records_and_replays(toy_kind, tmp_path):
    base = exercise_config(tmp_path / "tiles", 300.0, 300.0, 50.0, start_north=-60.0)
    cfg = NodeConfig.model_validate(base.model_dump() | {
        "links": [{"type": "toy", "name": "wheel", "channel": "toy-test"}],
        "arbitration": {"rudder": ["wheel"], "fail_safe": "hold"}})
    assert type(cfg.links[0]) is ToySettings
    assert "## `[links[] (type = 'toy')]`" in config_reference(NodeConfig, "Config")
    with pytest.raises(ValueError, match="channel"):
        NodeConfig.model_validate(base.model_dump() | {"links": [{"type": "toy", "name": "w", "channel": 5}]})

    model = build_world(cfg, None)
    live = start_world(model, cfg)
    record = tmp_path / "session"
    stop = threading.Event()
    wheel = threading.Thread(target=_wheel, args=(stop, lambda: live.time), daemon=True)
    with LinkHub(cfg.links, cfg.arbitration, record) as hub:
        wheel.start()
        try:
            run_realtime(model, live, hub, RATE, None, should_stop=lambda: live.time >= 2.0 - 1e-9)
        finally:
            stop.set()
            wheel.join(2.0)
        counts = dict(hub.order_counts)
        errors = dict(hub.links[0].health().errors)
    assert counts["wheel/rudder/0"] > 5 and errors == {"malformed": 1}
    assert math.degrees(live.ship.rudder) > 2.0  # turned to starboard under the wheel's orders

    lines = read_toy_log(record / "toy.log")[0]
    received = [r for r in lines if r.direction == "rx"]
    assert len(received) == counts["wheel/rudder/0"] + 1 and any(r.text.startswith("HDG") for r in lines)
    header = (record / TICKS_FILE).read_text().splitlines()[0]
    assert header.startswith("# icebridge ticks 2 ") and "toy" in header.split("inputs=")[1].split(",")

    session = load_inputs([str(record)], None, {}, 1.0 / RATE)
    assert isinstance(session, RecordedSession) and session.exact and session.reads["toy"] == len(received)
    again = start_world(model, cfg)
    with SessionSource(cfg.links, cfg.arbitration, session) as source:
        stats = run_replay(model, again, source, Playback(None), None, None)
        replayed = dict(source.orders)
        replay_errors = source.errors()
    assert stats.steps == len(session.ticks) and again.time == live.time
    assert replayed == counts and replay_errors == {"wheel": {"malformed": 1}}
    np.testing.assert_allclose(again.ship.eta, live.ship.eta, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(again.ship.nu, live.ship.nu, rtol=0.0, atol=1e-9)
