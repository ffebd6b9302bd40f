"""The closed forms of the dyads (RRR, RRP, RPR) and their 2×2 rate systems, written once.

Points and vectors are complex numbers x + iy.  Each function uses arithmetic,
``np.sqrt`` and ``np.maximum`` only, on numpy arrays (the vectorised solver of
:mod:`.linkage_solver`, its one user) or on scalars alike.  No
compiled copy of the dyads exists: a numba loop over the positions measured no
faster on any shipped command (:mod:`._linkage_kernels`, docs/performance.md).
"""

from __future__ import annotations

import numpy as np

__all__ = ["rrr", "rrp", "rpr", "solve2", "im_conj"]


def rrr(x1, x2, l1, l2, sign):
    """Inner joint of an RRR dyad: the point at ``l1`` from ``x1`` and ``l2`` from ``x2``.

    On the side ``sign`` (±1) of the line x1 → x2 (+1: to its left).  Returns
    ``(x3, h2)``; h2 < 0 where the two circles do not meet (x3 is then the
    foot of the missing height).
    """
    e = x2 - x1
    d2 = e.real * e.real + e.imag * e.imag
    d = np.sqrt(d2)
    x = (l1 * l1 - l2 * l2 + d2) / (2.0 * d)
    h2 = l1 * l1 - x * x
    return x1 + e * (x + 1j * (sign * np.sqrt(np.maximum(h2, 0.0)))) / d, h2


def rrp(x1, l1, g, u, sign):
    """Inner joint of an RRP dyad: the point of the line g + σu (|u| = 1) at ``l1`` from ``x1``.

    Of the two, the one with sign(u · (x3 − x1)) = ``sign``.  Returns
    ``(x3, h2)``; h2 < 0 where the circle misses the line.
    """
    w = g - x1
    p = w.real * u.real + w.imag * u.imag          # u · w
    c = u.real * w.imag - u.imag * w.real          # u × w: the line's distance from x1
    h2 = l1 * l1 - c * c
    return g + (sign * np.sqrt(np.maximum(h2, 0.0)) - p) * u, h2


def rpr(x1, x2, h0, u0, sign):
    """Rotation of the two links of an RPR dyad from the pose, as the unit complex E.

    In the links' common frame x2 − x1 = E·u0·(t + i·h0): the outer joints
    keep their distance ``h0`` across the sliding direction ``u0`` (pose
    coordinates, |u0| = 1) while t, their distance along it, takes the sign
    ``sign``.  Returns ``(E, h2)`` with h2 = t²; h2 < 0 where |x2 − x1| < |h0|.
    """
    e = x2 - x1
    h2 = e.real * e.real + e.imag * e.imag - h0 * h0
    return e / (u0 * (sign * np.sqrt(np.maximum(h2, 0.0)) + 1j * h0)), h2


def solve2(c1, c2, b):
    """Real (x, y) with x·c1 + y·c2 = b (complex), by Cramer's rule."""
    D = c1.real * c2.imag - c1.imag * c2.real
    return ((b.real * c2.imag - b.imag * c2.real) / D,
            (c1.real * b.imag - c1.imag * b.real) / D)


def im_conj(a, b):
    """Im(conj(a)·b) = a × b (the 2-D cross product)."""
    return a.real * b.imag - a.imag * b.real
