"""The package's source files, each parsed once per test process.

Tests that read the whole package's syntax (the import graph, where the
exception classes live) share these trees instead of each parsing every file
(0.8 s of CPU a time).  The trees are only read, never changed.
"""

import ast
import functools
from pathlib import Path

import mechcirc

PACKAGE = Path(mechcirc.__file__).resolve().parent


@functools.cache
def package_trees() -> dict[Path, ast.Module]:
    """``{path: tree}`` of every ``.py`` file of the package, in sorted path order."""
    return {path: ast.parse(path.read_text(encoding="utf-8"))
            for path in sorted(PACKAGE.rglob("*.py"))}


def statements(tree: ast.AST):
    """Every node of ``tree`` but expressions and what is inside them (as ``ast.walk``
    would give them, less those): an expression holds no statement, so a walk for
    classes, functions or imports need not enter one (most of a module's nodes)."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        todo.extend(c for c in ast.iter_child_nodes(node) if not isinstance(c, ast.expr))
