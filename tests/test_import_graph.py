"""The package's modules import one way: no import circle (issue 15 §5).

The graph is read from the source with ``ast``: every ``import`` of a mechcirc
module, at module level *and* inside functions (a lazy import is still a
dependency: it only moves the circle from import time to call time), except
under ``if TYPE_CHECKING:`` (annotations only, never executed).
"""

import ast
import functools
from pathlib import Path

import networkx as nx

import mechcirc

PACKAGE = Path(mechcirc.__file__).resolve().parent


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_type_checking(node) -> bool:
    return isinstance(node, ast.If) and (
        (isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING")
        or (isinstance(node.test, ast.Attribute) and node.test.attr == "TYPE_CHECKING"))


def _imports(path: Path, modules: set[str]):
    """(target module, lazy?) for every import of a mechcirc module in ``path``."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []

    def visit(node, lazy):
        if _is_type_checking(node):
            return
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            lazy = True
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("mechcirc"):
                    found.append((alias.name, lazy))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("mechcirc"):
                # ``from . import nodal`` imports the sub-module nodal.
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    found.append((sub if sub in modules else target, lazy))
        for child in ast.iter_child_nodes(node):
            visit(child, lazy)

    visit(tree, False)
    return found


@functools.lru_cache(maxsize=None)     # read once per run; the tests only read it
def import_graph() -> nx.DiGraph:
    files = sorted(PACKAGE.rglob("*.py"))
    modules = {_module_name(p) for p in files}
    g = nx.DiGraph()
    g.add_nodes_from(modules)
    for path in files:
        src = _module_name(path)
        for target, lazy in _imports(path, modules):
            # A package's __init__ is run by importing any of its sub-modules;
            # count edges to the module actually named.
            while target not in modules and "." in target:
                target = target.rpartition(".")[0]
            if target != src and not src.startswith(target + ".") and target != "mechcirc":
                g.add_edge(src, target, lazy=lazy)
    return g


def test_the_graph_is_read():
    g = import_graph()
    assert g.has_edge("mechcirc.sweep", "mechcirc.reduction")
    assert g.has_edge("mechcirc.reduction", "mechcirc.circuit")
    assert len(g) > 40


def test_no_import_circle():
    g = import_graph()
    cycles = list(nx.simple_cycles(g))
    shown = ["  " + " -> ".join(c + [c[0]]) for c in sorted(cycles, key=len)[:10]]
    assert not cycles, f"{len(cycles)} import circle(s), e.g.:\n" + "\n".join(shown)


def test_data_classes_import_nothing_above_them():
    g = import_graph()
    assert set(g.successors("mechcirc.circuit")) <= {"mechcirc.errors"}
