"""Closed-form K(ω) from the reduction tree, against the seed's eq. (7) written independently."""

import inspect
import random
import sys
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from reference.stb_eq7 import denominator, numerator

sp = pytest.importorskip("sympy")

from mechcirc.interop.formula import formula, symbol_values  # noqa: E402
from bounds import cpu_seconds_below
from cli_helpers import assert_user_error
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]
NAMES = [f"m{i}" for i in range(1, 13)] + ["k0", "k4", "k5", "eta1", "eta2", "eta3", "eta4"]


def is_zero_polynomial(expr) -> bool:
    """Whether the polynomial ``expr`` (numbers in Q(i), its symbols the variables) is 0.

    Built term by term in sympy's sparse polynomial ring over the Gaussian rationals
    (``PolyRing.from_expr``: sums and products of exact dicts of monomials), so the
    answer is exact, as ``sympy.expand(expr) == 0`` was, in about a twentieth of its
    CPU (the identities below: 0.05-0.07 s against 0.95-1.24 s).  Anything not a
    polynomial in the symbols is a ValueError, never a zero.
    """
    from sympy.polys.domains import QQ_I
    from sympy.polys.rings import ring

    R, *_ = ring(sorted(expr.free_symbols, key=str), QQ_I)
    return R.from_expr(expr) == 0


@pytest.fixture(scope="module")
def stb():
    F = formula(mechcirc.load(STB))
    S = {s.name: s for s in F.free_symbols}
    assert set(S) == set(NAMES) | {"omega"}       # etaB, etaC resolved into eta1..eta3
    p = {n: S[n] for n in NAMES}
    K7 = sp.I * numerator(S["omega"], p) / denominator(S["omega"], p)
    return F, K7, S


def test_stb_formula_is_eq7_symbolically(stb):
    """With η4 = 1 (the paper's value and the netlist's) the difference is identically 0.

    All 18 other parameters and ω stay symbols: one fraction, numerator
    multiplied out, must be the zero polynomial.
    """
    F, K7, S = stb
    diff = (F - K7).subs(S["eta4"], 1)
    num, _ = sp.fraction(sp.together(diff))
    assert is_zero_polynomial(num)


def test_stb_formula_differs_from_eq7_when_eta4_is_not_1(stb):
    # The netlist puts η4 on m9, m10, m12 and k0 (its reading of Fig. 3); eq. (7)
    # has η4 only in k0·η4 terms.  They agree at the paper's η4 = 1, and the test
    # must be able to see that they differ elsewhere, or the proof above proves
    # nothing.  (sympy.factor of the difference's numerator has the factors η4,
    # η4 − 1 and m9 − m11.)
    F, K7, S = stb
    rng = random.Random(1)
    point = {S[n]: sp.Rational(rng.randint(2, 90), 7) for n in NAMES}
    point[S["m9"]], point[S["m11"]] = sp.Rational(2, 5), sp.Rational(1, 2)   # must differ
    point[S["eta4"]] = sp.Rational(3, 2)
    point[S["omega"]] = sp.Rational(37)
    assert sp.nsimplify(F.subs(point) - K7.subs(point)) != 0


def test_stb_formula_equals_eq7_at_random_rational_points(stb):
    """Exact values at two random rational points, by substitution (a second route to the
    identity proven symbolically above: there every point with η4 = 1 is covered, so
    more points here would check the same path again; five cost 1.5 s of CPU)."""
    F, K7, S = stb
    rng = random.Random(6)
    for _ in range(2):
        point = {S[n]: sp.Rational(rng.randint(1, 400), rng.randint(1, 40)) for n in NAMES}
        point[S["eta4"]] = 1
        point[S["omega"]] = sp.Rational(rng.randint(1, 5000), rng.randint(1, 7))
        assert sp.simplify(F.subs(point) - K7.subs(point)) == 0


def test_formula_values_give_the_sweep():
    c = mechcirc.load(STB)
    F = formula(c, numeric=True)
    f = sp.lambdify(sp.Symbol("omega", positive=True), F, "numpy")
    omega = np.array([50.0, 500.0, 2500.0])
    np.testing.assert_allclose(f(omega), c.sweep(omega).K, rtol=1e-12)
    values = symbol_values(c)
    assert values[sp.Symbol("eta1", positive=True)] == sp.Rational(4, 5)
    assert values[sp.Symbol("k4", positive=True)] == 2_000_000


def test_expand_is_the_same_function_as_one_fraction():
    c = mechcirc.load(STB)
    nested, flat = formula(c), formula(c, expand=True)
    num, den = sp.fraction(flat)
    omega = sp.Symbol("omega", positive=True)
    assert num.is_polynomial(omega) and den.is_polynomial(omega)
    assert is_zero_polynomial(sp.fraction(sp.together(nested - flat))[0])


def test_lever_and_damper():
    c = mechcirc.parse(".param r=0.5\nmass m a 0 2\nlever L a 0 b 0 ratio=r\n"
                       "damper c b 0 30\ndrive V a 0 velocity=1\n")
    F = formula(c)
    w, m, r, cc = (sp.Symbol(n, positive=True) for n in ("omega", "m", "r", "c"))
    # primary: mass m in parallel with the damper seen through the lever, K = (1/c)/r²
    expected = 1 / (sp.I * w * m + cc * r**2)
    assert sp.simplify(F - expected) == 0


