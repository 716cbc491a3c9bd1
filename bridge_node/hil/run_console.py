"""The software console that gives ``icebridge run`` its orders (``[console]`` of the node
config; the default config's demo): ``icebridge console`` in its own process, wired to the
node over a real link as a bench's console is (slcan or NMEA 0183 on a socat pty pair,
Modbus TCP on 127.0.0.1), plays the script, writes its results, then holds its last orders
until the run ends. The node only sees one more console link, ``console``, first in the
arbitration: its loop polls it as any other and never waits for it.
"""
from __future__ import annotations

import json
import signal
import subprocess
import sys
from contextlib import ExitStack
from pathlib import Path

import tomli_w

from bridge_node.hil.bench import STOP_TIMEOUT_S, pty_folder, wire_end
from bridge_node.common.children import child_env, spawn
from bridge_node.hil.scenario import load_scenario
from bridge_node.node.config import DEFAULT_CONFIG, NodeConfig, resolve_path
from bridge_node.common.errors import UserError

LINK_NAME = "console"  # the node's end
INTERRUPTED = 130  # the console's exit status after Ctrl-C (which a terminal sends the run and it alike)
WAIT_S = 3600.0  # the console waits this long for the node's first outputs (a first run builds its tiles)


class RunConsole:
    """The run's console process and its link, in ``folder`` (config, log, results); a
    context manager. ``cfg``: the node config with the console's link (unchanged where the
    config has no ``[console]``). With a session ``record`` folder, the node config the run
    uses goes there as ``node.toml`` (the console's link, where it has one, as the node saw
    it, pty path and all): ``icebridge replay RECORD`` re-simulates the run exactly."""

    def __init__(self, cfg: NodeConfig, config_path: str | Path | None, folder: Path,
                 record: Path | None = None) -> None:
        self.settings = cfg.console
        self.cfg = cfg
        self.config_path = config_path
        self.where = f"{config_path or DEFAULT_CONFIG}: console"
        self.folder, self.record = folder, record
        self.log, self.results = folder / "console.log", folder / "console.json"
        self._process: subprocess.Popen | None = None
        self._stopped = False  # the run stopped the console (else it exited on its own)
        self._stack = ExitStack()
        names = {link.name for links in [cfg.links, *(ship.links for ship in cfg.ships)] for link in links}
        if self.settings is not None and LINK_NAME in names:
            raise UserError(f"{self.where}: the console's link is named {LINK_NAME!r}, as a link of "
                            "links (or of a ship's links) already is; rename that link")

    def __enter__(self) -> RunConsole:
        if self.settings is None:
            if self.record is not None:  # a run of its own links alone is replayed exactly too
                self._keep_node_config()
            return self
        load_scenario(self.settings.script)  # a mistake in the script stops the run before it starts
        try:
            self._start()
        except BaseException:
            self.__exit__()
            raise
        return self

    def _start(self) -> None:
        s = self.settings
        try:
            node_link, console_link, _ = wire_end("primary", s.link, LINK_NAME, pty_folder(self._stack), self._stack)
        except UserError as exc:
            raise UserError(f"{self.where}.link = {s.link!r}: {exc}; or set link = \"modbus\" (TCP on 127.0.0.1, "
                            "no socat needed)") from None
        arbitration = self.cfg.arbitration
        self.cfg = NodeConfig.model_validate(self.cfg.model_dump() | {
            "links": [*self.cfg.model_dump()["links"], node_link],
            "arbitration": arbitration.model_dump() | {"rudder": [LINK_NAME, *arbitration.rudder],
                                                       "engine": [LINK_NAME, *arbitration.engine]}})
        if self.record is not None:
            self._keep_node_config()
        self.folder.mkdir(parents=True, exist_ok=True)
        config = self.folder / "console.toml"
        config.write_text(tomli_w.dumps({"links": [console_link]}), encoding="utf-8")
        self.results.unlink(missing_ok=True)
        with open(self.log, "w") as log:
            self._process = spawn(
                [sys.executable, "-m", "bridge_node", "console", "--config", str(config), "--script", s.script,
                 "--wait", str(WAIT_S), "--hold", "--results", str(self.results)],
                stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, env=child_env())

    def _keep_node_config(self) -> None:
        """``node.toml`` in the record: the run's node config, its paths absolute, without
        ``[console]`` (the console was another process; its link is among the links)."""
        paths = {k: str(resolve_path(self.config_path, v)) for k, v in self.cfg.paths.model_dump().items()}
        node = self.cfg.model_dump(exclude_none=True, exclude={"console"}) | {"paths": paths}
        self.record.mkdir(parents=True, exist_ok=True)
        (self.record / "node.toml").write_text(tomli_w.dumps(node), encoding="utf-8")

    def __exit__(self, *exc) -> None:
        try:
            self._stop()
        finally:
            self._stack.close()

    def _stop(self) -> None:
        """SIGTERM, as Ctrl-C: the console closes its end and exits."""
        process = self._process
        if process is None or process.poll() is not None:
            return
        self._stopped = True
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()

    def summary(self) -> dict | None:
        """The console's account for the run summary: its script, the expectations met (or
        why there are none), its log; None without a console."""
        if self.settings is None:
            return None
        out = {"script": self.settings.script, "link": self.settings.link, "log": str(self.log)}
        try:
            results = json.loads(self.results.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            code = self._process.returncode if self._process else None
            if self._stopped or code == INTERRUPTED:
                return out | {"result": "the run ended before the script did"}
            tail = self.log.read_text(errors="replace").strip().splitlines()[-1:] if self.log.exists() else []
            return out | {"result": f"the console exited with status {code}: {' '.join(tail) or 'no output'}"}
        met = sum(r["met"] for r in results)
        total = sum(r["total"] for r in results)
        return out | {"result": f"{met} of {total} expectations met", "passed": met == total}
