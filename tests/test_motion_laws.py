"""Cam motion laws and tables (mechcirc.motion_laws) against closed forms,
sympy integrations, finite differences, quadrature and textbook coefficients."""

import itertools
import math
import pickle

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import quad

from mechcirc.errors import NetlistError
from mechcirc.motion_laws import LAWS, cam_cycle, law, motion_table, read_motion_table

U = np.linspace(0.0, 1.0, 20001)


def test_closed_forms_of_the_simple_laws():
    u = U
    refs = {
        "harmonic": ((1 - np.cos(np.pi * u)) / 2, np.pi / 2 * np.sin(np.pi * u),
                     np.pi ** 2 / 2 * np.cos(np.pi * u)),
        "cycloidal": (u - np.sin(2 * np.pi * u) / (2 * np.pi), 1 - np.cos(2 * np.pi * u),
                      2 * np.pi * np.sin(2 * np.pi * u)),
        "polynomial_345": (10 * u ** 3 - 15 * u ** 4 + 6 * u ** 5,
                           30 * u ** 2 - 60 * u ** 3 + 30 * u ** 4,
                           60 * u - 180 * u ** 2 + 120 * u ** 3),
    }
    for name, ref in refs.items():
        for got, want in zip(law(name, u), ref):
            assert np.max(np.abs(got - want)) <= 1e-13 * max(1.0, np.max(np.abs(want))), name


def _sympy_law(pieces):
    """s(u) of piecewise accelerations integrated by sympy, C fixed by s(1) = 1."""
    u, C, t = sp.symbols("u C t")
    s0 = v0 = 0
    parts = []
    for a, b, acc in pieces:
        v = v0 + sp.integrate(acc.subs(u, a + t), (t, 0, u - a))
        s = s0 + sp.integrate(v.subs(u, a + t), (t, 0, u - a))
        parts.append((a, b, s))
        v0, s0 = v.subs(u, b), s.subs(u, b)
    c = sp.solve(s0 - 1, C)[0]
    return c, [(a, b, sp.lambdify(u, s.subs(C, c), "numpy")) for a, b, s in parts]


R = sp.Rational
_u, _C = sp.symbols("u C")
SYMPY_PIECES = {
    "modified_trapezoid": [
        (0, R(1, 8), _C * sp.sin(4 * sp.pi * _u)), (R(1, 8), R(3, 8), _C),
        (R(3, 8), R(5, 8), _C * sp.cos(4 * sp.pi * (_u - R(3, 8)))), (R(5, 8), R(7, 8), -_C),
        (R(7, 8), 1, -_C * sp.cos(4 * sp.pi * (_u - R(7, 8))))],
    "modified_sine": [
        (0, R(1, 8), _C * sp.sin(4 * sp.pi * _u)),
        (R(1, 8), R(7, 8), _C * sp.cos(4 * sp.pi / 3 * (_u - R(1, 8)))),
        (R(7, 8), 1, -_C * sp.cos(4 * sp.pi * (_u - R(7, 8))))],
}


@pytest.mark.parametrize("name", sorted(SYMPY_PIECES))
def test_modified_laws_against_sympy(name):
    c, parts = _sympy_law(SYMPY_PIECES[name])
    # The closed forms of C: 8π/(π+2) (trapezoid) and 4π²/(π+4) (sine).
    exact = {"modified_trapezoid": 8 * sp.pi / (sp.pi + 2),
             "modified_sine": 4 * sp.pi ** 2 / (sp.pi + 4)}[name]
    assert sp.simplify(c - exact) == 0
    s = law(name, U)[0]
    for a, b, f in parts:
        sel = (U >= float(a)) & (U <= float(b))
        assert np.max(np.abs(s[sel] - f(U[sel]))) <= 1e-14


