"""Rewind and fork: the world brought to a save point (``bridge_node.control.save_point``)
by re-simulating its session record, after the records it was itself forked from. The
record's links are fed its inputs tick by tick and its commands are applied at their steps
through the one tick (``ExerciseTick``), with no outputs, as fast as the machine goes."""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from rich.console import Console

from bridge_node.control.save_point import FORK_FILE, SavePoint, read_save, same_state, state_of
from bridge_node.exercise.tick import ExerciseTick
from bridge_node.node.config import NodeConfig, load_config
from bridge_node.common.errors import UserError
from bridge_node.replay.engine import StepOrders
from bridge_node.node.fleet_session import session_source
from bridge_node.replay.session import NODE_CONFIG, read_session, record_files
from sim_core.world import WorldData, WorldModel

MAX_FORK_DEPTH = 32  # forks of forks followed back at most (a loop of fork files ends here)


def resimulate(model: WorldModel, data: WorldData, cfg: NodeConfig, point: SavePoint,
               progress: Callable[[int, int], None] = lambda done, total: None, depth: int = 0) -> None:
    """Step ``data``, the exercise's start, to ``point``; ``cfg`` is the config the world was
    built from (a record without its own ``node.toml`` is fed through its links).
    ``progress(step, of)`` is told as it goes. UserError where the record does not reach
    the saved state (a record changed, or another exercise's config)."""
    folder = Path(point.record)
    if depth > MAX_FORK_DEPTH:
        raise UserError(f"{folder}: forked from more than {MAX_FORK_DEPTH} records in a row (a loop of fork files?)")
    if (folder / FORK_FILE).is_file():
        resimulate(model, data, cfg, read_save(folder / FORK_FILE), progress, depth + 1)
    recorded = folder / NODE_CONFIG
    record_cfg = load_config(recorded) if recorded.is_file() else cfg
    try:
        session = read_session(folder, {n for n in record_files().values() if (folder / n).is_file()},
                               1.0 / record_cfg.realtime.rate_hz)
    except ValueError as exc:
        raise UserError(f"{folder}: {exc}") from None
    outcome = None
    with session_source(record_cfg, session) as source:
        orders = StepOrders(source)
        tick = ExerciseTick(model, data, orders, (), orders)
        while data.seq < point.seq and orders.k < source.steps:
            outcome = tick(source.dt, orders.clock(), send=False)
            if data.seq % 600 == 0:
                progress(data.seq, point.seq)
    progress(data.seq, point.seq)
    if data.seq != point.seq or outcome is None or not same_state(state_of(outcome.events), point.state):
        raise UserError(f"{folder}: re-simulated to step {data.seq}, the record does not reach the state saved "
                        f"at step {point.seq} (fork with the config the record was made with, and a record "
                        "that is whole)")


def resimulate_shown(model: WorldModel, data: WorldData, cfg: NodeConfig, point: SavePoint, console: Console) -> None:
    """``resimulate`` with its progress on the console's status line."""
    with console.status("re-simulating the record to the save point") as shown:
        resimulate(model, data, cfg, point,
                   lambda done, total: shown.update(f"re-simulating the record: step {done} of {total}"))
