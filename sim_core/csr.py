"""Flat ragged arrays (CSR style): row i owns items ``start[i]:start[i + 1]``, vectorised."""
from __future__ import annotations

import numpy as np


def offsets(counts: np.ndarray) -> np.ndarray:
    """CSR offsets (n+1,) from per-row counts (n,)."""
    out = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    return out


def segment_arange(counts: np.ndarray) -> np.ndarray:
    """Concatenated aranges: [0..counts[0]-1, 0..counts[1]-1, ...]."""
    counts = np.asarray(counts, dtype=np.int64)
    starts = np.cumsum(counts) - counts
    return np.arange(counts.sum()) - np.repeat(starts, counts)


def gather_ranges(starts: np.ndarray, stops: np.ndarray) -> np.ndarray:
    """Indices of the concatenated ranges [starts[i], stops[i])."""
    starts = np.asarray(starts, dtype=np.int64)
    return np.repeat(starts, stops - starts) + segment_arange(stops - starts)
