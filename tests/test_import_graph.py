"""The package's modules import one way: no import circle (issue 15 §5).

The graph is read from the source with ``ast``: every ``import`` of a mechcirc
module, at module level *and* inside functions (a lazy import is still a
dependency: it only moves the circle from import time to call time), except
under ``if TYPE_CHECKING:`` (annotations only, never executed).

One kind of edge is told apart: a *delegate*, a method whose body imports a
function and calls it with ``self`` (SciPy's ``lti.bode``: ``Circuit.sweep``
is ``from ._sweep import sweep; return sweep(self, omega, method=method)``).
The function is the implementation and the method only a convenience, so its
upward edge is no dependency of the class; the circle test leaves delegates
out and :func:`test_delegates_are_one_call_and_listed` checks that each is a
delegate and nothing more.
"""

import ast
import functools
from pathlib import Path

import networkx as nx
from package_source import package_trees

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


def _is_delegate(func, parent) -> bool:
    """A method whose body is: a docstring, ``from <module> import f…``, then at most
    three statements whose calls are all of the imported names, one with ``self``."""
    if not isinstance(parent, ast.ClassDef) or not isinstance(func, ast.FunctionDef):
        return False
    body = func.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        body = body[1:]
    if not body or not isinstance(body[0], ast.ImportFrom) or not 1 <= len(body) - 1 <= 3:
        return False
    names = {a.asname or a.name for a in body[0].names}
    calls = [n for s in body[1:] for n in ast.walk(s) if isinstance(n, ast.Call)]
    return bool(calls) and all(isinstance(c.func, ast.Name) and c.func.id in names
                               for c in calls) \
        and any(c.args and getattr(c.args[0], "id", None) == "self" for c in calls)


def _imports(path: Path, modules: set[str]):
    """(target module, lazy?, delegate?) for every import of a mechcirc module in ``path``."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    tree = package_trees()[path]
    found = []

    def visit(node, lazy, delegate=False):
        if _is_type_checking(node):
            return
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            lazy = True
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("mechcirc"):
                    found.append((alias.name, lazy, delegate))
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
                    found.append((sub if sub in modules else target, lazy, delegate))
        for child in ast.iter_child_nodes(node):
            if not isinstance(child, ast.expr):     # no statement (no import) inside one
                visit(child, lazy, delegate or _is_delegate(child, node))

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
        for target, lazy, delegate in _imports(path, modules):
            # A package's __init__ is run by importing any of its sub-modules;
            # count edges to the module actually named.
            while target not in modules and "." in target:
                target = target.rpartition(".")[0]
            if target != src and not src.startswith(target + ".") and target != "mechcirc":
                if g.has_edge(src, target):          # a plain import outweighs a delegate
                    delegate = delegate and g.edges[src, target]["delegate"]
                g.add_edge(src, target, lazy=lazy, delegate=delegate)
    return g


def without_delegates(g: nx.DiGraph) -> nx.DiGraph:
    return g.edge_subgraph([e for e in g.edges if not g.edges[e]["delegate"]]).copy()


def test_the_graph_is_read():
    g = import_graph()
    assert g.has_edge("mechcirc._sweep", "mechcirc.reduction")
    assert g.has_edge("mechcirc.reduction", "mechcirc.circuit")
    assert len(g) > 40


def test_no_import_circle():
    g = without_delegates(import_graph())
    cycles = list(nx.simple_cycles(g))
    shown = ["  " + " -> ".join(c + [c[0]]) for c in sorted(cycles, key=len)[:10]]
    assert not cycles, f"{len(cycles)} import circle(s), e.g.:\n" + "\n".join(shown)


def test_data_classes_import_nothing_above_them():
    g = without_delegates(import_graph())
    assert set(g.successors("mechcirc.circuit")) <= {"mechcirc.errors", "mechcirc._memo"}
    assert not set(g.successors("mechcirc._memo"))      # the memo mixin imports no module of ours


def test_delegates_are_one_call_and_listed():
    """The upward edges left out above are exactly the analysis methods of Circuit,
    Sweep.to_skrf, PeriodicResult.plot and TransientResult.plot (a new one is a decision, to be added here)."""
    g = import_graph()
    delegates = {e for e in g.edges if g.edges[e]["delegate"]}
    assert delegates == {("mechcirc.circuit", f"mechcirc.{m}") for m in
                         ("reduction", "nodal", "_sweep", "resonances", "modes", "periodic", "interop.skrf",
                          "interop.formula")} | {("mechcirc._sweep", "mechcirc.interop.skrf"),
                                                   ("mechcirc.periodic", "mechcirc.plotting"),
                                                   ("mechcirc.transient.result",
                                                    "mechcirc.plotting")}
    assert not _is_delegate(ast.parse("def f(self):\n    from .x import g\n    return h(self)\n")
                            .body[0], ast.ClassDef("C", [], [], [], []))


def test_the_index_is_a_plain_module_and_no_module_shadows_its_names():
    """``mechcirc`` is a plain module (no module class): so no submodule may share a
    name with a public name of the index, or importing it would rebind that name."""
    import importlib
    import importlib.util
    import types

    assert type(mechcirc) is types.ModuleType
    clashes = [n for n in mechcirc.__all__ if importlib.util.find_spec(f"mechcirc.{n}")]
    assert not clashes, clashes
    for private in ("mechcirc._sweep", "mechcirc._simplify"):
        importlib.import_module(private)      # the implementation modules, loaded
    assert isinstance(mechcirc.sweep, types.FunctionType)
    assert isinstance(mechcirc.simplify, types.FunctionType)
