"""The C heap's figures and page give-back (glibc): freed chunks pinned between live ones
stay resident until their pages are given back."""
import numpy as np
import pytest

from bridge_node.node.c_heap import give_back_free_pages, heap_in_use_mib
from bridge_node.node.realtime_loop import resident_mib

CHUNK = 64 * 1024  # bytes: below glibc's mmap threshold, so the chunks come from the heap


@pytest.mark.skipif(heap_in_use_mib() is None, reason="not glibc 2.33 or later: no mallinfo2")
def test_freed_chunks_between_live_ones_leave_the_resident_memory_when_given_back():
    in_use = heap_in_use_mib()
    chunks = [np.ones(CHUNK // 8) for _ in range(1024)]  # 64 MiB, every page touched
    assert heap_in_use_mib() - in_use > 60.0
    pins = chunks[::8]  # every eighth stays, so the heap's top cannot shrink past the rest
    del chunks
    freed_in_use = heap_in_use_mib()
    assert freed_in_use - in_use < 12.0  # the heap counts the freed 56 MiB as free...
    before = resident_mib()
    assert give_back_free_pages()
    after = resident_mib()
    assert before - after > 40.0  # ...and their pages leave the resident memory when given back
    assert abs(heap_in_use_mib() - freed_in_use) < 0.5  # giving pages back frees nothing in use
    assert sum(p[0] for p in pins) == len(pins)
