"""IceBridge simulation core: ship model, ice fracture, contact, buoyancy, scene, world step.

No I/O, no GL: every function here takes and returns numpy arrays and plain parameter
objects, so the core runs headless and under test without the bridge node.

numba compiles the core's kernels once and caches them. The cache goes to the user's cache
folder (``$XDG_CACHE_HOME/icebridge/numba/<digest>``, by default under
``~/.cache/icebridge/numba``), not into the installed source tree; set ``NUMBA_CACHE_DIR``
to put it elsewhere. It must be set before numba is first imported, hence here.

The digest is of the kernels' source files (``kernel_sources_digest``): numba keys a cached
kernel by its own file's time stamp alone, so a kernel that calls, and so compiles in,
another module's kernel kept the old code when only that module changed (the threshold of
``ice.vertical.settled``, compiled into ``ice.resting`` and ``ice.step``, changed and the
cached kernels ran the old one). A cache folder per version of the kernels' sources cannot
hold such stale code.
"""
import hashlib
import os
from pathlib import Path


def kernel_sources_digest(root: Path = Path(__file__).parent) -> str:
    """A digest (16 hex digits) of the core's source files that use numba (a compiled
    kernel can call only other compiled kernels), by their paths and contents."""
    digest = hashlib.sha1()
    for path in sorted(root.rglob("*.py")):
        source = path.read_bytes()
        if b"numba" in source:
            digest.update(path.relative_to(root).as_posix().encode() + b"\0" + source)
    return digest.hexdigest()[:16]


os.environ.setdefault("NUMBA_CACHE_DIR", str(Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
                                             / "icebridge" / "numba" / kernel_sources_digest()))
