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
