"""A corpus of series–parallel networks and their K(ω) in mpmath at 40 digits.

Written from the element laws (mass K = −j/(ωm), spring jω/k, damper 1/c;
series: K adds; parallel: 1/K adds; lever: K/r² seen from the primary), not from
mechcirc's reduction: a network is generated here as an expression, turned into
elements and levers for mechcirc, and evaluated here from the same expression.
Used by ``tests/test_sweep.py`` (small) and ``benchmarks/calibrate_sp.py`` (full).
"""

from __future__ import annotations

import itertools
import math

import mpmath
import numpy as np

from mechcirc.circuit import Circuit, Drive, Element, Lever

DIGITS = 40


# An expression is ("leaf", kind, value) | ("s", [children]) | ("p", [children])
# | ("lever", ratio, child).

def random_tree(rng, n_leaves: int, *, decades: float = 12.0, damped: float = 0.2,
                levers: float = 0.1):
    """A random expression of about ``n_leaves`` leaves, values over ``decades`` decades."""
    def leaf():
        kind = "damper" if rng.random() < damped else ("mass", "spring")[rng.integers(2)]
        return ("leaf", kind, float(10 ** rng.uniform(-decades / 2, decades / 2)))

    def build(n, top):
        if n <= 1:
            return leaf()
        if not top and rng.random() < levers:
            return ("lever", float(10 ** rng.uniform(-3, 3)), build(n, True))
        k = int(rng.integers(2, min(4, n) + 1))
        cuts = sorted(rng.choice(np.arange(1, n), size=k - 1, replace=False))
        sizes = np.diff([0, *cuts, n])
        kind = "s" if rng.random() < 0.5 else "p"
        return (kind, [build(int(s), False) for s in sizes])

    return build(n_leaves, True)


def ladder(rng, n_elements: int, *, r: float | None = 1e-3):
    """Issue 11's ladder: springs k ∈ [1e4, 2e4] N/m in series along the line,
    masses m ∈ [0.2, 1.2] kg from every inner node to the frame, and a damper r
    at the end (none when ``r`` is None)."""
    n_sections = n_elements // 2
    ks = rng.uniform(1e4, 2e4, n_sections)
    ms = rng.uniform(0.2, 1.2, n_sections)
    # Innermost first: (k_last + (m_last | r)) ...
    node = ("leaf", "damper", float(r)) if r is not None else None
    for k, m in zip(ks[::-1], ms[::-1]):
        shunt = ("leaf", "mass", float(m))
        if node is not None:
            shunt = ("p", [shunt, node])
        node = ("s", [("leaf", "spring", float(k)), shunt])
    return node


def to_circuit(expr, name: str = "corpus") -> Circuit:
    """mechcirc elements and levers of ``expr`` between node ``a`` and the frame."""
    elements, levers = [], []
    counter = itertools.count()

    def fresh():
        return f"n{next(counter)}"

    stack = [(expr, "a", "0")]
    while stack:
        e, n1, n2 = stack.pop()
        if e[0] == "leaf":
            elements.append(Element(e[1], f"{e[1][0]}{len(elements)}", n1, n2, e[2]))
        elif e[0] == "s":
            nodes = [n1] + [fresh() for _ in e[1][:-1]] + [n2]
            stack.extend((c, nodes[i], nodes[i + 1]) for i, c in enumerate(e[1]))
        elif e[0] == "p":
            stack.extend((c, n1, n2) for c in e[1])
        else:
            t = fresh()
            levers.append(Lever(f"L{len(levers)}", n1, n2, t, "0", e[1]))
            stack.append((e[2], t, "0"))
    return Circuit(tuple(elements), Drive("V", "a", "0", "velocity", 1.0), tuple(levers),
                   name=name)


