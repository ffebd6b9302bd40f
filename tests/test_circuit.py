"""The element laws (``circuit.law_terms``, ``element_mobility``, ``Lever.reflect``)
against the closed forms of DIGEST §1 written out here."""

import numpy as np
import pytest

from mechcirc.circuit import ELEMENT_POWER, Lever, element_mobility, law_terms

OMEGA = np.array([0.3, 1.0, 17.0, 4e3])


@pytest.mark.parametrize("kind, K", [
    ("mass", lambda w, s: -1j / (w * s)),
    ("spring", lambda w, s: 1j * w / s),
    ("damper", lambda w, s: (1 / s) * np.ones_like(w) + 0j),
])
def test_laws_are_the_closed_forms(kind, K):
    s = 2.5
    real, inv, om = law_terms(kind, np.float64(s))
    np.testing.assert_allclose(real + 1j * (inv / OMEGA + om * OMEGA), K(OMEGA, s), rtol=1e-15)
    # The admittance form is the reciprocal.
    real, inv, om = law_terms(kind, np.float64(s), admittance=True)
    np.testing.assert_allclose(real + 1j * (inv / OMEGA + om * OMEGA), 1 / K(OMEGA, s),
                               rtol=1e-15)
    np.testing.assert_allclose(element_mobility(kind, s, OMEGA), K(OMEGA, s), rtol=1e-15)
    assert sum(t != 0 for t in law_terms(kind, np.float64(s))) == 1
    assert set(ELEMENT_POWER) == {"mass", "spring", "damper"}


def test_limits_without_warnings():
    with np.errstate(all="raise"):
        K = element_mobility("mass", 2.0, np.array([0.0]))
        assert K[0].imag == -np.inf and K[0].real == 0       # −j∞, not nan + ∞j
        assert element_mobility("spring", 2.0, np.array([0.0]))[0] == 0


def test_unknown_kind_is_refused():
    with pytest.raises(ValueError, match="unknown element kind"):
        law_terms("inerter", 1.0)


def test_lever_reflects_by_the_square_of_its_ratio_without_overflow():
    lv = Lever("L", "p", "0", "s", "0", 1e200)
    assert lv.reflect(1e300) == pytest.approx(1e-100, rel=1e-15)   # r² alone overflows
    assert Lever("L", "p", "0", "s", "0", 3.0).reflect(9.0) == pytest.approx(1.0, rel=1e-15)
