"""The node's layers (issue 29, item 4): the shared utilities (``bridge_node.common``: errors,
paths, files, network rules, child processes) sit below everything and import nothing of the
node; the links, the state stream and the renderer sit below the exercise, the node's loop,
replay, the HIL bench, the station and the commands, and import none of them."""
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