def K_mp(expr, omega: float):
    """K(ω) of ``expr`` in mpmath (caller sets the precision); iterative."""
    w = mpmath.mpf(omega)
    j = mpmath.mpc(0, 1)
    # Post-order without recursion (ladders nest deep).
    out = {}
    stack = [(expr, False)]
    while stack:
        e, done = stack.pop()
        if e[0] == "leaf":
            v = mpmath.mpf(e[2])
            out[id(e)] = (-j / (w * v) if e[1] == "mass" else
                          j * w / v if e[1] == "spring" else 1 / v)
            continue
        kids = e[1] if e[0] in "sp" else [e[2]]
        if not done:
            stack.append((e, True))
            stack.extend((c, False) for c in kids)
            continue
        vals = [out.pop(id(c)) for c in kids]
        if e[0] == "s":
            out[id(e)] = mpmath.fsum(vals)
        elif e[0] == "p":
            out[id(e)] = 1 / mpmath.fsum(1 / v for v in vals)
        else:
            r = mpmath.mpf(e[1])
            out[id(e)] = vals[0] / (r * r)
    return out[id(expr)]


def reference(expr, omega) -> np.ndarray:
    """K(ω) at 40 digits, rounded to complex128, and its relative distance helper."""
    with mpmath.workdps(DIGITS):
        return [K_mp(expr, w) for w in omega]


def true_error(K: np.ndarray, ref) -> np.ndarray:
    """|K − K_ref| / |K_ref| computed in mpmath."""
    out = np.empty(len(ref))
    with mpmath.workdps(DIGITS):
        for i, (k, r) in enumerate(zip(K, ref)):
            if not np.isfinite(k):
                out[i] = np.inf
                continue
            d = abs(mpmath.mpc(k.real, k.imag) - r)
            out[i] = float(d / abs(r)) if r != 0 else (0.0 if d == 0 else math.inf)
    return out


def lossless(expr) -> bool:
    stack = [expr]
    while stack:
        e = stack.pop()
        if e[0] == "leaf":
            if e[1] == "damper":
                return False
        else:
            stack.extend(e[1] if e[0] in "sp" else [e[2]])
    return True


#: critical_points' answers so far: (repr of the tree, lo, hi, n_grid) -> the points.
_CRITICAL: dict = {}


def critical_points(expr, lo: float, hi: float, n_grid: int = 400) -> list:
    """Zeros and poles of K = jX of a lossless ``expr`` in [lo, hi], to 40 digits.

    X(ω) rises between its poles (Foster), so each sign change of X on a log grid
    brackets one zero (− to +) or one pole (+ to −); bisection in mpmath finds it.
    Computed once per process for a tree (its repr: every value's digits) and
    interval: tests/test_nodal_corpus.py builds the small corpus ten times.
    """
    key = (repr(expr), lo, hi, n_grid)
    if key not in _CRITICAL:
        _CRITICAL[key] = _critical_points(expr, lo, hi, n_grid)
    return list(_CRITICAL[key])


def _critical_points(expr, lo: float, hi: float, n_grid: int) -> list:
    grid = np.geomspace(lo, hi, n_grid)
    roots = []
    with mpmath.workdps(DIGITS):
        X = [mpmath.im(K_mp(expr, w)) for w in grid]
        for (w1, x1), (w2, x2) in zip(zip(grid, X), zip(grid[1:], X[1:])):
            if x1 * x2 >= 0:
                continue
            a, b = mpmath.mpf(w1), mpmath.mpf(w2)
            xa = x1
            for _ in range(110):        # 2^-110 of the bracket: beyond float64
                if float(a) == float(b):
                    # Every point of [a, b] rounds to this float (rounding is monotone),
                    # the further halvings' midpoint too: the answer is known.
                    break
                mid = (a + b) / 2
                try:
                    xm = mpmath.im(K_mp(expr, mid))
                except ZeroDivisionError:   # landed on the pole or zero exactly
                    a = b = mid
                    break
                if (xm < 0) == (xa < 0):
                    a, xa = mid, xm
                else:
                    b = mid
            roots.append(float((a + b) / 2))
    return roots
