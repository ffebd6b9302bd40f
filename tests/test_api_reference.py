"""The API reference (docs/api.md): every public function it documents has numpydoc sections.

The modules of the reference are read from the pdoc command shown in
docs/api.md, so a module added there is checked here too.  A public function
is a function named in a module's ``__all__``; it needs a one-line summary, a
``Parameters`` section when it takes parameters (``self`` aside) and a
``Returns`` (or ``Yields``) section when its body returns a value.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import re
import textwrap
from pathlib import Path

import pytest

API_PAGE = Path(__file__).resolve().parents[1] / "docs" / "api.md"
_SECTION = re.compile(r"^[ \t]*([A-Z][A-Za-z ]+)\n[ \t]*-{3,}[ \t]*$", re.M)


def reference_modules() -> list[str]:
    """The module names on the ``python -m pdoc`` line of docs/api.md."""
    lines = [ln for ln in API_PAGE.read_text(encoding="utf-8").splitlines()
             if ln.startswith("$ python -m pdoc ")]
    assert len(lines) == 1, "docs/api.md shows one pdoc command"
    words = lines[0].split()[4:]
    names, skip = [], False
    for w in words:
        if skip:
            skip = False
        elif w in ("-o", "--output-directory", "-d", "--docformat"):
            skip = True
        elif not w.startswith("-"):
            names.append(w)
    return names


def returns_value(fn) -> bool:
    """Whether ``fn``'s own body (not a nested function's) returns a value or yields."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(fn))).body[0]

    def walk(node) -> bool:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda,
                                  ast.ClassDef)):
                continue
            if isinstance(child, (ast.Yield, ast.YieldFrom)):
                return True
            if isinstance(child, ast.Return) and child.value is not None and not (
                    isinstance(child.value, ast.Constant) and child.value.value is None):
                return True
            if walk(child):
                return True
        return False

    return walk(tree)


def docstring_problems(fn) -> list[str]:
    """What ``fn``'s docstring lacks of a summary, Parameters and Returns (empty: nothing)."""
    doc = inspect.getdoc(fn) or ""
    sections = set(_SECTION.findall(doc))
    problems = []
    if not doc.strip() or _SECTION.match(doc):
        problems.append("a one-line summary")
    params = [p for p in inspect.signature(fn).parameters if p not in ("self", "cls")]
    if params and "Parameters" not in sections:
        problems.append("a Parameters section")
    if returns_value(fn) and not {"Returns", "Yields"} & sections:
        problems.append("a Returns section")
    return problems


def public_functions() -> dict[str, object]:
    found = {}
    for name in reference_modules():
        module = importlib.import_module(name)
        for attr in module.__all__:
            obj = getattr(module, attr)
            if inspect.isfunction(obj):
                found.setdefault(f"{obj.__module__}.{obj.__qualname__}", obj)
    return found


def test_the_reference_names_the_index_and_the_subpackages():
    names = reference_modules()
    assert names[0] == "mechcirc"
    assert {"mechcirc.kinematics", "mechcirc.scene", "mechcirc.sley",
            "mechcirc.transient"} <= set(names)
    assert len(public_functions()) >= 30


def test_every_public_function_has_numpydoc_sections():
    missing = {name: p for name, fn in public_functions().items()
               if (p := docstring_problems(fn))}
    assert not missing, "docstrings without " + "; ".join(
        f"{name}: {', '.join(p)}" for name, p in sorted(missing.items()))


@pytest.mark.parametrize("source,want", [
    ('def f(x):\n    """Summary."""\n    return x\n', ["a Parameters section", "a Returns section"]),
    ('def f():\n    """Summary."""\n    def g():\n        return 1\n', []),
    ('def f(x):\n    """Summary.\n\n    Parameters\n    ----------\n    x : int\n    """\n'
     '    return None\n', []),
    ('def f():\n    """Returns\n    -------\n    int\n    """\n    return 1\n',
     ["a one-line summary"]),
])
def test_the_check_can_fail(source, want, tmp_path):
    """The check itself: a value returned without Returns, parameters without Parameters,
    no summary; a nested function's return and ``return None`` are not values."""
    path = tmp_path / "m.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("m_api_check", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert docstring_problems(module.f) == want
