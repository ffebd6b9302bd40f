"""scipy's DOP853 with every kink of a piecewise right-hand side at a step's end: the
reference of the tests whose equations switch piece (contacts, clearances, a cam's
joints), whose error does not move with where the kinks fall among the steps."""

import numpy as np


def located(f, t, y, ends, side, rtol, atol):
    """``y' = f(t, y)`` from (t, y) through ``ends`` (increasing) by scipy's DOP853 at
    ``rtol``/``atol``, every kink at a step's end: the integration stops at each of ``ends``
    and, where a step changed ``side(t, y)`` (the piece of the right-hand side), bisects the
    switch on that step's interpolant and takes the step again up to it.  Returns (y at the
    last end, the steps' (start, interpolant) in order)."""
    from scipy.integrate import DOP853

    def run(t, y, tb, pieces, on=None):
        """From (t, y) to tb, the steps' interpolants into ``pieces``; where a step leaves the
        piece ``on``: (its start, its state, its interpolant, its end), else (tb, y(tb))."""
        s = DOP853(f, t, y, tb, rtol=rtol, atol=atol)
        while s.status == "running":
            t, y = s.t, s.y.copy()
            s.step()
            if on is not None and side(s.t, s.y) != on:
                return t, y, s.dense_output(), s.t
            pieces.append((t, s.dense_output()))
        assert s.status == "finished", s.status
        return s.t, s.y, None, None

    pieces = []
    for tb in ends:
        while t < tb:
            t, y, interp, hi = run(t, y, tb, pieces, side(t, y))
            if interp is not None:
                lo, on = t, side(t, y)
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    if side(mid, interp(mid)) == on:
                        lo = mid
                    else:
                        hi = mid
                t, y, _, _ = run(t, y, hi, pieces)
    return y, pieces


def at(pieces, t):
    """The solution of :func:`located`'s ``pieces`` at each of ``t`` (rows: components)."""
    idx = np.searchsorted([p[0] for p in pieces], t, "right") - 1
    return np.column_stack([pieces[i][1](v) for i, v in zip(idx, t)])
