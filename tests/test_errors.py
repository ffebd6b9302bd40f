"""Every exception and warning class lives in mechcirc/errors.py, under one base."""

import ast
import inspect
from pathlib import Path

from package_source import package_trees, statements

import mechcirc
from mechcirc import errors

PACKAGE = Path(mechcirc.__file__).resolve().parent


def test_errors_form_one_tree():
    classes = [c for _, c in inspect.getmembers(errors, inspect.isclass)
               if c.__module__ == errors.__name__]
    assert len(classes) > 10
    for c in classes:
        assert issubclass(c, (errors.MechcircError, errors.MechcircWarning)), c
    # Beside the classes, errors.py exports how messages quote user text and name the
    # nearest of the names there are.
    assert set(errors.__all__) == {c.__name__ for c in classes} | {
        "MAX_QUOTED", "clip", "shorten", "did_you_mean", "unknown_name"}
    assert issubclass(errors.UnitError, ValueError)            # callers may catch either


def test_no_public_exception_class_outside_errors_py():
    """Private ones may stay where they are raised and caught (study's _SpecError becomes a
    NetlistError in its module); BaseException subclasses are control flow (the CLI's
    SIGTERM unwinding), not errors."""
    found = []
    for path, tree in package_trees().items():
        if path.name == "errors.py":
            continue
        for node in statements(tree):
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                bases = [ast.unparse(b).rpartition(".")[2] for b in node.bases]
                if any(b.endswith(("Error", "Warning", "Exception")) and b != "BaseException"
                       for b in bases):
                    found.append(f"{path.relative_to(PACKAGE)}: {node.name}")
    assert found == []


def test_old_import_locations_still_work():
    from mechcirc.scene.simulation import SceneAccuracyWarning
    from mechcirc import BandError
    from mechcirc.sley import ParameterError
    from mechcirc.sley.simulation import SleyAccuracyWarning
    from mechcirc.units import UnitError

    assert (BandError, ParameterError, UnitError, SceneAccuracyWarning, SleyAccuracyWarning) \
        == (errors.BandError, errors.ParameterError, errors.UnitError,
            errors.SceneAccuracyWarning, errors.SleyAccuracyWarning)
