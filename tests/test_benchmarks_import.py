"""Every benchmarks/*.py compiles and every mechcirc name it uses exists.

Nothing runs a benchmark in the suite, so a renamed (often private) name
they reach into would only show when someone next runs one.  This reads each
script's syntax tree, without running it: ``import mechcirc.x``,
``from mechcirc.x import y`` and ``importlib.import_module("mechcirc.x")``
must import and name something that exists, and every attribute chain read
or assigned on a mechcirc module (``mechcirc.scene.cycle._BATCHED = False``)
must resolve.  ``from bench_x import y`` between scripts must name a
top-level definition of the sibling script (or of tests/reference).  A call
of a mechcirc function that spells out its arguments must fit the function's
signature.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "benchmarks").glob("*.py"))


def _resolve(dotted: str):
    """The object ``dotted`` names (``mechcirc.a.b``), importing submodules as needed;
    raises AttributeError / ImportError naming what is missing."""
    parts = dotted.split(".")
    obj = importlib.import_module(parts[0])
    for i, part in enumerate(parts[1:], start=1):
        if not isinstance(obj, types.ModuleType):
            break                       # an attribute of a class or value: not checked
        if hasattr(obj, part):
            obj = getattr(obj, part)
            continue
        try:
            obj = importlib.import_module(".".join(parts[: i + 1]))
        except ModuleNotFoundError:
            raise AttributeError(f"{'.'.join(parts[:i])} has no {part!r}") from None
    return obj


def _chain(node: ast.expr) -> list[str] | None:
    """``a.b.c`` as ["a", "b", "c"], or None when it is not a plain dotted name."""
    out = []
    while isinstance(node, ast.Attribute):
        out.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    out.append(node.id)
    return out[::-1]


def _top_level_names(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names.update(t.id for t in targets if isinstance(t, ast.Name))
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
    return names


def _local(module: str) -> Path | None:
    """The file of a module the scripts import from benchmarks/ or tests/, or None."""
    for d in (ROOT / "benchmarks", ROOT / "tests"):
        path = d / (module.replace(".", "/") + ".py")
        if path.exists():
            return path
    return None


def _aliases(tree: ast.AST) -> dict[str, str]:
    """Each local name a script binds to a mechcirc module or name -> its dotted name."""
    aliases: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "mechcirc":
                    aliases[a.asname or "mechcirc"] = a.name if a.asname else "mechcirc"
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module and \
                node.module.split(".")[0] == "mechcirc":
            for a in node.names:
                aliases[a.asname or a.name] = f"{node.module}.{a.name}"
    return aliases


def mechcirc_references(tree: ast.AST) -> tuple[list[str], list[tuple[str, str]]]:
    """The dotted mechcirc names a script uses, and its ``(sibling module, name)`` imports.

    Parameters
    ----------
    tree : ast.AST
        The parsed script.

    Returns
    -------
    tuple
        ``(dotted names, [(module, name), ...])``.
    """
    aliases = _aliases(tree)
    dotted: list[str] = [name for name in aliases.values() if name != "mechcirc"]
    siblings: list[tuple[str, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            dotted.extend(a.name for a in node.names if a.name.split(".")[0] == "mechcirc")
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module and \
                _local(node.module):
            siblings.extend((node.module, a.name) for a in node.names)
        elif isinstance(node, ast.Call) and _chain(node.func) in (["importlib", "import_module"],
                                                                  ["import_module"]):
            arg = node.args[0] if node.args else None
            if isinstance(arg, ast.Constant) and str(arg.value).startswith("mechcirc"):
                dotted.append(str(arg.value))
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            chain = _chain(node)
            if chain and chain[0] in aliases:
                dotted.append(".".join([aliases[chain[0]], *chain[1:]]))
    return dotted, siblings


def bad_calls(tree: ast.AST) -> list[str]:
    """Calls of mechcirc functions whose arguments the function's signature refuses
    (a required argument added, a keyword renamed), for calls that spell out every
    argument (no ``*args`` / ``**kwargs``).

    Parameters
    ----------
    tree : ast.AST
        The parsed script.

    Returns
    -------
    list of str
        ``"line N: name(...): why"`` for each refused call.
    """
    aliases = _aliases(tree)
    out = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call) or any(isinstance(a, ast.Starred) for a in node.args) \
                or any(k.arg is None for k in node.keywords):
            continue
        chain = _chain(node.func)
        if not chain or chain[0] not in aliases:
            continue
        name = ".".join([aliases[chain[0]], *chain[1:]])
        try:
            fn = _resolve(name)
            if not inspect.isfunction(fn):
                continue            # classes, methods of values: not checked
            inspect.signature(fn).bind(*node.args, **{k.arg: k.value for k in node.keywords})
        except (AttributeError, ImportError):
            continue                # reported as a missing name
        except TypeError as exc:
            out.append(f"line {node.lineno}: {name}(...): {exc}")
    return out


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_benchmark_compiles_and_its_mechcirc_names_exist(script):
    text = script.read_text(encoding="utf-8")
    compile(text, str(script), "exec")
    dotted, siblings = mechcirc_references(ast.parse(text))
    missing = []
    for name in sorted(set(dotted)):
        try:
            _resolve(name)
        except (AttributeError, ImportError) as exc:
            missing.append(f"{name}: {exc}")
    for module, name in sorted(set(siblings)):
        path = _local(module)
        if path is None or name not in _top_level_names(path):
            missing.append(f"{module}.{name}: not defined in {path}")
    missing += bad_calls(ast.parse(text))
    assert not missing, f"{script.name} uses names that do not exist:\n" + "\n".join(missing)


def test_the_check_sees_a_renamed_name():
    """The check itself: a missing function, a missing private module attribute that is
    assigned, and a missing submodule are all reported; existing ones are not."""
    tree = ast.parse("import mechcirc\nimport mechcirc.scene.cycle\n"
                     "from mechcirc.reduction import reduce_circuit, no_such_function\n"
                     "mechcirc.scene.cycle._NO_SUCH_SWITCH = False\n"
                     "mechcirc.no_such_module.f()\nmechcirc.parse('x').resonances()\n")
    dotted, _ = mechcirc_references(tree)
    bad = []
    for name in dotted:
        try:
            _resolve(name)
        except (AttributeError, ImportError):
            bad.append(name)
    assert sorted(set(bad)) == ["mechcirc.no_such_module", "mechcirc.no_such_module.f",
                                "mechcirc.reduction.no_such_function",
                                "mechcirc.scene.cycle._NO_SUCH_SWITCH"]
    calls = ast.parse("from mechcirc.kinematics import linkage_solver\n"
                      "import mechcirc.reduction as red\n"
                      "linkage_solver._compiled()\nlinkage_solver._compiled('newton_path')\n"
                      "red.reduce_circuit(c, no_such_keyword=1)\nred.reduce_circuit(*a)\n")
    found = bad_calls(calls)
    assert [f.split(":")[0] for f in found] == ["line 3", "line 5"], found
