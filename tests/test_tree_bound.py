"""The reciprocal rule of the series–parallel error bound, ρ(1/x̂) ≤ ρ/(1 − ρ), and the
bound where that rule carries it: near the exact poles and zeros of lossless trees,
inner nodes whose sums cancel to ρ ≈ 1e-4 … 1, checked against K in mpmath at 40 digits
on the numpy path and on the compiled plan."""

from __future__ import annotations

import functools

import mpmath
import numpy as np
import pytest

from mechcirc import _jit, _tree_eval, reduction
from reference import sp_corpus as corpus

U = np.finfo(float).eps / 2


def test_reciprocal_rule_is_the_worst_case():
    # |x̂ − x| ≤ ρ|x̂| allows x = x̂(1 − ρ), where |1/x − 1/x̂| / |1/x̂| = ρ/(1 − ρ) exactly.
    rho = np.concatenate([np.geomspace(1e-17, 0.999, 400), [0.5, 0.9, 0.999999]])
    # The same rule from a sum's bound E and its magnitude A (ρ = E/A).
    E, A = rho * 3.7, np.full(rho.shape, 3.7)
    with np.errstate(all="ignore"):
        got = _tree_eval.through_reciprocal(rho)
        via_sum = _tree_eval._over_excess(E, A)
    with mpmath.workdps(40):
        worst = np.array([float(mpmath.mpf(r) / (1 - mpmath.mpf(r))) for r in rho])
        worst_sum = np.array([float(mpmath.mpf(e) / (mpmath.mpf(a) - mpmath.mpf(e)))
                              for e, a in zip(E, A)])
    # Two roundings of the bound's own arithmetic (measured: within 1u): the bound
    # is carried in float64; the 4u added at every reciprocal is far above this.
    assert np.all(got >= worst * (1 - 2 * U))
    assert np.all(via_sum >= worst_sum * (1 - 2 * U))
    assert np.all(got <= worst * (1 + 2 * U))     # and it is that bound, not looser
    # No digit known: from ρ = 1 on, and for NaN, the bound is infinite (or NaN, flagged).
    with np.errstate(all="ignore"):
        out = _tree_eval.through_reciprocal(np.array([1.0, 1.5, np.inf, np.nan]))
        out2 = _tree_eval._over_excess(np.array([3.7, 5.0, np.inf]), np.full(3, 3.7))
    assert np.all(np.isinf(out[:3])) and np.isnan(out[3])
    assert np.all(np.isinf(out2))


@functools.lru_cache(maxsize=1)
def _near_critical_points():
    """Lossless random trees at 1e-9 … 3e-15 relative distance of their exact poles and
    zeros, with K at 40 digits (computed once)."""
    rng = np.random.default_rng(2611)
    cases = []
    for _ in range(8):
        expr = corpus.random_tree(rng, int(rng.integers(8, 40)), damped=0.0)
        crit = corpus.critical_points(expr, 1e-3, 1e3, 40)[:3]
        omega = np.array([w * (1 + d) for w in crit for d in (1e-9, -1e-11, 1e-13, 3e-15)])
        if omega.size:
            cases.append((corpus.to_circuit(expr), omega, corpus.reference(expr, omega)))
    return cases


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_bound_holds_where_inner_sums_cancel(path):
    if path == "compiled":
        pytest.importorskip("numba")
    saved = _jit.COMPILED
    _jit.COMPILED = path == "compiled"
    try:
        est, true = [], []
        for c, omega, ref in _near_critical_points():
            K, rho = reduction.evaluate(c.tree, omega, error=True)
            est.append(rho)
            true.append(corpus.true_error(K, ref))
    finally:
        _jit.COMPILED = saved
    est, true = np.concatenate(est), np.concatenate(true)
    fin = np.isfinite(est)
    # The cases reach the range where the reciprocal rule matters (measured: 29 of
    # 48 points with a bound above 1e-4, 31 true errors above 1e-6, up to 3.9e-2).
    assert np.count_nonzero(fin & (est > 1e-4)) >= 20
    assert np.count_nonzero(true > 1e-6) >= 20
    # A true bound everywhere; measured margin 7.7 (the least bound / true error where
    # the true error exceeds one rounding, both paths), asserted ≥ 2.
    assert np.all(est[fin] >= true[fin])
    big = fin & (true > U)
    assert np.min(est[big] / true[big]) >= 2.0