def test_textbook_peak_coefficients():
    # Peaks of h·s'/β and h·s''/β² for h = β = 1, located on a fine grid and
    # polished: the exact maxima are at known u.
    peaks_v = {"harmonic": math.pi / 2, "cycloidal": 2.0, "modified_trapezoid": 2.0,
               "polynomial_345": 15 / 8}
    peaks_a = {"harmonic": math.pi ** 2 / 2, "cycloidal": 2 * math.pi,
               "modified_trapezoid": 8 * math.pi / (math.pi + 2),
               "modified_sine": 4 * math.pi ** 2 / (math.pi + 4),
               "polynomial_345": 10 / math.sqrt(3)}
    # where the peaks are (exactly): harmonic/cycloidal/345 velocity at 1/2, the
    # 345 acceleration at 1/2 − √3/6, the modified laws' at 1/8
    where_a = {"harmonic": 0.0, "cycloidal": 0.25, "modified_trapezoid": 0.125,
               "modified_sine": 0.125, "polynomial_345": 0.5 - math.sqrt(3) / 6}
    for name, want in peaks_v.items():
        assert abs(law(name, [0.5])[1][0] - want) <= 1e-12
        assert np.max(law(name, U)[1]) <= want + 1e-12
    for name, want in peaks_a.items():
        assert abs(law(name, [where_a[name]])[2][0] - want) <= 1e-12 * want
        assert np.max(np.abs(law(name, U)[2])) <= want * (1 + 1e-12)
    # the printed textbook values (Norton, Table 8-3), to their digits
    for name, printed in (("modified_trapezoid", 4.888), ("modified_sine", 5.528),
                          ("polynomial_345", 5.7735), ("cycloidal", 6.2832)):
        assert abs(peaks_a[name] - printed) < 6e-4
    assert abs(np.max(law("modified_sine", U)[1]) - 1.76) < 1e-3


@pytest.mark.parametrize("name", LAWS)
def test_derivatives_against_finite_differences(name):
    h = 1e-5
    u = np.linspace(0.01, 0.99, 97)
    u = u[np.min(np.abs(u[:, None] - np.array([1, 3, 5, 7]) / 8), axis=1) > 2 * h]
    _s, ds, dds = law(name, u)
    sp_, dsp, _ = law(name, u + h)
    sm, dsm, _ = law(name, u - h)
    assert np.max(np.abs((sp_ - sm) / (2 * h) - ds)) < 1e-8
    assert np.max(np.abs((dsp - dsm) / (2 * h) - dds)) < 1e-7
    # continuity at the piece boundaries: s, s' (and s'' for all but harmonic's ends)
    for b in (0.125, 0.375, 0.625, 0.875):
        lo, hi = law(name, [b - 1e-13]), law(name, [b + 1e-13])
        for q in range(3):
            assert abs(lo[q][0] - hi[q][0]) < 1e-9


def test_cam_cycle_values_and_derivatives():
    h, beta = 0.05, math.radians(120)
    m = cam_cycle("cycloidal", 120, 60, 120, h)
    th = np.radians([0, 30, 60, 120, 150, 180, 240, 270, 300, 330, 359.9])
    x, dx, ddx = m.evaluate(th)
    u = th / beta
    ref = np.where(th <= beta, h * (u - np.sin(2 * np.pi * u) / (2 * np.pi)), 0)
    ref = np.where((th > beta) & (th <= math.radians(180)), h, ref)
    ur = (th - math.radians(180)) / beta
    ref = np.where((th > math.radians(180)) & (th <= math.radians(300)),
                   h * (1 - (ur - np.sin(2 * np.pi * ur) / (2 * np.pi))), ref)
    assert np.max(np.abs(x - ref)) < 1e-15
    # the peak velocity 2h/β and acceleration 2πh/β² (per radian of cam angle)
    _, dx, ddx = m.evaluate(np.array([beta / 2, beta / 4]))
    assert abs(dx[0] - 2 * h / beta) <= 1e-12 * (2 * h / beta)
    assert abs(ddx[1] - 2 * np.pi * h / beta ** 2) <= 1e-12 * (2 * np.pi * h / beta ** 2)
    assert pickle.loads(pickle.dumps(m)) == m


