"""The HIL bench: the node as its own process (``icebridge run``, render off) wired to the
software console over loopback and pty endpoints, with the configs of both written to the
run folder.

Virtual CAN across processes is slcan over a pty pair (socat), as with a USB-CAN adapter:
the bench creates the pair, the node opens one end, the console the other. Serial NMEA 0183
is a pty pair too, and Modbus TCP is the console's register server on 127.0.0.1. The
console's ends are named by role: ``primary`` and ``backup`` (the node's rudder and engine
sources in that order) and ``panel``, an NMEA 0183 instrument and alarm panel (ALR) that
gives no orders.
"""
from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import time
from contextlib import ExitStack
from pathlib import Path

import tomli_w

from bridge_node.hil.player import BusOff, Console, ScenarioResult, play
from bridge_node.hil.scenario import Scenario
from bridge_node.hil.settings import ConsoleConfig, load_console_config
from bridge_node.common.children import child_env, ending_with_parent, private_folder, spawn
from bridge_node.node.config import DEFAULT_CONFIG, load_config, read_toml, resolve_path
from bridge_node.common.errors import UserError
from bridge_node.common.network import free_port

KINDS = {"can": "can", "nmea": "nmea0183", "nmea0183": "nmea0183", "modbus": "modbus"}
ORDER_ROLES = ("primary", "backup")
CONSOLE_SOURCE = 0x42  # the console's NMEA 2000 source address
LINK_TIMEOUT_S = 1.0  # a console end silent this long is stale at the node
NMEA_RATES = {"RSA": 10.0, "ROT": 10.0, "HDT": 10.0, "RPM": 5.0}  # Hz: the panel's readings, within 38400 baud
MODBUS_REGISTERS = [{"order": "rudder", "address": 0, "type": "int16", "scale": 0.1},
                    {"order": "telegraph", "address": 1, "type": "uint16", "scale": 1.0}]
MODBUS_WRITES = [{"value": "rudder_angle", "address": 10, "type": "int16", "scale": 0.1},
                 {"value": "shaft_rpm", "address": 11, "type": "int16", "scale": 1.0},
                 {"value": "heading", "address": 12, "type": "int16", "scale": 0.1}]
STOP_TIMEOUT_S = 30.0


