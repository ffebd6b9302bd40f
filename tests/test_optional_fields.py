"""Optional fields the type annotations now spell out: a circuit read without a drive,
a Sweep built by hand without its tree or circuit."""
import numpy as np
import pytest

from mechcirc import parse
from mechcirc._sweep import Sweep
from mechcirc.errors import InputError

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
