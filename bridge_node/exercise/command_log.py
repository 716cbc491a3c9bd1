"""The session record's ``commands.log``: every instructor command the node (a link fault,
a save point) and the world applied, one JSON line each, with the step it was applied at (``WorldEvents.seq``) and the simulated
time, in the world's own terms (SI, exactly as applied), so that a replay of the record
applies the same commands at the same steps. Lines are written and flushed as they come
(commands are rare, and a crash must not lose one); a torn last line is skipped on reading.
"""
from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

from bridge_node.control.commands import CommandError, NodeCommand, command_from_record, command_record
from bridge_node.exercise.tick import StepListener, TickOutcome
from bridge_node.links.record_reader import complete_lines
from bridge_node.links.session_record import cut_torn_tail
from sim_core.instructor import Command

COMMANDS_FILE = "commands.log"


class CommandLog(StepListener):
    """Writes ``commands.log`` in a session folder."""

    def __init__(self, folder: Path) -> None:
        path = Path(folder) / COMMANDS_FILE
        cut_torn_tail(path)
        self._file = open(path, "a", encoding="ascii")

    def on_step(self, outcome: TickOutcome) -> None:
        events = outcome.events
        applied = (*outcome.node_commands, *events.commands)
        for command in applied:
            self._file.write(json.dumps({"seq": events.seq, "time": events.time,
                                         "command": command_record(command)}) + "\n")
        if applied:
            self._file.flush()

    def stop(self) -> None:
        if not self._file.closed:
            self._file.close()


def read_commands(path: Path) -> tuple[dict[int, list[Command | NodeCommand]], Counter]:
    """The commands of a ``commands.log`` by the step they were applied at, and counts of
    torn and malformed lines."""
    lines, counts = complete_lines(path)
    by_step: dict[int, list[Command | NodeCommand]] = {}
    for line in lines:
        try:
            entry = json.loads(line)
            seq = entry["seq"]
            if not isinstance(seq, int) or isinstance(seq, bool) or seq < 1:
                raise ValueError(f"step {seq!r}")
            by_step.setdefault(seq, []).append(command_from_record(entry["command"]))
        except (ValueError, KeyError, TypeError, CommandError, RecursionError):
            counts["malformed"] += 1
    return by_step, counts