class PtyPair:
    """Two linked pseudo-terminals (socat) at ``node_end`` and ``console_end``, as a cable or
    a USB-CAN adapter's wire; ``cut`` removes them (the adapter unplugged), ``restore`` makes
    them again at the same paths. A context manager."""

    def __init__(self, folder: Path, name: str) -> None:
        self.node_end, self.console_end = folder / f"{name}-node", folder / f"{name}-console"
        self._proc: subprocess.Popen | None = None

    def restore(self) -> None:
        if shutil.which("socat") is None:
            raise UserError("socat is missing: install it (apt-get install socat, or run scripts/setup.sh)")
        self._proc = spawn(ending_with_parent(["socat", f"pty,raw,echo=0,link={self.node_end}",
                                               f"pty,raw,echo=0,ignoreeof,link={self.console_end}"]),
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 5.0
        while not (self.node_end.exists() and self.console_end.exists()):
            if time.monotonic() > deadline:
                self.cut()
                raise UserError(f"socat did not create the pty pair {self.node_end}")
            time.sleep(0.01)

    def cut(self) -> None:
        if self._proc is not None:
            self._proc.terminate()
            self._proc.wait(5.0)
            self._proc = None
        for path in (self.node_end, self.console_end):
            path.unlink(missing_ok=True)

    def __enter__(self) -> PtyPair:
        self.restore()
        return self

    def __exit__(self, *exc) -> None:
        self.cut()


def _node_link(name: str, kind: str, endpoint: str | int) -> dict:
    """The node's side of one console end (a ``[[links]]`` table named ``name``)."""
    common = {"name": name, "type": kind, "timeout_s": LINK_TIMEOUT_S}
    if kind == "can":
        return common | {"interface": "slcan", "channel": endpoint, "bitrate": 250000,
                         "allowed_sources": [CONSOLE_SOURCE]}
    if kind == "nmea0183":
        return common | {"port": endpoint, "baudrate": 38400, "rates": NMEA_RATES}
    return common | {"host": "127.0.0.1", "port": endpoint, "poll_hz": 20.0, "registers": MODBUS_REGISTERS,
                     "writes": MODBUS_WRITES}


def _console_link(role: str, kind: str, endpoint: str | int) -> dict:
    """The console's side of one link (a console config ``[[links]]`` table)."""
    if kind == "can":
        return {"role": role, "type": "can", "interface": "slcan", "channel": endpoint,
                "source_address": CONSOLE_SOURCE}
    if kind == "nmea0183":
        return {"role": role, "type": "nmea0183", "port": endpoint, "baudrate": 38400}
    return {"role": role, "type": "modbus", "port": endpoint, "registers": MODBUS_REGISTERS, "writes": MODBUS_WRITES}


def wire_end(role: str, kind: str, node_name: str, ptys: Path, stack: ExitStack) -> tuple[dict, dict, PtyPair | None]:
    """One console end wired to the node: a pty pair (socat) in ``ptys`` for CAN and NMEA
    0183, a free port on 127.0.0.1 for Modbus; the node's ``[[links]]`` table (named
    ``node_name``), the console's, and the pair (kept open by ``stack``)."""
    if kind == "modbus":
        port = free_port()
        return _node_link(node_name, kind, port), _console_link(role, kind, port), None
    pair = stack.enter_context(PtyPair(ptys, role))
    return (_node_link(node_name, kind, str(pair.node_end)), _console_link(role, kind, str(pair.console_end)),
            pair)


def pty_folder(stack: ExitStack) -> Path:
    """A temporary folder for pty pairs, removed by ``stack`` (or, should this process be
    killed first, by the next one made): socat's address syntax has no quoting, so the ptys
    live in a folder of plain characters."""
    folder = private_folder("hil")
    stack.callback(shutil.rmtree, folder, ignore_errors=True)
    return folder


def parse_kinds(text: str) -> list[str]:
    """``--links`` (link kinds of the primary and backup ends, comma separated) as link types."""
    names = [k.strip() for k in text.split(",")]
    bad = [k for k in names if k not in KINDS]
    if bad or not 1 <= len(names) <= 2:
        raise UserError(f"--links {text!r}: one or two of {', '.join(KINDS)}, comma separated (primary,backup)")
    return [KINDS[k] for k in names]


class Bench:
    """The node process and the software console, wired together in ``folder``; a context
    manager. ``kinds``: the link types of the primary (and backup) ends. ``node_config``: the
    user's node config the generated one starts from (its links and arbitration sources are
    replaced; default: the built-in config)."""

    def __init__(self, folder: Path, kinds: list[str], node_config: str | None = None,
                 startup_timeout_s: float = 180.0) -> None:
        self.folder, self.kinds = folder, kinds
        self.base = Path(node_config) if node_config else DEFAULT_CONFIG
        self.startup_timeout_s = startup_timeout_s
        self.pairs: dict[str, PtyPair] = {}
        self.console: Console | None = None
        self.node: subprocess.Popen | None = None
        self.node_summary: dict | None = None
        self._stack = ExitStack()

    def _write_configs(self) -> ConsoleConfig:
        """The node config and the console config of the bench, in the run folder."""
        load_config(self.base)  # the user's config is checked with the node's own errors first
        _, base = read_toml(self.base, "config file")
        node_links, console_links = [], []
        ptys = pty_folder(self._stack)
        for role, kind in [*zip(ORDER_ROLES, self.kinds), ("panel", "nmea0183")]:
            node_link, console_link, pair = wire_end(role, kind, role, ptys, self._stack)
            node_links.append(node_link)
            console_links.append(console_link)
            if pair is not None:
                self.pairs[role] = pair
        sources = list(ORDER_ROLES[:len(self.kinds)])
        paths = base.get("paths", {})
        cache = resolve_path(self.base, paths.get("cache_dir", "~/.cache/icebridge"))
        base.pop("console", None)  # the bench's console gives the orders, not the config's own
        base |= {"links": node_links,
                 "arbitration": base.get("arbitration", {}) | {"rudder": sources, "engine": sources},
                 # absolute: the node reads a relative path from its config's folder, which is this one
                 "paths": paths | {"cache_dir": str(cache), "session_dir": str((self.folder / "sessions").resolve())},
                 "stream": base.get("stream", {}) | {"publish": f"tcp://127.0.0.1:{free_port()}",
                                                     "snapshot": f"tcp://127.0.0.1:{free_port()}"},
                 "control": base.get("control", {}) | {"endpoint": f"tcp://127.0.0.1:{free_port()}"},
                 "instructor": base.get("instructor", {}) | {"start": False}}  # the bench has no instructor
        ships = self.base.resolve().parent / "ships"
        if ships.is_dir() and not (self.folder / "ships").exists():
            (self.folder / "ships").symlink_to(ships)  # ships beside the user's config stay found
        (self.folder / "node.toml").write_text(tomli_w.dumps(base), encoding="utf-8")
        console = {"links": console_links}
        (self.folder / "console.toml").write_text(tomli_w.dumps(console), encoding="utf-8")
        load_config(self.folder / "node.toml")
        return load_console_config(self.folder / "console.toml")

    def __enter__(self) -> Bench:
        self.folder.mkdir(parents=True, exist_ok=True)
        try:
            self.console = self._stack.enter_context(Console(self._write_configs()))
            with open(self.folder / "node.json", "w") as out, open(self.folder / "node.log", "w") as log:
                self.node = spawn(
                    [sys.executable, "-m", "bridge_node", "run", "--config", str(self.folder / "node.toml"),
                     "--render", "none", "--json", "--out", str(self.folder / "node")], stdout=out, stderr=log,
                    env=child_env())
            self.console.wait_ready(self.startup_timeout_s, self.node_gone)
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        try:
            self._stop_node()
        finally:
            self._stack.close()

    def node_gone(self) -> str | None:
        """Why the node process is not running (with the end of its log), or None."""
        if self.node is None or self.node.poll() is None:
            return None
        tail = (self.folder / "node.log").read_text(errors="replace").strip().splitlines()[-3:]
        return f"the node exited with status {self.node.returncode}: {' | '.join(tail) or 'no output'}"

    def _stop_node(self) -> None:
        """SIGTERM, as Ctrl-C: the node closes its links, flushes its record and prints its summary."""
        if self.node is None:
            return
        if self.node.poll() is None:
            self.node.send_signal(signal.SIGTERM)
            try:
                self.node.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.node.kill()
                self.node.wait()
        self.node = None
        lines = (self.folder / "node.json").read_text(errors="replace").strip().splitlines()
        try:
            self.node_summary = json.loads(lines[-1]) if lines else None
        except json.JSONDecodeError:
            self.node_summary = None

    def bus_off(self, role: str, begin: bool) -> None:
        """The CAN adapter of ``role`` gone (``begin``) or back: its pty pair removed or made again."""
        pair = self.pairs[role]
        pair.cut() if begin else pair.restore()

    def play(self, scenario: Scenario, path: str) -> ScenarioResult:
        """Play one scenario through the bench's console (CAN ends can have a bus-off)."""
        bus_off: BusOff | None = self.bus_off if "can" in self.kinds else None
        return play(self.console, scenario, path, bus_off)

