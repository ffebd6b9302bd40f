"""The refinement's arithmetic between the nodal kernels, point by point: the one copy,
run by numpy elementwise and compiled by numba.

The error estimate of a correction (:func:`estimate_point`) and the first-step bound
(:func:`bound_point`) from their row sums and maxima, written once as arithmetic
without a branch on its values (as :mod:`mechcirc._dd`): the numpy path
(:func:`mechcirc.nodal._estimate`, :func:`mechcirc.nodal.first_step_bound`) applies
them to its arrays of row reductions; :mod:`mechcirc._nodal_kernels` loads a copy
compiled by numba (:func:`mechcirc._jit.load` with ``_COMPILE``) and applies them ω
by ω in one loop that forms the reductions too.  The two paths' reductions (|z|, the
sums over a row) are not the same bits (numpy's SIMD |z| and products, its pairwise
sums): each path is deterministic and its estimate bounds its own error
(tests/test_nodal.py).

numba's disk cache checks only the file of the compiled kernel: after editing this
file, touch ``_nodal_kernels.py``.
"""

from __future__ import annotations

import numpy as np

from ._jit import decorators

HAVE_NUMBA, _, _inline = decorators(not globals().get("_COMPILE"))

U = 2.0 ** -53                          # unit roundoff


def _select_scalar(c, a, b):
    """``a if c else b``: :func:`numpy.where` of one point (numba's allocates an array)."""
    return a if c else b


select = _inline(_select_scalar) if HAVE_NUMBA else np.where


@_inline
def estimate_point(nd, nx, npv, K, dK, da, db, xr, first):
    """(Relative error of K before the correction d, contraction ρ) from ‖d‖, ‖x‖, ‖prev‖
    (max |·| of the rows), |K|, |d_a − d_b|, |d_a|, |d_b| and |xᵀr|
    (:func:`mechcirc.nodal._estimate`; ``first``: no ``prev``, ‖x‖ given for it)."""
    npv = np.maximum(npv, 4.0 * U * U * nx)
    rho = select(npv > 0, nd / npv, 0.0)
    own = 1.0 if first else np.minimum(rho, 1.0)
    est = np.maximum((dK + own * (da + db)) / K, xr / K)
    # Stagnation at the residual's own rounding level is not divergence: only
    # corrections of the size of x itself that do not shrink mean a singular A.
    diverged = (rho >= 0.5) & (nd > 1e-2 * nx)
    return select(diverged | np.isnan(est), np.inf, est), rho


@_inline
def bound_point(lu, rounding, by_c, by_m, by_k, lever, w, K, n, m):
    """:func:`mechcirc.nodal.first_step_bound` from |x|ᵀP̃|L||U||d| ``lu``, |x|ᵀ|r̂|, the
    element sums by kind (|c|, |m|, |k| times (|x_i| + |x_j|)(|d_i| + |d_j|)), the levers'
    Σ |v| |x_r| |d_c|, |ω|, |K|, n unknowns and ``m`` the most terms of a row."""
    entry = by_c + w * by_m + by_k / w + lever
    return 2.0 * (8.0 * (n + 2) * U * lu + U * rounding + (m + 4) * U * entry) / K
