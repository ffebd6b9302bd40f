"""Exact resonances against closed forms and high-precision roots of the seed's eq. (7)."""

import math

import mpmath
import numpy as np
import pytest

import mechcirc
from reference import stb_eq7


def _chain(N, k=100.0, m=1.0):
    """Drive at d; d -k- n1 -k- ... -k- nN -k- frame; a mass m from each n_i to the frame."""
    lines = ["drive V d 0 velocity=1", f"spring k0 d n1 {k}"]
    for i in range(1, N + 1):
        lines.append(f"mass m{i} n{i} 0 {m}")
        lines.append(f"spring k{i} n{i} {f'n{i + 1}' if i < N else '0'} {k}")
    return mechcirc.parse("\n".join(lines))


@pytest.mark.parametrize("N", [1, 5, 40])
def test_spring_mass_chain_against_closed_forms(N):
    k, m = 100.0, 1.0
    found = _chain(N, k, m).resonances()
    j = np.arange(1, N + 1)
    # Drive held: fixed-fixed chain of N masses.  Released: fixed-free chain.
    held = 2 * math.sqrt(k / m) * np.sin(j * np.pi / (2 * (N + 1)))
    released = 2 * math.sqrt(k / m) * np.sin((2 * j - 1) * np.pi / (2 * (2 * N + 1)))
    res = np.array([r.omega for r in found if r.kind == "resonance"])
    anti = np.array([r.omega for r in found if r.kind == "antiresonance"])
    np.testing.assert_allclose(res, held, rtol=1e-10)
    np.testing.assert_allclose(anti, released, rtol=1e-10)
    assert all(r.zeta == 0 and r.omega_d == r.omega for r in found)
    assert all(r.error <= 1e-10 for r in found)


def test_thousand_element_chain():
    c = _chain(500)              # 1,001 elements
    found = c.resonances()
    assert len(found) == 1000
    j = np.arange(1, 501)
    held = 20 * np.sin(j * np.pi / 1002)
    np.testing.assert_allclose([r.omega for r in found if r.kind == "resonance"], held,
                               rtol=1e-10)


def _roots_in_omega_squared(poly, degree):
    """Roots x = ω² of a polynomial given as a function of ω, found in 60-digit arithmetic.

    The coefficients are recovered by interpolating at degree + 1 points exactly
    (a Vandermonde solve in mpmath), then mpmath.polyroots finds the roots.
    """
    with mpmath.workdps(60):
        xs = [mpmath.mpf(i + 1) * 1000 for i in range(degree + 1)]
        V = mpmath.matrix([[x ** p for p in range(degree, -1, -1)] for x in xs])
        y = mpmath.matrix([poly(mpmath.sqrt(x)) for x in xs])
        coeffs = mpmath.lu_solve(V, y)
        descending = [coeffs[i] for i in range(degree + 1)]
        try:        # mpmath >= 1.4 wants ascending order; 1.3 knows only descending
            roots = mpmath.polyroots(descending[::-1], maxsteps=200, extraprec=200, asc=True)
        except TypeError:
            roots = mpmath.polyroots(descending, maxsteps=200, extraprec=200)
        return sorted(float(mpmath.sqrt(r.real)) for r in roots if r.real > 0)


def test_stb_against_the_roots_of_eq_7():
    """Resonances are the zeros of eq. (7)'s numerator, anti-resonances of its denominator."""
    c = mechcirc.load("netlists/stb_heald.mcir")
    p = {k: float(v) for k, v in c.params.items() if k.startswith("eta")}
    values = {e.name: e.value for e in c.elements}
    p.update({k: v for k, v in values.items() if k.startswith("m")})
    p.update(k0=values["k0"], k4=values["k4"], k5=values["k5"])
    mp_p = {k: mpmath.mpf(v) for k, v in p.items()}

    def numerator(w):
        return stb_eq7.numerator(w, mp_p)

    def denominator(w):
        return stb_eq7.denominator(w, mp_p) / w

    zeros = _roots_in_omega_squared(numerator, 3)
    poles = _roots_in_omega_squared(denominator, 2)
    found = c.resonances()
    np.testing.assert_allclose([r.omega for r in found if r.kind == "resonance"], zeros,
                               rtol=1e-10)
    np.testing.assert_allclose([r.omega for r in found if r.kind == "antiresonance"], poles,
                               rtol=1e-10)


def test_damped_single_degree_of_freedom():
    m, k, c_ = 2.0, 5e4, 30.0
    circuit = mechcirc.parse(f"drive V a 0 velocity=1\nspring k a b {k}\n"
                             f"damper c a b {c_}\nmass m b 0 {m}\n")
    (res, anti) = circuit.resonances()
    wn = math.sqrt(k / m)
    zeta = c_ / (2 * math.sqrt(k * m))
    assert res.kind == "resonance"
    assert res.omega == pytest.approx(wn, rel=1e-10)
    assert res.zeta == pytest.approx(zeta, rel=1e-10)
    assert res.omega_d == pytest.approx(wn * math.sqrt(1 - zeta ** 2), rel=1e-10)
    # Released: spring and damper alone relax with s = -k/c (a real pole of K).
    assert anti.kind == "antiresonance" and anti.omega_d == 0
    assert anti.omega == pytest.approx(k / c_, rel=1e-10)


def test_hidden_mode_is_not_reported():
    # A mass-spring hanging off the frame side of the drive path is not seen from it.
    text = ("drive V a 0 velocity=1\nmass m a b 1\nspring k b 0 100\n"
            "mass hidden_m c 0 1\nspring hidden_k c 0 400\n")
    with pytest.warns(mechcirc.UnloadedElementWarning):
        found = mechcirc.parse(text).resonances()
    assert [(r.kind, round(r.omega, 9)) for r in found] == [("resonance", 10.0)]


def test_omega_max_limits_the_list():
    found = _chain(5).resonances(omega_max=10.0)
    assert found and all(r.omega <= 10.0 for r in found)
    assert len(found) < 10
