"""Writing the node's output files (summaries, exports, images, videos, reports, the
template library) safely and atomically: the output is written to a new temporary file
beside it, then renamed over it. Only an absent path or a regular file is ever replaced:
a symbolic link, a device node (``/dev/null``), a FIFO or a folder is refused before
anything is written, and checked again just before the rename. A failed write (a full
disk) is a UserError and leaves the old file as it was."""
from __future__ import annotations

import os
import secrets
from pathlib import Path
from types import TracebackType

from bridge_node.common.errors import UserError
from bridge_node.common.paths import replaceable, writable_file


class OutputFile:
    """One output written atomically; a context manager. ``tmp`` is the temporary file to
    write (it keeps the output's suffix, for writers that choose the format by it); leaving
    the block without an error puts it in place (``commit``), with one removes it
    (``discard``). ``what`` names the option or the kind of output for the messages."""

    def __init__(self, path: str | Path, what: str) -> None:
        self.path, self.what = writable_file(path, what), what
        self.tmp = self.path.with_name(f".{self.path.name}.{secrets.token_hex(4)}.tmp{self.path.suffix}")
        try:  # a new file of our own (O_EXCL: never one planted there), mode as the umask says
            os.close(os.open(self.tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666))
        except OSError as exc:
            raise self._error(exc) from None

    def _error(self, exc: OSError) -> UserError:
        return UserError(f"{self.what} = {str(self.path)!r}: cannot write this file ({exc.strerror or exc})")

    def commit(self) -> Path:
        """Put the written file in place of the output (refused if the output's path has
        become anything but a regular file meanwhile); returns the output's path."""
        try:
            replaceable(self.path, self.what)
            os.replace(self.tmp, self.path)
        except OSError as exc:
            raise self._error(exc) from None
        finally:
            self.discard()
        return self.path

    def discard(self) -> None:
        """Remove the temporary file, if it is still there."""
        self.tmp.unlink(missing_ok=True)

    def __enter__(self) -> Path:
        return self.tmp

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if kind is None:
            self.commit()
            return
        self.discard()
        if isinstance(exc, OSError):  # a full disk, an I/O error: the user's to fix, not a traceback
            raise self._error(exc) from None


def write_output(path: str | Path, data: bytes | str, what: str) -> Path:
    """Write ``data`` (str as UTF-8) to the output file ``path`` atomically; UserError if
    the path is refused or the write fails. Returns the path."""
    output = OutputFile(path, what)
    with output as tmp:
        tmp.write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
    return output.path
