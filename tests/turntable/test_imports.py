"""The turntable package's modules import each other one way: no cycle, counting the imports made
inside functions too (they close a cycle at run time just the same); imports for the type checker
only (``if TYPE_CHECKING:``) do not run and are left out.

Truth: the import statements of the source files, read with ``ast`` (nothing is imported).
"""

from __future__ import annotations

import ast
from pathlib import Path

import rotacal.turntable

PACKAGE = "rotacal.turntable"


def _imports() -> dict[str, set[str]]:
    """Module → the modules of the package it imports (anywhere in its file)."""
    folder = Path(rotacal.turntable.__file__).parent
    modules = {p.stem for p in folder.glob("*.py") if p.stem != "__init__"}
    graph: dict[str, set[str]] = {}
    for name in modules:
        tree = ast.parse((folder / f"{name}.py").read_text(encoding="utf-8"))
        for block in ast.walk(tree):  # drop the bodies of `if TYPE_CHECKING:`
            if isinstance(block, ast.If) and ast.unparse(block.test) == "TYPE_CHECKING":
                block.body = []
        found: set[str] = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                if node.module.startswith(PACKAGE + "."):
                    found.add(node.module.split(".")[2])
                elif node.module == PACKAGE:
                    found.update(a.name for a in node.names if a.name in modules)
            elif isinstance(node, ast.Import):
                found.update(
                    a.name.split(".")[2] for a in node.names if a.name.startswith(PACKAGE + ".")
                )
        graph[name] = found & modules - {name}
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """A cycle of the graph as a list of modules (first = last), or None."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None


def test_turntable_modules_import_each_other_without_a_cycle() -> None:
    graph = _imports()
    assert "model" in graph["budget"] or "config" in graph["budget"]  # the graph is read
    assert "model" not in graph["config"] and "config" in graph["model"]
    assert "allocation" not in graph["montecarlo"]  # only for the type checker
    assert _cycle(graph) is None, " → ".join(_cycle(graph) or [])
