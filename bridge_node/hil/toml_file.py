"""TOML files validated by a pydantic schema, with errors that name the file, the line,
the key, the bad value and what is allowed (``ConfigError``, printed without a traceback)."""
from __future__ import annotations

import re
from pathlib import Path

from pydantic import ValidationError

from bridge_node.node.config import ConfigError, _describe, read_toml
from sim_core.params import Params

_HEADER = re.compile(r"^\s*\[\[?\s*([A-Za-z0-9_.\-]+)\s*\]\]?")


def key_line(text: str, loc: tuple) -> int | None:
    """The 1-based line of the key at ``loc`` (e.g. ``("expect", 2, "quantity")``): the key's
    own line, else the header of its table (array-of-tables entries counted), else None."""
    lines = text.splitlines()
    table, index, keys = "", None, [p for p in loc if isinstance(p, str)]
    if len(loc) >= 2 and isinstance(loc[0], str) and isinstance(loc[1], int):
        table, index, keys = loc[0], loc[1], [p for p in loc[2:] if isinstance(p, str)]
    start, end, seen = 0, len(lines), -1
    if table:
        start = None
        for i, line in enumerate(lines):
            m = _HEADER.match(line)
            if m and start is not None:
                end = i
                break
            if m and m.group(1) == table:
                seen += 1
                if seen == index:
                    start = i
        if start is None:
            return None
    else:
        end = next((i for i, line in enumerate(lines) if _HEADER.match(line)), len(lines))
    for key in keys[:1]:
        pattern = re.compile(rf"^\s*{re.escape(key)}\s*=")
        for i in range(start, end):
            if pattern.match(lines[i]):
                return i + 1
    return start + 1 if table else None


def load_toml_model(path: str | Path, schema: type[Params], what: str) -> Params:
    """Read ``path`` and validate it against ``schema``; ConfigError naming the file, the
    line and the key of every error (``what``: the kind of file, for the messages)."""
    path = Path(path)
    text, data = read_toml(path, what)
    try:
        return schema.model_validate(data)
    except ValidationError as exc:
        found = []
        for err in exc.errors():
            line = key_line(text, tuple(err["loc"]))
            found.append(f"{path}:{line}: {_describe(err)}" if line else f"{path}: {_describe(err)}")
        raise ConfigError(f"invalid {what}:\n  " + "\n  ".join(found)) from None
