"""mechcirc._methods: the analysis methods attached to Circuit and Sweep are discoverable."""

import pydoc
import re

import pytest

import mechcirc
from mechcirc import Circuit, Sweep
from mechcirc._methods import ATTACHED

CLASSES = {"Circuit": Circuit, "Sweep": Sweep}
PAIRS = [(cls, name) for cls, names in ATTACHED.items() for name in names]


def test_the_list_is_what_is_attached():
    # every public callable/property _methods defines on Circuit is in ATTACHED
    import mechcirc._methods as m

    mine = {name for name, value in vars(Circuit).items()
            if not name.startswith("_")
            and getattr(getattr(value, "fget", getattr(value, "func", value)), "__module__",
                        None) == m.__name__}
    assert mine == set(ATTACHED["Circuit"])
    assert set(ATTACHED) == {"Circuit", "Sweep"}


@pytest.mark.parametrize("cls,name", PAIRS)
def test_attached_method_is_documented_and_listed(cls, name):
    obj = CLASSES[cls]
    attr = vars(obj)[name]
    func = getattr(attr, "fget", getattr(attr, "func", attr))
    assert (func.__doc__ or "").strip(), f"{cls}.{name} has no docstring"
    # help(Circuit) shows it with its docstring's first line
    text = pydoc.render_doc(obj, renderer=pydoc.plaintext)
    assert re.search(rf"\b{name}\b", text)
    assert func.__doc__.strip().splitlines()[0][:30] in text
    # the package index names it as .name
    assert re.search(rf"\.{name}\b", mechcirc.__doc__), f"{cls}.{name} not in mechcirc's index"
    if cls == "Circuit":
        assert f"``{name}``" in Circuit.__doc__


def test_declarations_for_type_checkers_match_what_is_attached():
    # circuit.py declares the attached methods under TYPE_CHECKING (never run);
    # read them from the source and compare with the attached functions.
    import ast
    import inspect
    from pathlib import Path

    import mechcirc.circuit as circuit_module

    tree = ast.parse(Path(circuit_module.__file__).read_text(encoding="utf-8"))
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Circuit")
    block = next(n for n in cls.body if isinstance(n, ast.If)
                 and getattr(n.test, "id", None) == "TYPE_CHECKING")
    declared = {f.name: f for f in block.body if isinstance(f, ast.FunctionDef)}
    assert set(declared) == set(ATTACHED["Circuit"])
    for name, f in declared.items():
        attr = vars(Circuit)[name]
        func = getattr(attr, "fget", getattr(attr, "func", attr))
        want = [(p.name, p.kind.name) for p in inspect.signature(func).parameters.values()]
        args = f.args
        got = [(a.arg, "POSITIONAL_OR_KEYWORD") for a in args.args]
        if args.kwarg:
            got.append((args.kwarg.arg, "VAR_KEYWORD"))
        assert got == want, name
        is_property = any(getattr(d, "id", None) == "property" for d in f.decorator_list)
        assert is_property == (not callable(attr) or hasattr(attr, "fget")
                               or hasattr(attr, "func")), name