@pytest.mark.parametrize("name", LAWS)
def test_fourier_coefficients_against_quadrature(name):
    m = cam_cycle(name, 100, 40, 130, 0.02)
    c = m.fourier(12)
    edges = sorted(set(np.degrees(np.array(m.start)).round(12)) | {360.0})
    for k in (1, 2, 3, 7, 12):
        def f(d, part, k=k):
            val = m.evaluate(np.radians(d))[1] * np.exp(-1j * k * np.radians(d))
            return float(getattr(val, part))
        re = sum(quad(f, a, b, args=("real",), epsabs=1e-14, epsrel=1e-12)[0]
                 for a, b in itertools.pairwise(edges)) / 360
        im = sum(quad(f, a, b, args=("imag",), epsabs=1e-14, epsrel=1e-12)[0]
                 for a, b in itertools.pairwise(edges)) / 360
        assert abs(c[k - 1] - complex(re, im)) <= 1e-13 * max(abs(c[0]), 1e-3)
    # and the series rebuilds dx/dθ
    cc = m.fourier(4000)
    th = np.radians(np.linspace(0, 360, 37))
    k = np.arange(1, 4001)
    series = (2 * np.exp(1j * np.outer(th, k)) @ cc).real
    assert np.max(np.abs(series - m.evaluate(th)[1])) < 1e-3 * np.max(np.abs(m.evaluate(th)[1]))


def test_fourier_of_a_table_against_gauss_legendre_quadrature():
    """A 720-piece table: each piece's short integral by 12-point Gauss–Legendre (on
    pieces of 0.5°, its truncation about 1e-16 up to k = 1000), independent of the closed
    form.  The low harmonics are where a sum of each end's term e^{−jkθ}q⁽ʳ⁾ apart cancels
    (the derivative terms of neighbouring pieces nearly equal): 1.1e-13 of the largest
    coefficient at k = 1 in a version that summed them so; 1.4e-15 now (8.1e-15 before
    the blocked form), at most 2.7e-15 at these k, so the bound has a margin of 3.7.
    (At k = 1000 the reference's own rounding of e^{−jkθ}, θ up to 2π, reaches 7e-15.)"""
    ang = np.linspace(0, 360, 721)
    m = motion_table(ang, cam_cycle("cycloidal", 120, 60, 120, 0.05).evaluate(
        np.radians(ang))[0])
    c = m.fourier(333)
    node, weight = np.polynomial.legendre.leggauss(12)
    edges = np.radians(ang)
    mid, half = (edges[1:] + edges[:-1]) / 2, np.diff(edges) / 2
    theta = (mid[:, None] + half[:, None] * node).ravel()
    dx = m.evaluate(theta)[1] * (half[:, None] * weight).ravel()
    for k in (1, 2, 7, 50, 333):
        ref = np.sum(dx * np.exp(-1j * k * theta)) / (2 * np.pi)
        assert abs(c[k - 1] - ref) <= 1e-14 * abs(c[0]), (k, abs(c[k - 1] - ref))


def test_table_spline_is_exact_for_a_trigonometric_cycle(tmp_path):
    ang = np.linspace(0, 360, 721)
    x = 0.01 * np.sin(np.radians(ang))
    path = tmp_path / "lift.csv"
    path.write_text("angle_deg,displacement\n" +
                    "\n".join(f"{a:.17g},{v:.17g}" for a, v in zip(ang, x)) + "\n")
    m = read_motion_table(path)
    th = np.radians(np.linspace(0, 360, 101))
    _, dx, _ = m.evaluate(th)
    assert np.max(np.abs(dx - 0.01 * np.cos(th))) < 1e-9
    c = m.fourier(3)
    assert abs(c[0] - 0.005) < 1e-9 and abs(c[1]) < 1e-11
    assert 0 < m.error < 1e-6


