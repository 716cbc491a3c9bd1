"""Checks of the folders and files the node will write, made before the work starts, so a
bad path is one clear message and never a traceback after a finished run."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from bridge_node.node.errors import UserError


def expand_user(path: str | Path, what: str) -> Path:
    """``~`` expanded; UserError naming ``what`` for an unknown user (``~nobody/x``)."""
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


def writable_file(path: str | Path, what: str) -> Path:
    """The file path if it can be written: not a folder, in a folder files can be written
    in (created if missing), not a read-only existing file; UserError otherwise."""
    path = expand_user(path, what)
    if path.is_dir():
        raise UserError(f"{what} = {str(path)!r}: is a folder, expected a file name")
    reason = _cannot_write_in(path.parent)
    if reason is None and path.exists() and not os.access(path, os.W_OK):
        reason = "the file exists and cannot be overwritten"
    if reason:
        raise UserError(f"{what} = {str(path)!r}: cannot write this file ({reason})")
    return path
