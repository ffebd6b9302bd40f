"""mechcirc.circuit: the one table of element laws and what derives from it.

References are the laws written out by hand here (DIGEST §1: mass K = −j/(ωmη),
spring jω/(kη), damper 1/(cη)), independent of the table under test.
"""

import numpy as np
import pytest

import mechcirc
from mechcirc.circuit import ELEMENT_UNITS, LAWS, Element, element_mobility
from mechcirc.explain import explain_lines

OMEGA = np.array([1e-3, 0.37, 1.0, 12.5, 3e4])
HAND = {"mass": lambda w, s: -1j / (w * s),
        "spring": lambda w, s: 1j * w / s,
        "damper": lambda w, s: 1.0 / s + 0j * w}


@pytest.mark.parametrize("kind", ["mass", "spring", "damper"])
def test_element_mobility_is_the_law_written_by_hand(kind):
    for s in (2.0, 0.125, 7.3e5):
        np.testing.assert_allclose(element_mobility(kind, s, OMEGA), HAND[kind](OMEGA, s),
                                   rtol=1e-15, atol=0)
    e = Element(kind, "x", "a", "0", 3.0, eta=0.25)
    np.testing.assert_allclose(e.mobility(OMEGA), HAND[kind](OMEGA, 0.75), rtol=1e-15)


def test_table_says_where_each_law_stamps_and_its_unit():
    # S = 1/K = s·(jω)^(−p): jωm in M, c in G, k/(jω) in K of A = G + j(ωM − K/ω).
    assert {k: (law.power, law.matrix) for k, law in LAWS.items()} == {
        "mass": (-1, "M"), "spring": (1, "K"), "damper": (0, "G")}
    assert ELEMENT_UNITS == {"mass": "kg", "spring": "N/m", "damper": "N·s/m"}


def test_limits_at_zero_frequency_are_exact():
    w = np.array([0.0])
    assert element_mobility("mass", 2.0, w)[0] == complex(0, -np.inf)
    assert element_mobility("spring", 2.0, w)[0] == 0
    with pytest.raises(ValueError, match="unknown element kind"):
        element_mobility("inerter", 1.0, w)


def test_explain_text_reads_the_law_of_each_element():
    c = mechcirc.parse("drive V a 0 velocity=1\nmass m a 0 2 eta=0.5\n"
                       "spring k a b 800\ndamper c b 0 4\n")
    text = "\n".join(explain_lines(c))
    assert "K = -j/(1·ω)" in text            # m·η = 1
    assert "K = jω/800" in text
    assert "K = 1/4" in text


def test_symbolic_leaf_evaluates_to_the_law():
    sympy = pytest.importorskip("sympy")
    from mechcirc.interop.formula import formula

    for kind in ("mass", "spring", "damper"):
        c = mechcirc.parse(f"drive V a 0 velocity=1\n{kind} x a 0 2.5 eta=0.4\n")
        expr = formula(c, numeric=True)
        f = sympy.lambdify(sympy.Symbol("omega", positive=True), expr, "numpy")
        np.testing.assert_allclose(np.asarray(f(OMEGA), dtype=complex) * np.ones_like(OMEGA),
                                   HAND[kind](OMEGA, 1.0), rtol=1e-15)
