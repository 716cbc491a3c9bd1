"""The contact space calls Chipmunk through pymunk's private cffi bindings
(``pymunk._chipmunk``; why: ``sim_core/ice/chipmunk_bodies.py``). pymunk is pinned to its major
version in pyproject.toml; this test fails loudly, naming what is gone, if a pymunk release
drops or renames any function, constant or C type the code uses."""
import re
from pathlib import Path

from pymunk._chipmunk import ffi, lib

ICE = Path(__file__).resolve().parent.parent / "sim_core" / "ice"
SOURCE = "".join((ICE / name).read_text() for name in ("contact.py", "chipmunk_bodies.py", "contact_resting.py"))


def test_every_chipmunk_function_and_constant_the_contact_space_uses_is_there():
    used = sorted(set(re.findall(r"\blib\.(\w+)", SOURCE)))
    assert len(used) > 20  # (the pattern finds the calls)
    missing = [name for name in used if not hasattr(lib, name)]
    assert not missing, f"pymunk {__import__('pymunk').version} lacks {missing}: the contact space (sim_core/ice/contact*.py, chipmunk_bodies.py) needs them"


def test_every_c_type_the_contact_space_casts_to_is_there():
    types = sorted(set(re.findall(r'ffi\.(?:cast|new)\("([^"]+)"', SOURCE)))
    assert {"cpBody *", "cpShape *", "cpVect[]"} <= set(types)
    for name in types:
        ffi.typeof(name)  # raises (ffi.error) for a type the bindings no longer declare
