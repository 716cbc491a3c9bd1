"""Child processes end with the node that started them, and leave nothing behind in /tmp.

Linux sends a process its parent-death signal (``prctl(PR_SET_PDEATHSIG)``) when the
thread that started it ends, however it ends: SIGKILL or a crash included. So every such
child is started by one thread that lives as long as the process (``spawn``): one started
by a short-lived thread (a test's replug, a watchdog) would be signalled when that thread
ended. A child that
runs ``icebridge`` (the software console, a render process, a HIL bench's node) asks for it
itself at its start (``end_with_parent``), told its parent by ``ICEBRIDGE_PARENT_PID``
(``child_env``); a program of another kind (socat) is started through util-linux's
``setpriv --pdeathsig`` (``ending_with_parent``). The node's own folders in /tmp carry its
pid (``private_folder``); one whose process is gone is removed when the next is made.
"""
from __future__ import annotations

import ctypes
import os
import shutil
import signal
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

PARENT_VARIABLE = "ICEBRIDGE_PARENT_PID"
_PR_SET_PDEATHSIG = 1  # linux/prctl.h
_SPAWNER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="icebridge-spawner")  # lives with the process


def spawn(command: list[str], **popen: object) -> subprocess.Popen:
    """``subprocess.Popen(command, **popen)``, started on the process's one spawning thread."""
    return _SPAWNER.submit(subprocess.Popen, command, **popen).result()


def child_env(env: dict[str, str] | None = None) -> dict[str, str]:
    """The environment for an ``icebridge`` child of this process (``env``, or this one's)."""
    return {**(os.environ if env is None else env), PARENT_VARIABLE: str(os.getpid())}


def end_with_parent() -> None:
    """Where this process was started as a child of a node (``child_env``): receive SIGTERM
    when that node ends, and end now if it already has."""
    parent = os.environ.get(PARENT_VARIABLE, "")
    if not parent.isdigit():
        return
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    except (OSError, AttributeError):  # not Linux: the parent's own shutdown is all there is
        return
    if os.getppid() != int(parent):
        raise SystemExit("icebridge: the node that started this process has ended")


def ending_with_parent(command: list[str]) -> list[str]:
    """``command`` (not an ``icebridge`` one) to be started so that it ends with this process."""
    return ["setpriv", "--pdeathsig", "TERM", *command] if shutil.which("setpriv") else command


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def private_folder(kind: str) -> Path:
    """A new folder ``icebridge-<kind>-<pid>-*`` in the temporary folder (mode 0700), after
    removing those of the same kind whose process is gone (a node killed before it could)."""
    root = Path(tempfile.gettempdir())
    for old in root.glob(f"icebridge-{kind}-*-*"):
        pid = old.name.split("-")[2]
        if pid.isdigit() and not _alive(int(pid)) and old.stat().st_uid == os.getuid():
            shutil.rmtree(old, ignore_errors=True)
    return Path(tempfile.mkdtemp(prefix=f"icebridge-{kind}-{os.getpid()}-"))
