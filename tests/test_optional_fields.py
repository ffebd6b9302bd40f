"""Optional fields the type annotations now spell out: a circuit read without a drive,
a Sweep built by hand without its tree or circuit."""
import numpy as np
import pytest

from mechcirc import parse
from mechcirc._sweep import Sweep
from mechcirc.batch import designs
from mechcirc.errors import InputError, NetlistError
from mechcirc.explain import explain_lines
from mechcirc.modes import sweep_sensitivity

NET = "mass m1 a 0 1\nspring k1 a 0 10\n"


def test_driveless_circuit_prints_and_lists_its_nodes():
    c = parse(NET, require_drive=False)
    assert c.drive is None
    assert repr(c) == "<Circuit 'circuit': 1 mass, 1 spring; no drive>"
    assert c.nodes == ["0", "a"]


def test_driven_circuit_lists_the_drive_nodes():
    c = parse(NET + "drive V b 0 velocity=1\nspring k2 b a 5\n")
    assert c.nodes == ["0", "a", "b"]
    assert repr(c).endswith("velocity drive 'V' 1 between 'b' and '0'>")


@pytest.mark.parametrize("method, missing", [("sp", "reduction tree"), ("nodal", "circuit")])
def test_hand_built_sweep_without_its_source_says_so(method, missing):
    c = parse(NET + "drive V a 0 velocity=1\n")
    s = Sweep(np.array([1.0, 2.0]), np.array([0.1j, 0.2j]), c.drive, method)
    with pytest.raises(InputError, match=f"without its {missing}"):
        s.force("m1")
    with pytest.raises(InputError, match=f"without its {missing}"):
        _ = s.error


def _no_drive(call):
    c = parse(NET, require_drive=False, source="free.net")
    with pytest.raises(NetlistError, match="has no drive") as info:
        call(c)
    assert info.value.source == "free.net"


@pytest.mark.parametrize("call", [
    lambda c: c.sweep([1.0, 2.0], method="sp"),
    lambda c: c.sweep([1.0, 2.0], method="nodal"),
    lambda c: c.resonances(),
    lambda c: c.tree,
    lambda c: explain_lines(c),
    lambda c: sweep_sensitivity(c, [1.0]),
    lambda c: designs(c).sweep([1.0]),
], ids=["sweep-sp", "sweep-nodal", "resonances", "tree", "explain", "sensitivity",
        "designs"])
def test_analyses_seen_from_the_drive_name_the_missing_drive(call):
    # A circuit read with require_drive=False: every analysis that needs the drive
    # fails with a located NetlistError, not an AttributeError on None.
    _no_drive(call)


def test_require_drive_returns_the_drive():
    c = parse(NET + "drive V a 0 force=2\n")
    assert c.require_drive() is c.drive
    assert c.require_drive().amplitude == 2.0


def test_designs_from_circuits_name_the_missing_drive():
    from mechcirc.batch import from_circuits

    _no_drive(lambda c: from_circuits([c, c]))
