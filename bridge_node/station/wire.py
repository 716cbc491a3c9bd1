"""The station's binary messages to the browser: one WebSocket binary message is a small
JSON header and the bulk data as raw little-endian typed arrays, read in the page as
``Float32Array``/``Int32Array`` views without parsing (no per-floe JSON objects).

Layout: ``uint32`` length of the JSON text, the JSON text (padded with spaces so the arrays
start on an 8-byte boundary), then each array's bytes in the order the header's
``arrays`` list names them (``[name, dtype, count]``); every dtype is 4 bytes wide, so each
array starts aligned.
"""
from __future__ import annotations

import json
import struct

import numpy as np

_DTYPES = {"f4": np.dtype("<f4"), "i4": np.dtype("<i4"), "u4": np.dtype("<u4")}


def pack(header: dict, arrays: dict[str, np.ndarray]) -> bytes:
    """One binary message: ``header`` (JSON-able; its ``arrays`` key is set here) and the
    named arrays, each cast to its little-endian 4-byte dtype by kind (float -> f4, signed
    -> i4, unsigned -> u4) and flattened."""
    parts, listed = [], []
    for name, array in arrays.items():
        a = np.asarray(array)
        kind = "f4" if a.dtype.kind == "f" else ("u4" if a.dtype.kind in "ub" else "i4")
        data = np.ascontiguousarray(a, dtype=_DTYPES[kind]).ravel()
        listed.append([name, kind, int(data.size)])
        parts.append(data.tobytes())
    text = json.dumps({**header, "arrays": listed}, separators=(",", ":")).encode()
    text += b" " * (-(4 + len(text)) % 8)
    return b"".join([struct.pack("<I", len(text)), text, *parts])


def unpack(message: bytes) -> tuple[dict, dict[str, np.ndarray]]:
    """The header and arrays of a ``pack`` message (for tests and tools)."""
    (length,) = struct.unpack_from("<I", message)
    header = json.loads(message[4:4 + length])
    arrays, offset = {}, 4 + length
    for name, kind, count in header["arrays"]:
        arrays[name] = np.frombuffer(message, dtype=_DTYPES[kind], count=count, offset=offset)
        offset += 4 * count
    return header, arrays
