"""mechcirc.circuit: the one table of element laws and what derives from it.

References are the laws written out by hand here (Grigoriev et al. 2002: mass K = −j/(ωmη),
spring jω/(kη), damper 1/(cη)), independent of the table under test.
"""

import numpy as np
import pytest

import mechcirc
from mechcirc.circuit import ELEMENT_UNITS, LAWS, Element, Lever, element_mobility, law_terms
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
    assert {k: law.power for k, law in LAWS.items()} == {"mass": -1, "spring": 1, "damper": 0}
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


def test_nodes_frame_first_then_in_order_of_appearance():
    from mechcirc.circuit import node_names
    from mechcirc.topology import node_names as topology_node_names

    c = mechcirc.parse("drive V d 0 velocity=1\nmass m a 0 1\nspring k b a 2\n"
                       "lever L a 0 c 0 ratio=2\ndamper x c 0 1\n")
    assert node_names(c.elements, c.levers) == ["a", "0", "b", "c"]
    assert c.nodes == ["0", "a", "b", "c", "d"]
    assert topology_node_names is node_names


# law_terms (the form the series–parallel reduction sums) and Lever.reflect

@pytest.mark.parametrize("kind, K", [
    ("mass", lambda w, s: -1j / (w * s)),
    ("spring", lambda w, s: 1j * w / s),
    ("damper", lambda w, s: (1 / s) * np.ones_like(w) + 0j),
])
def test_law_terms_are_the_closed_forms(kind, K):
    s = 2.5
    real, inv, om = law_terms(kind, np.float64(s))
    np.testing.assert_allclose(real + 1j * (inv / OMEGA + om * OMEGA), K(OMEGA, s), rtol=1e-15)
    # The admittance form is the reciprocal.
    real, inv, om = law_terms(kind, np.float64(s), admittance=True)
    np.testing.assert_allclose(real + 1j * (inv / OMEGA + om * OMEGA), 1 / K(OMEGA, s),
                               rtol=1e-15)
    np.testing.assert_allclose(element_mobility(kind, s, OMEGA), K(OMEGA, s), rtol=1e-15)
    assert sum(t != 0 for t in law_terms(kind, np.float64(s))) == 1


def test_limits_without_floating_point_warnings():
    with np.errstate(all="raise"):
        K = element_mobility("mass", 2.0, np.array([0.0]))
        assert K[0].imag == -np.inf and K[0].real == 0       # −j∞, not nan + ∞j
        assert element_mobility("spring", 2.0, np.array([0.0]))[0] == 0


def test_law_terms_refuse_an_unknown_kind():
    with pytest.raises(ValueError, match="unknown element kind"):
        law_terms("inerter", 1.0)


def test_lever_reflects_by_the_square_of_its_ratio_without_overflow():
    lv = Lever("L", "p", "0", "s", "0", 1e200)
    assert lv.reflect(1e300) == pytest.approx(1e-100, rel=1e-15)   # r² alone overflows
    assert Lever("L", "p", "0", "s", "0", 3.0).reflect(9.0) == pytest.approx(1.0, rel=1e-15)
