"""The instructor station started by ``icebridge run`` (``[instructor] start = true``): its
own process (``icebridge instructor``), a subscriber of the state stream and a client of
the control endpoint like any other, which ends with the node."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from bridge_node.common.children import child_env, spawn
from bridge_node.node.config import NodeConfig

STOP_TIMEOUT_S = 10.0


class StationProcess:
    """``icebridge instructor`` for the node's config, logging to ``out/instructor.log``; a
    context manager. ``address`` is the page's."""

    def __init__(self, cfg: NodeConfig, config_path: str | None, out: Path) -> None:
        s = cfg.instructor
        host = f"[{s.host}]" if ":" in s.host else s.host
        self.address = f"http://{host}:{s.port}/"
        self.log = out / "instructor.log"
        self.command = [sys.executable, "-m", "bridge_node", "instructor",
                        *(["--config", str(config_path)] if config_path else [])]
        self._process: subprocess.Popen | None = None

    def __enter__(self) -> StationProcess:
        self.log.parent.mkdir(parents=True, exist_ok=True)
        with open(self.log, "w", encoding="utf-8") as log:
            self._process = spawn(self.command, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                  env=child_env())
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    def stop(self) -> dict:
        """End the station (SIGTERM, then SIGKILL after ``STOP_TIMEOUT_S``); what the summary
        says of it. Safe to call twice."""
        code = None
        if self._process is not None:
            if self._process.poll() is None:
                self._process.terminate()
                try:
                    self._process.wait(STOP_TIMEOUT_S)
                except subprocess.TimeoutExpired:
                    self._process.kill()
                    self._process.wait()
            code = self._process.returncode
        return {"address": self.address, "log": str(self.log), "exit": code}
