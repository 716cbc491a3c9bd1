"""The node's layers (issue 29, item 4): the shared utilities (``bridge_node.common``: errors,
paths, files, network rules, child processes) sit below everything and import nothing of the
node; the links, the state stream and the renderer sit below the exercise, the node's loop,
replay, the HIL bench, the station and the commands, and import none of them; and no two
packages import each other, directly or round a longer loop."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "bridge_node"
ABOVE_THE_LINKS = {"node", "exercise", "replay", "hil", "station", "commands", "reference"}


def _imported_packages(folder: Path) -> dict[str, set[str]]:
    """For each module of ``folder``, the bridge_node packages it imports."""
    out = {}
    for path in folder.rglob("*.py"):
        found = set()
        for node in ast.walk(ast.parse(path.read_text())):
            names = [node.module] if isinstance(node, ast.ImportFrom) and node.module else \
                [a.name for a in node.names] if isinstance(node, ast.Import) else []
            found |= {n.split(".")[1] for n in names if n.startswith("bridge_node.") and n.count(".") >= 1}
        out[str(path.relative_to(PACKAGE.parent))] = found
    return out


def test_the_shared_utilities_import_nothing_of_the_node():
    upward = {m: sorted(p - {"common"}) for m, p in _imported_packages(PACKAGE / "common").items() if p - {"common"}}
    assert not upward, f"bridge_node.common must stay below the rest: {upward}"


def test_links_stream_and_render_import_nothing_above_them():
    for layer in ("links", "stream", "render"):
        upward = {m: sorted(p & ABOVE_THE_LINKS) for m, p in _imported_packages(PACKAGE / layer).items()
                  if p & ABOVE_THE_LINKS}
        assert not upward, f"bridge_node.{layer} imports from the layers above it: {upward}"


def _package_graph() -> dict[str, set[str]]:
    """bridge_node package -> the bridge_node packages its modules import (itself left out)."""
    graph: dict[str, set[str]] = {}
    for module, imported in _imported_packages(PACKAGE).items():
        parts = module.split("/")
        if len(parts) > 2:  # bridge_node/<package>/...
            graph.setdefault(parts[1], set()).update(imported - {parts[1]})
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import loop among the packages (depth-first search), or None."""
    state: dict[str, str] = {}  # package -> "open" while on the path, "done" after

    def visit(node: str, path: list[str]) -> list[str] | None:
        state[node] = "open"
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return path[path.index(nxt):] + [node, nxt] if nxt in path else path + [node, nxt]
            if nxt not in state:
                found = visit(nxt, path + [node])
                if found:
                    return found
        state[node] = "done"
        return None

    for start in sorted(graph):
        if start not in state:
            found = visit(start, [])
            if found:
                return found
    return None


def test_no_package_imports_round_a_loop():
    graph = _package_graph()
    assert {"links", "node", "replay", "exercise", "control"} <= set(graph)
    assert _cycle(graph) is None, f"packages import each other round a loop: {' -> '.join(_cycle(graph))}"
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]  # the search finds a loop
