"""Pieces shared by the fixed-step integrators of the sley and scene kernels."""

from __future__ import annotations

from ._jit import decorators

HAVE_NUMBA, _jit, _jit_inline = decorators()

__all__ = ["record_hermite"]


@_jit_inline
def record_hermite(rec_t, rec_y, j, t_out0, dt_out, t, h, last, y, f0, ynew, f1, n):
    """Record the output times in the step [t, t + h] by cubic Hermite interpolation.

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
        s = (tj - t) / h
        s2 = s * s
        s3 = s2 * s
        h00 = 2.0 * s3 - 3.0 * s2 + 1.0
        h10 = s3 - 2.0 * s2 + s
        h01 = -2.0 * s3 + 3.0 * s2
        h11 = s3 - s2
        for i in range(n):
            rec_y[j, i] = h00 * y[i] + h * h10 * f0[i] + h01 * ynew[i] + h * h11 * f1[i]
        rec_t[j] = tj
        j += 1
    return j