def _ladder_at_an_inner_zero():
    """A lossless 60-rung ladder whose innermost sum k + m (spring and mass in series)
    is zero at ω₀ = √(k/m): within a few ulps of ω₀ its bound E exceeds the computed
    |Ŝ| > 0, 119 terms 1/S below the root; then 3 points away from it."""
    rng = np.random.default_rng(26)
    expr = corpus.ladder(rng, 120, r=None)
    inner = expr
    while inner[1][1][0] == "p":               # ("s", [spring, ("p", [mass, inner])])
        inner = inner[1][1][1][1]
    (_, _, k), (_, _, m) = inner[1]
    w0 = float(np.sqrt(k / m))
    near = w0 * (1 + np.arange(-10, 11) * 1e-16)
    omega = np.concatenate([near, [w0 * (1 - 1e-3), w0 * (1 + 1e-3), 10.0 * w0]])
    return expr, corpus.to_circuit(expr), omega


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_a_sum_with_no_digit_known_makes_the_bound_infinite(monkeypatch, path):
    # (the compiled plan forms a term 1/S of the bound as E + c(|Ŝ| − E) over
    # |Ŝ|(|Ŝ| − E), one division, and takes ρ/(1 − ρ) where that product is not in
    # [1e-300, 1e300]: here |Ŝ| − E goes to 0 and below it)
    if path == "compiled":
        pytest.importorskip("numba")
    monkeypatch.setattr(_jit, "COMPILED", path == "compiled")
    expr, c, omega = _ladder_at_an_inner_zero()
    K, rho = reduction.evaluate(c.tree, omega, error=True)
    # Near ω₀ no digit of the inner sum is known: the bound is ∞ (the rule
    # ρ(1/x̂) = ρ/(1 − ρ), ∞ from ρ ≥ 1 on), although K is finite there.  (Without
    # the clamp of |Ŝ| − E at 0, 19 of these 21 points get a finite 2.8e-13 …
    # 2.9e-13 at the root, the term E/(|Ŝ| − E) being negative; the other two
    # reach ∞ through Ŝ = 0 by themselves.)
    assert np.isfinite(K).all()
    assert np.all(rho[:21] == np.inf)
    # Away from it a finite bound of the true error (mpmath, 40 digits).
    true = corpus.true_error(K[21:], corpus.reference(expr, omega[21:]))
    assert np.all(np.isfinite(rho[21:])) and np.all(rho[21:] >= true)
    assert np.all(rho[21:] < 1e-11)           # measured 7.9e-16 … 6.3e-13


def test_one_point_has_the_bound_of_an_array_of_one(monkeypatch):
    monkeypatch.setattr(_jit, "COMPILED", False)
    _, c, omega = _ladder_at_an_inner_zero()
    K1, rho1 = reduction.evaluate(c.tree, omega[:1], error=True)
    K0, rho0 = reduction.evaluate(c.tree, np.float64(omega[0]), error=True)
    assert K0.shape == rho0.shape == ()
    assert K0 == K1[0] and rho0 == rho1[0]


@pytest.mark.parametrize("chunk", [None, 7])
def test_a_sweep_with_error_has_the_numbers_of_error_asked_afterwards(monkeypatch, chunk):
    # sweep(error=True) takes K and its bound from one pass over the tree; the
    # Sweep asked for its error afterwards evaluates the tree again.  The same
    # numbers either way, also in chunks of ω (7 points: 11 = 7 + 4).
    from mechcirc import _sweep

    if chunk is not None:
        monkeypatch.setattr(_sweep, "CHUNK_POINTS", chunk)
    monkeypatch.setattr(_jit, "COMPILED", False)
    _, c, omega = _ladder_at_an_inner_zero()
    omega = np.concatenate([[0.0], omega[:21:4], omega[21:], [np.inf]])   # 0 and ∞ too
    one = c.sweep(omega, error=True)
    assert "error" in one._cache                  # computed with K, not afterwards
    two = c.sweep(omega)
    assert "error" not in two._cache
    np.testing.assert_array_equal(one.K, two.K)
    np.testing.assert_array_equal(one.error, two.error)
    np.testing.assert_array_equal(one.flags, two.flags)
    assert np.isinf(one.error).sum() >= 2 and np.isfinite(one.error).sum() >= 3


@pytest.mark.parametrize("scale", [1e200, 1e-200])
def test_compiled_bound_where_a_square_would_overflow_or_underflow(monkeypatch, scale):
    # The compiled plan forms |S| = √(a² + b²) without a branch and redoes with hypot
    # the points whose larger part is outside [1e-150, 1e150]; here every sum is there
    # (its squares are ∞ or 0): the bound is the numpy path's and holds against mpmath.
    pytest.importorskip("numba")
    omega = np.array([0.5, 1.0, 3.0])
    # damper 1/c and spring jω/k of one size (scale), a lever and a mass around them
    expr = ("p", [("s", [("leaf", "damper", 1 / scale), ("leaf", "spring", 1 / scale)]),
                  ("lever", 2.0, ("s", [("leaf", "damper", 2 / scale),
                                        ("leaf", "spring", 3 / scale)]))])
    c = corpus.to_circuit(expr)
    monkeypatch.setattr(_jit, "COMPILED", True)
    K1, r1 = reduction.evaluate(c.tree, omega, error=True)
    monkeypatch.setattr(_jit, "COMPILED", False)
    K0, r0 = reduction.evaluate(c.tree, omega, error=True)
    assert np.all(np.isfinite(r1)) and np.all(r1 > 0)
    np.testing.assert_allclose(K1, K0, rtol=2e-14, atol=0)
    np.testing.assert_allclose(r1, r0, rtol=1e-12)
    true = corpus.true_error(K1, corpus.reference(expr, omega))
    assert np.all(r1 >= true)
