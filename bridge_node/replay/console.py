"""The replay's terminal: single keys (space pause, + faster, - slower, f or the right
arrow seek 1 min, F seek 10 min, q quit) and a progress bar of logged time with the wall
time and the speed reached."""
from __future__ import annotations

import datetime as dt
import os
import select
import sys
import termios
import time
import tty

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn

from bridge_node.replay.engine import Playback, ReplayStats, Source

ARROWS = {"\x1b[C": "right"}
KEYS_HELP = "keys: space pause | + faster | - slower | f seek 1 min | F seek 10 min | q quit"


def logged_text(t: float, absolute: bool) -> str:
    """A logged time as UTC clock time (absolute) or seconds from the start."""
    if absolute:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S")
    return f"{t:.1f} s"


class KeyReader:
    """Single key presses from the terminal while open (cbreak mode, restored on close);
    none when standard input is not a terminal."""

    def __init__(self) -> None:
        self._fd = sys.stdin.fileno() if sys.stdin is not None and sys.stdin.isatty() else None
        self._saved = None

    @property
    def interactive(self) -> bool:
        """Whether keys can be read (standard input is a terminal)."""
        return self._fd is not None

    def __enter__(self) -> KeyReader:
        if self._fd is not None:
            self._saved = termios.tcgetattr(self._fd)
            tty.setcbreak(self._fd)
        return self

    def __exit__(self, *exc) -> None:
        if self._saved is not None:
            termios.tcsetattr(self._fd, termios.TCSADRAIN, self._saved)

    def keys(self) -> list[str]:
        """Keys pressed since the last call (an arrow as its name)."""
        if self._fd is None or not select.select([self._fd], [], [], 0.0)[0]:
            return []
        text = os.read(self._fd, 64).decode("utf-8", errors="replace")
        for sequence, name in ARROWS.items():
            text = text.replace(sequence, "\0" + name + "\0")
        out = []
        for part in text.split("\0"):
            out += [part] if part in ARROWS.values() else [c for c in part if c != "\x1b"]
        return out


class ReplayProgress:
    """A rich progress bar over the source's logged time: logged time, wall time, the
    speed reached (logged s per wall s) and the playback state; reads the keys."""

    def __init__(self, console: Console, source: Source, keys: KeyReader) -> None:
        self.source, self.keys = source, keys
        self.start = time.monotonic()
        self.progress = Progress(TextColumn("{task.description}"), BarColumn(),
                                 TextColumn("{task.fields[logged]}"), TextColumn("wall {task.fields[wall]}"),
                                 TextColumn("x{task.fields[rate]}"), console=console, transient=True)
        self.task = self.progress.add_task("replay", total=source.steps, logged="", wall="", rate="")

    def __enter__(self) -> ReplayProgress:
        self.progress.start()
        if self.keys.interactive:
            self.progress.console.print(KEYS_HELP)
        return self

    def __exit__(self, *exc) -> None:
        self.progress.stop()

    def __call__(self, k: int, stats: ReplayStats, playback: Playback) -> list[str]:
        """Show step k; returns the keys pressed since the last call."""
        s = self.source
        wall = time.monotonic() - self.start
        state = ("paused" if playback.paused else f"seeking to step {playback.seek_to}" if k < playback.seek_to
                 else "as fast as possible" if playback.speed is None else f"x{playback.speed:g}")
        end = s.logged_time(s.steps - 1) + s.dt
        self.progress.update(self.task, completed=k, description=state,
                             logged=f"{logged_text(s.logged_time(min(k, s.steps - 1)), s.absolute)} / "
                                    f"{logged_text(end, s.absolute)}",
                             wall=f"{wall:.0f} s", rate=f"{k * s.dt / max(wall, 1e-9):.1f}")
        return self.keys.keys()
