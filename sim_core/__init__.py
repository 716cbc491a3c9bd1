"""IceBridge simulation core: ship model, ice fracture, contact, buoyancy, scene, world step.

No I/O, no GL: every function here takes and returns numpy arrays and plain parameter
objects, so the core runs headless and under test without the bridge node.

numba compiles the core's kernels once and caches them. The cache goes to the user's cache
folder (``$XDG_CACHE_HOME/icebridge/numba``, by default ``~/.cache/icebridge/numba``), not
into the installed source tree; set ``NUMBA_CACHE_DIR`` to put it elsewhere. It must be set
before numba is first imported, hence here.
"""
import os
from pathlib import Path

os.environ.setdefault("NUMBA_CACHE_DIR", str(Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
                                             / "icebridge" / "numba"))