def test_formula_cli(capsys):
    assert cli.main(["formula", str(STB), "--latex"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("K(\\omega) = ") and "\\eta_{1}^{2}" in out and "eta1 = 4/5" in out
    assert cli.main(["formula", str(STB), "--numeric", "--expand"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("K(omega) = (") and "where" not in out


def test_bridge_without_a_tree_comes_from_the_nodal_equations():
    c = mechcirc.parse("spring k1 a b 1\nspring k2 a c 2\nspring k3 b c 3\nspring k4 b 0 4\n"
                       "spring k5 c 0 5\nmass m a 0 1\ndrive V a 0 velocity=1\n")
    F = formula(c)
    w, m, g1, g2, g3, g4, g5 = (sp.Symbol(n, positive=True)
                                for n in ("omega", "m", "k1", "k2", "k3", "k4", "k5"))
    # Equivalent stiffness of a bridge a-b (g1), a-c (g2), b-c (g3), b-0 (g4), c-0 (g5),
    # the textbook formula for a bridge's conductance (Y-Δ free form).
    k_eq = (g1 * g2 * (g4 + g5) + g4 * g5 * (g1 + g2) + g3 * (g1 + g2) * (g4 + g5)) / \
        ((g1 + g4) * (g2 + g5) + g3 * (g1 + g2 + g4 + g5))
    expected = 1 / (sp.I * w * m + k_eq / (sp.I * w))
    assert is_zero_polynomial(sp.fraction(sp.together(F - expected))[0])


def _ladder(n):
    lines = ["drive V n0 0 velocity=1"]
    for i in range(n):
        lines += [f"mass m{i} n{i} n{i + 1} 1", f"spring k{i} n{i + 1} 0 100"]
    return mechcirc.parse("\n".join(lines))


def test_deep_trees_are_refused_with_a_reason(capsys):
    from mechcirc.errors import MechcircError
    from mechcirc.interop.formula import MAX_TREE_DEPTH

    with pytest.raises(MechcircError, match=r"66 levels deep; formulas are built up to 64"):
        formula(_ladder(MAX_TREE_DEPTH // 2 + 1))     # depth 2n
    F = formula(_ladder(MAX_TREE_DEPTH // 2))        # the deepest accepted
    # prints with a cold SymPy cache in 600 frames above this one, so a caller
    # deep in a notebook or a test runner under coverage still has ~400 left of
    # Python's default 1,000 (measured: about 470 frames at 64 levels)
    limit = sys.getrecursionlimit()
    sp.core.cache.clear_cache()
    sys.setrecursionlimit(len(inspect.stack(0)) + 600)
    try:
        assert str(F) and sp.latex(F)
    finally:
        sys.setrecursionlimit(limit)


def test_formula_on_a_large_network_without_a_tree_is_refused_at_once(tmp_path, capsys):
    pytest.importorskip("sympy")
    lines = ["drive V n0_0 0 velocity=1"]
    k = 0
    for i in range(3):
        for j in range(3):
            n = f"n{i}_{j}"
            if j < 2:
                lines.append(f"spring k{k} {n} n{i}_{j + 1} {100 + k}")
                k += 1
            if i < 2:
                lines.append(f"damper c{k} {n} n{i + 1}_{j} {1 + k}")
                k += 1
            lines.append(f"mass m{k} {n} 0 {1 + k}")
            k += 1
    path = tmp_path / "grid.mcir"
    path.write_text("\n".join(lines) + "\n")
    with cpu_seconds_below(10):
        assert_user_error(["formula", path], capsys, "21 elements", "--method nodal")


def test_formula_bridge_by_cramer_matches_a_numeric_solve():
    """The determinant form equals K from an independent dense complex solve at sampled ω."""
    sp = pytest.importorskip("sympy")
    import numpy as np

    import mechcirc
    from mechcirc.interop.formula import formula_and_values

    text = ("spring k1 a b 1000\nspring k2 a c 2000\ndamper c3 b c 5\nmass m4 b 0 1\n"
            "mass m5 c 0 2\nspring k6 c 0 300\ndrive V a 0 velocity=1\n")
    K, values = formula_and_values(mechcirc.parse(text))
    f = sp.lambdify(sp.Symbol("omega", positive=True), K.subs(values), "numpy")
    for w in (0.7, 13.0, 55.5, 400.0):
        # Nodal admittance (velocity drive: unit velocity at a; K = v/Q = 1/Q):
        # unknown node velocities b, c; force at a from the elements at a.
        yk = lambda k: k / (1j * w)                                     # noqa: E731
        A = np.array([[yk(1000) + 5 + 1j * w * 1, -5],
                      [-5, yk(2000) + 5 + 1j * w * 2 + yk(300)]])
        rhs = np.array([yk(1000), yk(2000)])
        vb, vc = np.linalg.solve(A, rhs)
        Q = yk(1000) * (1 - vb) + yk(2000) * (1 - vc)
        assert abs(complex(f(w)) - 1 / Q) <= 1e-12 * abs(1 / Q)
