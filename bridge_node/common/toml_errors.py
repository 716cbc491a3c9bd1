"""Messages for TOML that Python's ``tomllib`` cannot take although it may be valid TOML
(nesting deeper than Python's recursion, an integer of more than 4300 digits, a time zone
offset of 24 h or more), naming the file, the line and the key; and values shown safely in
messages (a huge integer cannot even be printed in decimal)."""
from __future__ import annotations

import re
from pathlib import Path

MAX_SHOWN = 80  # characters of a bad value shown in a message
_DIGITS = re.compile(r"[0-9][0-9_]{4300,}")  # more than 4300 digits: refused by int()
_KEY = re.compile(r"^\s*([A-Za-z0-9_\-.\"' ]+?)\s*=")
_TABLE = re.compile(r"^\s*\[\[?\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_DEEP = 64  # a nesting this deep is where a too-deep value is reported


def shown(value: object) -> str:
    """``repr(value)``, at most MAX_SHOWN characters; an integer too long to print in
    decimal is described by its size."""
    if isinstance(value, int) and value.bit_length() > 14_000:  # about 4200 digits
        return f"<an integer of {value.bit_length()} bits>"
    text = repr(value)
    return text if len(text) <= MAX_SHOWN else text[:MAX_SHOWN - 3] + "..."


def _too_deep(text: str) -> int | None:
    """Where the bracket nesting of ``[`` and ``{`` first passes _DEEP, strings and
    comments skipped (roughly: enough to point at the value), or None."""
    depth, quote, i = 0, "", 0
    while i < len(text):
        c = text[i]
        if quote:
            if c == "\\" and quote == '"':
                i += 1
            elif c == quote or c == "\n":
                quote = ""
        elif c in "\"'":
            quote = c
        elif c == "#":
            i = text.find("\n", i)
            if i < 0:
                return None
        elif c in "[{":
            depth += 1
            if depth > _DEEP:
                return i
        elif c in "]}":
            depth -= 1
        i += 1
    return None


def _key_at(text: str, pos: int) -> str:
    """The dotted key whose value holds position ``pos``: the last assignment at or before
    its line, under the last table header before it."""
    table, key = "", ""
    for line in text[:pos].split("\n"):
        header, assignment = _TABLE.match(line), _KEY.match(line)
        if header and not assignment:
            table, key = header.group(1), ""
        elif assignment:
            key = assignment.group(1)
    return ".".join(k for k in (table, key) if k) or "(top level)"


def toml_error(path: Path, text: str, exc: Exception) -> str:
    """The message for ``exc`` raised by ``tomllib.loads(text)`` (a RecursionError or a
    ValueError that is not a TOMLDecodeError): the file, and where found the line and key."""
    if isinstance(exc, RecursionError):
        pos, problem = _too_deep(text), "values nested too deep for Python's TOML reader"
    elif (found := _DIGITS.search(text)) is not None:
        pos, problem = found.start(), "an integer of more than 4300 digits"
    else:
        pos, problem = None, str(exc)[:200]
    if pos is None:
        return f"{path}: not valid TOML: {problem}"
    line = text.count("\n", 0, pos) + 1
    return f"{path}:{line}: {_key_at(text, pos)}: not valid TOML: {problem}"
