"""Reading the files the node is given (configs, ships, scenarios, DBC and warp files, logs
and session records): each must be a regular file no larger than the limit for its kind,
and is read with that bound. A device (``/dev/zero``), a FIFO, a folder or a huge file is
one clear UserError, never a hang or a memory blow-up.

The file is opened non-blocking (a FIFO that slipped past the check cannot block the open,
and a special file that ignores its size, as ``/proc/kmsg``, cannot block the read) and
checked again on the open descriptor, so a file swapped after the first check is caught.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

from bridge_node.common.errors import UserError

MIB = 2**20
TOML_LIMIT = 4 * MIB  # configs, ships, scenarios, console configs: kilobytes
DBC_LIMIT = 4 * MIB  # a console's DBC is kilobytes; anything this large is not one
LOG_LIMIT = 512 * MIB  # replay logs and session record files
_CHUNK = MIB
_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def file_kind(mode: int) -> str:
    """What a file of this ``st_mode`` is, in words: "a FIFO", "a character device"..."""
    return next((name for test, name in _KINDS if test(mode)), "a regular file" if stat.S_ISREG(mode)
                else "a special file")


def _size_text(limit: int) -> str:
    return f"{limit / MIB:g} MiB" if limit >= MIB else f"{limit} bytes"


def _checked(where: str, subject: str, mode: int, size: int, limit: int) -> None:
    """UserError unless ``mode`` is a regular file's and ``size`` within ``limit``."""
    if not stat.S_ISREG(mode):
        raise UserError(f"{where}: {subject} is not a regular file (it is {file_kind(mode)})")
    if size > limit:
        raise UserError(f"{where}: {subject} is larger than {_size_text(limit)}, the limit for this kind of file")


def _read_bounded(fd: int, where: str, subject: str, limit: int) -> bytes:
    """At most ``limit`` bytes from the open file; UserError if it holds more."""
    info = os.fstat(fd)
    _checked(where, subject, info.st_mode, info.st_size, limit)
    chunks, total = [], 0
    while total <= limit:
        chunk = os.read(fd, min(_CHUNK, limit + 1 - total))
        if not chunk:
            break
        chunks.append(chunk)
        total += len(chunk)
    _checked(where, subject, info.st_mode, total, limit)  # a file that grew, or reports no size (/proc)
    return b"".join(chunks)


def read_input(path: str | Path, what: str, limit: int, where: str | None = None) -> bytes:
    """The bytes of an input file: a regular file (a symbolic link to one is fine) of at
    most ``limit`` bytes. UserError otherwise, starting with ``where`` (default: the path;
    give the config file and key a path came from) and naming the file as ``what``
    ("config file", "DBC file"...)."""
    path = Path(path)
    where = where or str(path)
    subject = f"the {what}" if where == str(path) else f"the {what} {path}"
    try:
        info = os.stat(path)  # before the open: a device is never opened, a FIFO never waited on
        _checked(where, subject, info.st_mode, info.st_size, limit)
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
        try:
            return _read_bounded(fd, where, subject, limit)
        finally:
            os.close(fd)
    except FileNotFoundError:
        raise UserError(f"{where}: {what} not found") from None
    except (OSError, ValueError) as exc:  # unreadable, a name too long, a NUL in the name...
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise UserError(f"{where}: cannot read {subject}: {reason}") from None


def read_input_text(path: str | Path, what: str, limit: int, where: str | None = None,
                    errors: str = "strict") -> str:
    """``read_input`` decoded as UTF-8; with ``errors="strict"`` a UserError naming the
    file and the first bad byte if it is not UTF-8 text."""
    data = read_input(path, what, limit, where)
    try:
        return data.decode("utf-8", errors=errors)
    except UnicodeDecodeError as exc:
        raise UserError(f"{where or path}: the {what} is not UTF-8 text (byte {exc.start} is "
                        f"{data[exc.start:exc.start + 1]!r})") from None
