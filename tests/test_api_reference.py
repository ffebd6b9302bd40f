"""The API reference (docs/api.md): every public function it documents has numpydoc sections.

The modules of the reference are read from the pdoc command shown in
docs/api.md (with the sub-modules pdoc adds by itself), and must be every
public module of the package (no leading underscore in its dotted name).  A module's public functions and classes are
the names in its ``__all__`` (without one: the public names it defines, as
pdoc shows them).  A function needs a one-line summary, a ``Parameters``
section naming its parameters (``self`` and private ones aside), a ``Returns``
section when its body returns a value and a ``Yields`` section when it yields; a class
needs a summary of its own.  The sections are read by numpydoc's
``NumpyDocString`` when numpydoc is installed (the ``docs`` extra), else by
the same rule on section underlines.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import pkgutil
import re
import textwrap
from pathlib import Path

import pytest

import mechcirc

API_PAGE = Path(__file__).resolve().parents[1] / "docs" / "api.md"
_SECTION = re.compile(r"^[ \t]*([A-Z][A-Za-z ]+)\n[ \t]*-{3,}[ \t]*$", re.M)


def reference_modules() -> list[str]:
    """The module names of the ``python -m pdoc`` command of docs/api.md (``\\`` continues)."""
    text = API_PAGE.read_text(encoding="utf-8").replace("\\\n", " ")
    lines = [ln for ln in text.splitlines() if ln.startswith("$ python -m pdoc ")]
    assert len(lines) == 1, "docs/api.md shows one pdoc command"
    names, skip = [], False
    for w in lines[0].split()[4:]:
        if skip:
            skip = False
        elif w in ("-o", "--output-directory", "-d", "--docformat"):
            skip = True
        elif not w.startswith("-"):
            names.append(w)
    return names


def documented_modules() -> list[str]:
    """The modules pdoc documents for that command: each one named and, as pdoc walks a
    package, its sub-modules that are in its ``__all__`` (all of them when it has none)."""
    out = []

    def add(name: str) -> None:
        out.append(name)
        module = importlib.import_module(name)
        names = getattr(module, "__all__", None)
        for sub in pkgutil.iter_modules(getattr(module, "__path__", []), name + "."):
            if names is None or sub.name.rpartition(".")[2] in names:
                add(sub.name)

    for name in reference_modules():
        add(name)
    return out


def public_modules() -> set[str]:
    """Every module of the package without a leading underscore in its dotted name."""
    return {"mechcirc"} | {m.name for m in pkgutil.walk_packages(mechcirc.__path__, "mechcirc.")
                           if not any(p.startswith("_") for p in m.name.split("."))
                           and not m.name.startswith("mechcirc.cli.")}


def code_of(fn):
    """``fn``'s own definition (the function a decorator such as contextmanager wraps)."""
    fn = inspect.unwrap(fn)
    return ast.parse(textwrap.dedent(inspect.getsource(fn))).body[0]


def returns_and_yields(fn) -> tuple[bool, bool]:
    """Whether ``fn``'s own body (not a nested function's) returns a value, and whether it yields."""
    found = [False, False]

    def walk(node) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda,
                                  ast.ClassDef)):
                continue
            if isinstance(child, (ast.Yield, ast.YieldFrom)):
                found[1] = True
            if isinstance(child, ast.Return) and child.value is not None and not (
                    isinstance(child.value, ast.Constant) and child.value.value is None):
                found[0] = True
            walk(child)

    walk(code_of(fn))
    return found[0], found[1]


def sections(doc: str) -> tuple[bool, set[str], set[str]]:
    """(has a summary, the non-empty sections, the parameter names) of a numpydoc docstring."""
    try:
        from numpydoc.docscrape import NumpyDocString
    except ImportError:
        found = set(_SECTION.findall(doc))
        names = set()
        if "Parameters" in found:        # its entries: the lines at the section's indentation
            body = re.split(r"^[ \t]*Parameters\n[ \t]*-{3,}[ \t]*\n", doc, flags=re.M)[1]
            body = _SECTION.split(body)[0]
            names = {n for ln in body.splitlines() if ln and not ln[0].isspace()
                     for n in ln.split(" : ")[0].split(",")}
        return bool(doc.strip()) and not _SECTION.match(doc), found, _bare(names)
    parsed = NumpyDocString(doc)
    return any(ln.strip() for ln in parsed["Summary"]), {
        s for s in ("Parameters", "Returns", "Yields") if parsed[s]}, _bare(
        n for p in parsed["Parameters"] for n in p.name.split(","))


