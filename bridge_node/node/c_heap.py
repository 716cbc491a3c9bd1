"""This process's C heap (glibc malloc): the bytes in use, and giving its free pages back.

Numpy's arrays, the engine's bodies and Python's larger objects come from malloc. In the
main job the heap's bytes in use level off once the live floes do, but its resident size
kept growing: the per-step temporaries (sized by the floes and contacts of the step) and
the long-lived pieces between them leave free chunks that glibc keeps resident, and the
heap's top only ever grows past them. Traced with ``malloc_stats`` 360 s apart in a 640 s
run: the main arena held 3.7 MB more from the system while its bytes in use fell by 0.1 MB.
``malloc_trim`` gives the whole pages inside free chunks back to the system (the pages stay
mapped and fault in again when reused). No Python library exposes these two glibc calls,
hence ctypes here. Elsewhere (musl, macOS, Windows) both report that they cannot.
"""
from __future__ import annotations

import ctypes


class _MallInfo2(ctypes.Structure):
    """glibc's ``struct mallinfo2`` (2.33 and later): byte counts as size_t."""

    _fields_ = [(name, ctypes.c_size_t) for name in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks",
                 "keepcost")]


def _libc() -> ctypes.CDLL | None:
    try:
        return ctypes.CDLL(None)  # the C library this process already runs on
    except OSError:
        return None


_LIBC = _libc()
_MALLINFO2 = getattr(_LIBC, "mallinfo2", None)
_MALLOC_TRIM = getattr(_LIBC, "malloc_trim", None)
if _MALLINFO2 is not None:
    _MALLINFO2.restype = _MallInfo2
    _MALLINFO2.argtypes = []
if _MALLOC_TRIM is not None:
    _MALLOC_TRIM.restype = ctypes.c_int
    _MALLOC_TRIM.argtypes = [ctypes.c_size_t]


def heap_in_use_mib() -> float | None:
    """Bytes the C heap has handed out and not had back, all arenas and mmapped blocks
    included, in MiB; None where the C library does not say (not glibc 2.33+)."""
    if _MALLINFO2 is None:
        return None
    info = _MALLINFO2()
    return (info.uordblks + info.hblkhd) / 2**20


def give_back_free_pages() -> bool:
    """Give the whole free pages inside the heap's free chunks back to the system
    (``malloc_trim(0)``); False where the C library cannot."""
    if _MALLOC_TRIM is None:
        return False
    _MALLOC_TRIM(0)
    return True
