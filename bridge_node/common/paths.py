"""Checks of the folders and files the node will write, made before the work starts, so a
bad path is one clear message and never a traceback after a finished run."""
from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

from bridge_node.common.errors import UserError
from bridge_node.common.input_files import file_kind

NUL_IN_PATH = "a path cannot contain a NUL character"


def expand_user(path: str | Path, what: str) -> Path:
    """``~`` expanded; UserError naming ``what`` for an unknown user (``~nobody/x``) or a
    NUL character in the path."""
    if "\0" in str(path):
        raise UserError(f"{what} = {str(path)!r}: {NUL_IN_PATH}")
    try:
        return Path(path).expanduser()
    except RuntimeError:
        raise UserError(f"{what} = {str(path)!r}: cannot expand ~ (no such user)") from None


def _cannot_write_in(folder: Path) -> str | None:
    """Why no file can be written in the folder (created if missing), or None."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        return exc.strerror or str(exc)
    return None


def writable_dir(path: str | Path, what: str) -> Path:
    """The folder (created if missing) if files can be written in it; UserError naming
    ``what`` (an option or config key) and the path otherwise."""
    path = expand_user(path, what)
    reason = _cannot_write_in(path)
    if reason:
        raise UserError(f"{what} = {str(path)!r}: cannot write files there ({reason})")
    return path


def replaceable(path: Path, what: str) -> None:
    """UserError unless ``path`` is absent or a regular file, the only thing an output may
    replace: never a symbolic link (the link would be replaced, or what it points to
    written), a device node, a FIFO, a socket or a folder. Checks the path itself, never
    opens it."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as exc:
        raise UserError(f"{what} = {str(path)!r}: cannot write this file ({exc.strerror or exc})") from None
    if stat.S_ISLNK(mode):
        raise UserError(f"{what} = {str(path)!r}: is a symbolic link; outputs replace only regular files "
                        "(give the file's own path)")
    if stat.S_ISDIR(mode):
        raise UserError(f"{what} = {str(path)!r}: is a folder, expected a file name")
    if not stat.S_ISREG(mode):
        raise UserError(f"{what} = {str(path)!r}: is {file_kind(mode)}; outputs replace only regular files")


def writable_file(path: str | Path, what: str) -> Path:
    """The file path if it can be written: absent or a regular file (see ``replaceable``),
    in a folder files can be written in (created if missing), not a read-only existing
    file; UserError otherwise."""
    path = expand_user(path, what)
    replaceable(path, what)
    reason = _cannot_write_in(path.parent)
    if reason is None and path.exists() and not os.access(path, os.W_OK):
        reason = "the file exists and cannot be overwritten"
    if reason:
        raise UserError(f"{what} = {str(path)!r}: cannot write this file ({reason})")
    return path