def _bare(names) -> set[str]:
    return {n.strip().lstrip("*") for n in names}


def docstring_problems(fn) -> list[str]:
    """What ``fn``'s docstring lacks of a summary, Parameters (naming every parameter but
    ``self``, ``cls`` and private ones), Returns and Yields."""
    summary, found, named = sections(inspect.getdoc(fn) or "")
    problems = [] if summary else ["a one-line summary"]
    params = [p for p in inspect.signature(fn).parameters if p not in ("self", "cls")]
    if params and "Parameters" not in found:
        problems.append("a Parameters section")
    elif missing := [p for p in params if p not in named and not p.startswith("_")]:
        problems.append(f"parameters {', '.join(missing)} in Parameters")
    returns, yields = returns_and_yields(fn)
    if returns and "Returns" not in found:
        problems.append("a Returns section")
    if yields and "Yields" not in found:
        problems.append("a Yields section")
    return problems


def public_objects(kind) -> dict[str, object]:
    """The public functions (``kind=inspect.isfunction``) or classes of the reference."""
    found = {}
    for name in documented_modules():
        module = importlib.import_module(name)
        names = getattr(module, "__all__", None)
        if names is None:
            names = [k for k, v in vars(module).items()
                     if not k.startswith("_") and getattr(v, "__module__", None) == name]
        for attr in names:
            obj = getattr(module, attr)
            if kind(obj):
                found.setdefault(f"{obj.__module__}.{obj.__qualname__}", obj)
    return found


def test_the_reference_names_every_public_module():
    """Each once (pdoc warns of a module named twice, or named and walked to)."""
    names = documented_modules()
    assert reference_modules()[0] == "mechcirc" and len(names) == len(set(names))
    assert set(names) == public_modules()
    assert len(public_objects(inspect.isfunction)) >= 200


def test_every_public_function_has_numpydoc_sections():
    missing = {name: p for name, fn in public_objects(inspect.isfunction).items()
               if (p := docstring_problems(fn))}
    assert not missing, "docstrings without " + "; ".join(
        f"{name}: {', '.join(p)}" for name, p in sorted(missing.items()))


def test_every_public_class_has_a_summary():
    """The class's own docstring (a dataclass without one gets its signature as __doc__)."""
    bare = [name for name, cls in public_objects(inspect.isclass).items()
            if not sections(cls.__dict__.get("__doc__") or "")[0]
            or cls.__doc__.startswith(cls.__name__ + "(")]
    assert not bare, f"classes without a summary: {', '.join(sorted(bare))}"


@pytest.mark.parametrize("source,want", [
    ('def f(x):\n    """Summary."""\n    return x\n', ["a Parameters section", "a Returns section"]),
    ('def f():\n    """Summary."""\n    def g():\n        return 1\n', []),
    ('def f(x):\n    """Summary.\n\n    Parameters\n    ----------\n    x : int\n    """\n'
     '    return None\n', []),
    ('def f(x, y, *z, _w=1):\n    """Summary.\n\n    Parameters\n    ----------\n    x : int\n'
     '        Not y : int.\n    """\n', ["parameters y, z in Parameters"]),
    ('def f(x, y, *z):\n    """Summary.\n\n    Parameters\n    ----------\n    x, y : int\n'
     '    *z : int\n\n    Returns\n    -------\n    None\n    """\n', []),
    ('def f():\n    """Returns\n    -------\n    int\n    """\n    return 1\n',
     ["a one-line summary"]),
    ('def f():\n    """Summary.\n\n    Returns\n    -------\n    int\n    """\n    yield 1\n',
     ["a Yields section"]),
    ('import contextlib\n@contextlib.contextmanager\ndef f(x):\n    """Summary."""\n'
     '    yield x\n', ["a Parameters section", "a Yields section"]),
])
def test_the_check_can_fail(source, want, tmp_path):
    """The check itself: a value returned without Returns, parameters without Parameters or
    missing from it, no summary, a generator without Yields (also under a decorator); a
    nested function's return and ``return None`` are not values."""
    path = tmp_path / "m.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("m_api_check", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert docstring_problems(module.f) == want
