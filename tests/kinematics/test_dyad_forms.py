"""The dyads' closed forms (mechcirc.kinematics._dyad_forms), written once (numpy).

* each form against an independent construction in mpmath (50 digits): the
  RRR inner joint by the law of cosines, the RRP one as a root of the
  quadratic |g + σu − x1|² = l1², the RPR rotation as the angle between the
  pose's and the current outer-joint vectors; Cramer's rule against numpy.

The linkage solver's dyads and FourBar.evaluate run these very functions; the
dyads are compared with Newton and with FourBar in test_linkage_solver.
"""

import math

import mpmath as mp
import numpy as np
import pytest

from mechcirc.kinematics import _dyad_forms as F

mp.mp.dps = 50
RNG = np.random.default_rng(7)
N = 64


def _c(z):
    return mp.mpc(z.real, z.imag)


def _cases():
    x1 = RNG.uniform(-50, 50, N) + 1j * RNG.uniform(-50, 50, N)
    x2 = x1 + RNG.uniform(20, 80, N) * np.exp(1j * RNG.uniform(-math.pi, math.pi, N))
    d = np.abs(x2 - x1)
    l1 = d * RNG.uniform(0.4, 1.2, N)
    l2 = d * RNG.uniform(0.4, 1.2, N)
    ok = (l1 + l2 > d * 1.01) & (np.abs(l1 - l2) < d * 0.99)
    return x1[ok], x2[ok], l1[ok], l2[ok]


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_rrr_against_the_law_of_cosines(sign):
    x1, x2, l1, l2 = _cases()
    x3, h2 = F.rrr(x1, x2, l1, l2, sign)
    assert np.all(h2 > 0)
    for k in range(len(x1)):
        a, b = _c(x1[k]), _c(x2[k])
        d = abs(b - a)
        cos_a = (mp.mpf(l1[k]) ** 2 + d ** 2 - mp.mpf(l2[k]) ** 2) / (2 * l1[k] * d)
        ref = a + l1[k] * (b - a) / d * mp.expj(sign * mp.acos(cos_a))
        assert abs(complex(ref) - x3[k]) <= 1e-14 * 100       # achieved 4.3e-14
    assert np.max(np.abs(np.abs(x3 - x1) - l1)) <= 1e-13
    assert np.max(np.abs(np.abs(x3 - x2) - l2)) <= 1e-13


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_rrp_against_the_quadratic(sign):
    x1, g, l1, _ = _cases()
    u = np.exp(1j * RNG.uniform(-math.pi, math.pi, len(x1)))
    x3, h2 = F.rrp(x1, l1, g, u, sign)
    for k in range(len(x1)):
        a, gg, uu = _c(x1[k]), _c(g[k]), _c(u[k])
        w = gg - a
        p = mp.re(mp.conj(uu) * w)                       # u · w
        disc = p * p - (abs(w) ** 2 - mp.mpf(l1[k]) ** 2)
        if disc < 0:
            assert h2[k] < 0
            continue
        roots = [-p + mp.sqrt(disc), -p - mp.sqrt(disc)]
        # the root with sign(u · (x3 − x1)) = sign, i.e. sign(p + σ)
        sigma = next(s for s in roots if mp.sign(p + s) == sign)
        ref = gg + sigma * uu
        assert abs(complex(ref) - x3[k]) <= 1e-14 * 100       # achieved 2.0e-14


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_rpr_against_the_angle_between_the_outer_joint_vectors(sign):
    x1, x2, _, _ = _cases()
    u0 = np.exp(1j * RNG.uniform(-math.pi, math.pi, len(x1)))
    h0 = np.abs(x2 - x1) * RNG.uniform(-0.9, 0.9, len(x1))
    E, h2 = F.rpr(x1, x2, h0, u0, sign)
    for k in range(len(x1)):
        e = _c(x2[k]) - _c(x1[k])
        t = sign * mp.sqrt(abs(e) ** 2 - mp.mpf(h0[k]) ** 2)
        pose = _c(u0[k]) * (t + 1j * mp.mpf(h0[k]))     # x2 − x1 in the links' frame
        ref = mp.expj(mp.arg(e) - mp.arg(pose))
        assert abs(complex(ref) - E[k]) <= 4e-15                # achieved 4.6e-16
        assert abs(complex(t) ** 2 - h2[k]) <= 1e-14 * abs(complex(e)) ** 2   # 3.5e-16


def test_solve2_against_numpy_solve():
    c1, c2, b = (RNG.normal(size=N) + 1j * RNG.normal(size=N) for _ in range(3))
    x, y = F.solve2(c1, c2, b)
    for k in range(N):
        A = np.array([[c1[k].real, c2[k].real], [c1[k].imag, c2[k].imag]])
        ref = np.linalg.solve(A, [b[k].real, b[k].imag])
        scale = np.max(np.abs(ref)) * np.linalg.cond(A)
        assert abs(x[k] - ref[0]) <= 1e-14 * scale and abs(y[k] - ref[1]) <= 1e-14 * scale

