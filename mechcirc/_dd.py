"""Double-double arithmetic: the one copy, run by numpy elementwise and compiled by numba.

A value is a pair (hi, lo) with hi + lo exact to about 2⁻¹⁰⁴ relative; real
and complex arrays alike (complex addition, and complex times real, work
component by component).  Every function is arithmetic without a branch on
its values, so the same text serves the vectorised numpy code (this module as
imported: plain functions, no numba) and the compiled kernels
(:mod:`mechcirc._nodal_kernels` loads a copy compiled by numba with
:func:`mechcirc._jit.load`).  Callers silence numpy's floating-point warnings.

numba's disk cache checks only the file of the compiled kernel: after editing
this file, touch ``_nodal_kernels.py`` (or clear its ``__pycache__``) so that
the cached kernels are compiled again.
"""

from __future__ import annotations

from ._jit import decorators

HAVE_NUMBA, _, _inline = decorators(not globals().get("_COMPILE"))

SPLITTER = 134217729.0                  # 2²⁷ + 1 (Veltkamp's split)
_BIG = 2.0 ** 995                       # above it, SPLITTER·a may overflow


@_inline
def split(a):
    """a = hi + lo exactly, hi and lo of 26 significant bits each (real a).

    |a| above 2⁹⁹⁵ is split as a·2⁻²⁸ (exact) and scaled back by 2²⁸ (exact: a
    power of two, not a division, which costs a dozen multiplications), so that
    SPLITTER·a does not overflow.
    """
    big = abs(a) > _BIG
    b = a * (1.0 + big * (2.0 ** -28 - 1.0))
    c = SPLITTER * b
    hi = (c - (c - b)) * (1.0 + big * (2.0 ** 28 - 1.0))
    return hi, a - hi


@_inline
def two_sum(a, b):
    """a + b = s + e exactly (Knuth's TwoSum)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


@_inline
def two_prod(a, ah, al, b):
    """a·b = p + e exactly (Dekker's TwoProduct; real ``a`` split beforehand as ah + al)."""
    bh, bl = split(b)
    return two_prod_split(a, ah, al, b, bh, bl)


@_inline
def two_prod_split(a, ah, al, b, bh, bl):
    """:func:`two_prod` with ``b`` split beforehand too, as bh + bl."""
    p = a * b
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@_inline
def dd_add(ah, al, bh, bl):
    """(ah + al) + (bh + bl), not renormalised."""
    s, e = two_sum(ah, bh)
    return s, e + (al + bl)


@_inline
def dd_difference(ah, bh, al, bl, lo):
    """(ah + al) − (bh + bl) rounded once (al and bl read only where ``lo``)."""
    s, e = two_sum(ah, -bh)
    if lo:
        e = e + (al - bl)
    return s + e


@_inline
def dd_mul_d(h, lo, w, wh, wl):
    """(h + lo)·w for a real double w split beforehand as wh + wl."""
    p, e = two_prod(w, wh, wl, h)
    return p, e + lo * w


@_inline
def dd_div_d(h, lo, w, wh, wl):
    """(h + lo)/w for a real double w split beforehand as wh + wl."""
    q = h / w
    p, e = two_prod(w, wh, wl, q)
    return q, (((h - p) - e) + lo) / w


@_inline
def dd_norm(h, lo):
    """(h, lo) renormalised: |lo| ≤ ulp(h)/2 (Fast2Sum)."""
    s = h + lo
    return s, lo - (s - h)


def dd_mul_split(a, b):
    """(ah + al)(bh + bl) (real) of two values given with their high parts split, as
    ``(hi, hi's high half, hi's low half, lo)`` (:func:`with_splits`)."""
    p, e = two_prod_split(a[0], a[1], a[2], b[0], b[1], b[2])
    return dd_norm(p, e + (a[0] * b[3] + a[3] * b[0]))


def with_splits(a):
    """A complex double-double value (re hi, re lo, im hi, im lo) as its real and
    imaginary parts, each ``(hi, *split(hi), lo)``: what :func:`dd_mul_split` takes, so
    that a value used in several products is split once."""
    return (a[0], *split(a[0]), a[1]), (a[2], *split(a[2]), a[3])


@_inline
def dd_sub(ah, al, bh, bl):
    """(ah + al) − (bh + bl), renormalised."""
    s, e = two_sum(ah, -bh)
    return dd_norm(s, e + (al - bl))


@_inline
def dd_div_dd(ah, al, bh, bl):
    """(ah + al)/(bh + bl) (real)."""
    q = ah / bh
    qh, ql = split(q)
    p, e = two_prod(q, qh, ql, bh)
    return q, ((((ah - p) - e) + al) - q * bl) / bh


def cdd_mul(a, b, split_a=None):
    """Complex double-double product; a value is (re_hi, re_lo, im_hi, im_lo).

    ``split_a``: :func:`with_splits` of ``a`` (then ``a`` is not read), where the caller
    has it already."""
    (ar, ai), (br, bi) = split_a or with_splits(a), with_splits(b)
    rr, ii = dd_mul_split(ar, br), dd_mul_split(ai, bi)
    ri, ir = dd_mul_split(ar, bi), dd_mul_split(ai, br)
    return (*dd_sub(*rr, *ii), *dd_norm(*dd_add(*ri, *ir)))


def cdd_div(a, b):
    """Complex double-double quotient a / b (b of moderate size: no overflow check)."""
    (ar, ai), (br, bi) = with_splits(a), with_splits(b)
    den = dd_norm(*dd_add(*dd_mul_split(br, br), *dd_mul_split(bi, bi)))
    re = dd_norm(*dd_add(*dd_mul_split(ar, br), *dd_mul_split(ai, bi)))
    im = dd_sub(*dd_mul_split(ai, br), *dd_mul_split(ar, bi))
    return (*dd_norm(*dd_div_dd(*re, *den)), *dd_norm(*dd_div_dd(*im, *den)))
