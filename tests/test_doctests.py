"""The examples in the package's docstrings run and print what they show (doctest).

pytest's ``--doctest-modules`` would need the package in ``testpaths`` and
would import every module, including those of optional extras; this file
walks the package instead and skips a module only when an optional
dependency it needs is not installed.  Every module is walked, the command
line's included (only ``__main__`` is not imported: it runs the CLI).
"""

import doctest
import importlib
import pkgutil

import pytest

import mechcirc

OPTIONAL = {"numba", "dask", "distributed", "sympy", "pyarrow", "pandas"}


def _modules():
    names = ["mechcirc"]
    for info in pkgutil.walk_packages(mechcirc.__path__, "mechcirc."):
        if info.name.endswith("__main__"):     # importing it would run the command line
            continue
        names.append(info.name)
    return names


@pytest.mark.parametrize("name", _modules())
def test_docstring_examples(name):
    try:
        module = importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name and exc.name.split(".")[0] in OPTIONAL:
            pytest.skip(f"optional dependency {exc.name} not installed")
        raise
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = [t for t in finder.find(module, name) if t.examples]
    report = []
    for test in tests:
        if test.filename and not test.filename.endswith(".py"):
            continue
        runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)


def test_every_module_is_walked():
    """The walk reaches the subpackages and the modules that hold examples."""
    names = set(_modules())
    for name in ("mechcirc.cli", "mechcirc.cli._common", "mechcirc._sweep", "mechcirc.units",
                 "mechcirc.interop.formula", "mechcirc.kinematics.fourbar",
                 "mechcirc.sley.simulation", "mechcirc.scene", "mechcirc.transient"):
        assert name in names, name


def test_public_index():
    """The API map's names exist, and mechcirc.sweep / .simplify are the functions."""
    import types

    import mechcirc._simplify  # noqa: F401  (importing the private module keeps the function)
    from mechcirc import parse_band

    for name in mechcirc.__all__:
        assert getattr(mechcirc, name) is not None, name
    assert isinstance(mechcirc.sweep, types.FunctionType)
    assert isinstance(mechcirc.simplify, types.FunctionType) and parse_band
    assert mechcirc.find_resonances.__module__ == "mechcirc.resonances"
    assert issubclass(mechcirc.NotSeriesParallelError, mechcirc.TopologyError)
    c = mechcirc.parse("mass m a 0 2\nspring k a 0 800\ndrive V a 0 velocity=1\n")
    assert mechcirc.sweep(c, [10.0]).K[0] == c.sweep([10.0]).K[0]
    assert [r.omega for r in mechcirc.find_resonances(c)] == [r.omega for r in c.resonances()]
    for name in mechcirc.__all__:
        assert name in mechcirc.__doc__, name
