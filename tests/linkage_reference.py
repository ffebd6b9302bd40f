"""The constraint residual Φ(q) and its Jacobian of a :class:`mechcirc.kinematics.Linkage`,
written out from the equations (absolute coordinates q = [x, y, φ] per link), independent of
the package's solvers: a reference for the tests (fsolve on Φ) and the benchmarks' baseline
(the first release's Newton on them).

``local``, ``idx`` and ``rows`` are ``lk.local_offsets()``, ``lk.link_index()`` and
``lk.constraint_rows()``."""

import math

import numpy as np

_PERP = np.array([[0.0, -1.0], [1.0, 0.0]])


def _rot(phi):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s], [s, c]])


def _ends(q, local, idx, rows):
    """(row k, link index i, sign, R(φᵢ)·s) for each link end of each pin's two rows:
    the pin's point on link a (sign +1) and on link b (sign −1), the ground left out."""
    for j, (p, a, b) in enumerate(rows):
        for body, sign in ((a, 1.0), (b, -1.0)):
            if body != "ground":
                i = idx[body]
                yield 2 * j, i, sign, _rot(q[3 * i + 2]) @ local[body][p]


def phi(lk, q, angles, local, idx, rows):
    """Φ(q) with the cranks driven to ``angles`` [rad] (crank order)."""
    def point(link, p):
        i = idx[link]
        return q[3 * i:3 * i + 2] + _rot(q[3 * i + 2]) @ local[link][p]

    out = np.empty(len(q))
    k = 0
    for p, a, b in rows:
        out[k:k + 2] = (lk.pose[p] if a == "ground" else point(a, p)) - point(b, p)
        k += 2
    for c, ang in zip(lk.cranks, angles):
        out[k] = q[3 * idx[c.link] + 2] - ang
        k += 1
    return out


def jac(lk, q, local, idx, rows):
    """∂Φ/∂q at ``q`` (see :func:`phi`)."""
    J = np.zeros((len(q), len(q)))
    for k, i, sign, r in _ends(q, local, idx, rows):
        J[k:k + 2, 3 * i:3 * i + 2] += sign * np.eye(2)
        J[k:k + 2, 3 * i + 2] += sign * (_PERP @ r)
    k = 2 * len(rows)
    for c in lk.cranks:
        J[k, 3 * idx[c.link] + 2] = 1.0
        k += 1
    return J