@pytest.mark.parametrize("body,line,col,what", [
    ("angle_deg,displacement\n0,0\n90,1\n90,0\n180,0\n360,0\n", 4, 1, "repeats"),
    ("angle_deg,displacement\n0,0\n90,1\n80,0\n180,0\n360,0\n", 4, 1, "below"),
    ("angle_deg,displacement\n0,0\n90,nan\n180,0\n270,0\n360,0\n", 3, 4, "finite"),
    ("angle_deg,displacement\n0,0\n90,1\n180,0\n270,0\n359,0\n", 6, 1, "one revolution"),
    ("angle_deg,displacement\n0,0\n90,1\n180,0\n270,0\n360,0.1\n", 6, 5, "not periodic"),
    ("angle_deg,displacement\n0,0\n90,x1\n180,0\n270,0\n360,0\n", 3, 4, "not a number"),
    ("angle,displacement\n0,0\n", 1, 1, "angle_deg"),
])
def test_bad_tables_are_located(tmp_path, body, line, col, what):
    path = tmp_path / "bad.csv"
    path.write_text(body)
    with pytest.raises(NetlistError) as info:
        read_motion_table(path)
    err = info.value
    assert (err.line, err.col) == (line, col) and what in str(err), str(err)


def test_table_direct():
    m = motion_table([0, 90, 180, 270, 360], [0, 1, 0, -1, 0])
    x, _, _ = m.evaluate(np.radians([0, 90, 180, 270, 360]))
    assert np.allclose(x, [0, 1, 0, -1, 0], atol=1e-15)
    assert m.error == math.inf        # too few rows for an estimate


def test_a_row_csv_cannot_split_is_a_located_error(tmp_path):
    """Fuzz (issue 23, seed 3018541): a carriage return inside a row made csv raise
    csv.Error ('new-line character seen in unquoted field'), exit 1."""
    p = tmp_path / "lift.csv"
    p.write_bytes(b"angle_deg,displacement\n0,0\n90,0.1\r2\n180,0\n270,0.1\n360,0\n")
    with pytest.raises(NetlistError, match="not a CSV row") as info:
        read_motion_table(p)
    assert info.value.line == 3


def test_quintic_piece_against_an_exact_solve():
    """:func:`mechcirc.motion_laws.quintic` against the right end's 3 × 3 system solved in
    exact rational arithmetic (the float inputs taken as exact), 300 random pieces of widths
    1e-3 … 3 and end values 1e-3 … 1e3 apart.  Error of each a_k·h^k, relative to the largest
    end value: measured 3.0e-15 at most (the 3 × 3 solve it replaced: 1.0e-13); asserted 2e-14
    (a 6.6x margin; the old solve fails it)."""
    from fractions import Fraction as F

    from mechcirc.motion_laws import quintic

    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(300):
        h = float(10 ** rng.uniform(-3, 0.5))
        a = rng.normal(size=3) * 10 ** rng.uniform(-3, 3, 3)
        b = a + rng.normal(size=3) * 10 ** rng.uniform(-6, 1, 3)
        got = quintic(h, a, b)
        H, (a0, a1, a2), (b0, b1, b2) = F(h), map(F, a), map(F, b)
        r = [b0 - a0 - a1 * H - a2 / 2 * H * H, b1 - a1 - a2 * H, b2 - a2]
        M = [[H ** 3, H ** 4, H ** 5], [3 * H ** 2, 4 * H ** 3, 5 * H ** 4],
             [6 * H, 12 * H ** 2, 20 * H ** 3]]
        exact = [c * H ** (3 + i) for i, c in enumerate(_solve_exact(M, r))]   # a_k h^k
        scale = max(map(abs, [*a, *b])) * max(1.0, h) ** 2
        worst = max(worst, *(abs(float(got[3 + i]) * h ** (3 + i) - float(exact[i])) / scale
                             for i in range(3)))
    assert worst <= 2e-14


def _solve_exact(M, r):
    """x with M x = r by Gaussian elimination in rational arithmetic (no pivoting needed:
    exact)."""
    n = len(r)
    A = [list(row) + [v] for row, v in zip(M, r)]
    for i in range(n):
        for j in range(i + 1, n):
            f = A[j][i] / A[i][i]
            A[j] = [x - f * y for x, y in zip(A[j], A[i])]
    x = [0] * n
    for i in reversed(range(n)):
        x[i] = (A[i][n] - sum(A[i][k] * x[k] for k in range(i + 1, n))) / A[i][i]
    return x
