"""What the fuzz tests write into TOML documents (configs, scenario files, stream headers):
careless values, every key path of a document, and a document with a few keys mutated."""
import math

from hypothesis import strategies as st


def mutants():
    """Values a careless integrator might write anywhere in a config."""
    return st.sampled_from([True, False, "", "1.0", "x" * 300, -1, 0, 1e30, -1e30, math.nan, math.inf, [], {},
                            [1, 2], {"unknown": 1}, "/dev/zero", "socket://192.0.2.1:4001", 0x42, "any"])


def paths_of(node, prefix=()):
    """Every key path (tuples of keys and list indices) in a parsed TOML document."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        yield prefix + (key,)
        yield from paths_of(value, prefix + (key,))


def mutated(doc: dict, data) -> dict:
    """The document with one to three keys replaced, deleted or joined by an unknown one
    (``data``: hypothesis's ``st.data()``)."""
    for _ in range(data.draw(st.integers(1, 3))):
        path = data.draw(st.sampled_from(list(paths_of(doc))))
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        action = data.draw(st.sampled_from(["replace", "delete", "add"]))
        if action == "replace":
            parent[path[-1]] = data.draw(mutants())
        elif action == "delete" and isinstance(parent, dict):
            del parent[path[-1]]
        elif isinstance(parent, dict):
            parent["unexpected_key"] = data.draw(mutants())
    return doc
