"""The analysis methods of Circuit and Sweep: one-line delegates written in their classes."""

import pydoc
import re
import warnings

import pytest

import mechcirc
from mechcirc import Circuit, Sweep

CLASSES = {"Circuit": Circuit, "Sweep": Sweep}
METHODS = {"Circuit": ("tree", "unloaded", "nodal", "sweep", "resonances", "two_port",
                       "formula"),
           "Sweep": ("to_skrf",)}
PAIRS = [(cls, name) for cls, names in METHODS.items() for name in names]


def _function(attr):
    return getattr(attr, "fget", getattr(attr, "func", attr))


@pytest.mark.parametrize("cls", CLASSES)
def test_every_method_is_written_in_its_class(cls):
    """Nothing is attached from another module (no setattr at import)."""
    obj = CLASSES[cls]
    for name, attr in vars(obj).items():
        func = _function(attr)
        if callable(func) and hasattr(func, "__qualname__") and not name.startswith("__"):
            assert func.__module__ == obj.__module__, (name, func.__module__)
            assert func.__qualname__ == f"{cls}.{name}", (name, func.__qualname__)


@pytest.mark.parametrize("cls,name", PAIRS)
def test_method_is_documented_and_listed(cls, name):
    obj = CLASSES[cls]
    func = _function(vars(obj)[name])
    assert (func.__doc__ or "").strip(), f"{cls}.{name} has no docstring"
    # help(Circuit) shows it with its docstring's first line
    text = pydoc.render_doc(obj, renderer=pydoc.plaintext)
    assert re.search(rf"\b{name}\b", text)
    assert func.__doc__.strip().splitlines()[0][:30] in text
    # the package index names it as .name
    assert re.search(rf"\.{name}\b", mechcirc.__doc__), f"{cls}.{name} not in mechcirc's index"
    if cls == "Circuit":
        assert f"``{name}``" in Circuit.__doc__


def test_a_warning_points_at_the_callers_line():
    """UnloadedElementWarning from ``c.tree`` / ``c.sweep`` / ``c.resonances()`` names this
    file and line."""
    text = "drive V a 0 velocity=1\nmass m a 0 1\nspring k a 0 100\nmass lone x y 2\n"
    for use in (lambda c: c.tree, lambda c: c.sweep([1.0, 2.0]), lambda c: c.resonances()):
        c = mechcirc.parse(text)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            line = use.__code__.co_firstlineno
            use(c)
        hits = [w for w in caught if issubclass(w.category, mechcirc.UnloadedElementWarning)]
        assert hits and all((w.filename, w.lineno) == (__file__, line) for w in hits), \
            [(w.filename, w.lineno) for w in hits]
