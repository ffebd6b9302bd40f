"""Pieces shared by the fixed-step integrators of the sley and scene kernels."""

from __future__ import annotations

from ._jit import decorators

HAVE_NUMBA, _jit, _jit_inline = decorators()
# called once per step: inlined into a caller that counts references (numba's runtime), its
# array arguments were counted atomically at every call (compiled apart, without counting)
_leaf = decorators(nrt=False)[1]

__all__ = ["hermite_point", "record_hermite"]


@_jit_inline
def hermite_point(out, s, h, y, f0, ynew, f1, n, m):
    """The state at the fraction s of the step [t, t + h] into ``out``: cubic Hermite.

    ``y``/``f0`` are the state and its derivative at t, ``ynew``/``f1`` at t + h.
    ``m > 0``: the state is [q (m), q̇ (m), rest] with f = [q̇, q̈, ...] (a second-order
    system): q by the quintic Hermite interpolant matching q, q̇, q̈ at both ends
    (error O(h⁶)) and q̇ by its derivative (O(h⁵)); the rest (and all of it for
    ``m = 0``) cubic in y and f (O(h⁴)).
    """
    s2 = s * s
    s3 = s2 * s
    for i in range(2 * m, n):
        h00 = 2.0 * s3 - 3.0 * s2 + 1.0
        h10 = s3 - 2.0 * s2 + s
        h01 = -2.0 * s3 + 3.0 * s2
        h11 = s3 - s2
        out[i] = h00 * y[i] + h * h10 * f0[i] + h01 * ynew[i] + h * h11 * f1[i]
    if m == 0:
        return
    s4 = s3 * s
    s5 = s4 * s
    r = 1.0 - s
    g = 30.0 * s2 * r * r                  # d/ds of the end values' weight w1
    w1 = 10.0 * s3 - 15.0 * s4 + 6.0 * s5
    v0 = s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5
    a0 = 0.5 * (s2 - 3.0 * s3 + 3.0 * s4 - s5)
    v1 = -4.0 * s3 + 7.0 * s4 - 3.0 * s5
    a1 = 0.5 * (s3 - 2.0 * s4 + s5)
    dv0 = 1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4
    da0 = 0.5 * (2.0 * s - 9.0 * s2 + 12.0 * s3 - 5.0 * s4)
    dv1 = -12.0 * s2 + 28.0 * s3 - 15.0 * s4
    da1 = 0.5 * (3.0 * s2 - 8.0 * s3 + 5.0 * s4)
    hh = h * h
    for i in range(m):
        dq = ynew[i] - y[i]
        out[i] = y[i] + w1 * dq + h * (v0 * f0[i] + v1 * f1[i]) + \
            hh * (a0 * f0[m + i] + a1 * f1[m + i])
        out[m + i] = g * dq / h + dv0 * f0[i] + dv1 * f1[i] + \
            h * (da0 * f0[m + i] + da1 * f1[m + i])


@_leaf
def record_hermite(rec_t, rec_y, j, t_out0, dt_out, t, h, last, y, f0, ynew, f1, n, m, tmp):
    """Record the output times in the step [t, t + h] by Hermite interpolation
    (:func:`hermite_point`: cubic, or quintic in the positions for ``m > 0``), each through
    the scratch ``tmp`` (n) (a view ``rec_y[j]`` would cost two atomic reference counts).

    ``y``/``f0`` are the state and its derivative at t, ``ynew``/``f1`` at t + h;
    output time j is ``t_out0 + j·dt_out``.  The last step (``last``) also takes a
    time a rounding past its end.  Returns the next j to record.
    """
    nrec = rec_y.shape[0]
    while j < nrec:
        tj = t_out0 + j * dt_out
        if tj >= t + h and not last:
            break
        if tj > t + h * (1.0 + 1e-9):
            break
        hermite_point(tmp, (tj - t) / h, h, y, f0, ynew, f1, n, m)
        for i in range(n):
            rec_y[j, i] = tmp[i]
        rec_t[j] = tj
        j += 1
    return j
