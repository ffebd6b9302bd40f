"""A corpus for the nodal path's flags and error estimates, with references at 40 digits.

Every network is generated here as a plain description and given to
mechcirc as netlist text or elements; its reference K(ω) comes from that
description, never from mechcirc's code path: a dense solve of the nodal
equations in mpmath (:mod:`reference.mp_nodal`, for grids and meshes) or the
series–parallel closed form in mpmath (:mod:`reference.sp_corpus`, for trees
with levers and ladders).  Values are written with ``repr``, so both sides see
the same binary numbers.

Families (``size`` "small" for the test suite, "full" for the calibration
in ``docs/accuracy.md``: ``python tests/reference/nodal_corpus.py``):

* ``grid poles``: the uniform spring–mass grid (its eigenfrequencies in
  closed form, some of them modes the corner drive does not see, where A(ω)
  is singular but K regular) and (full) grids of random values (poles from
  an eigen-solve, polished by ``mpmath.findroot`` on 1/K), sampled at
  relative distances 1e-6, −1e-9, 1e-12, −1e-14 and 0 from each pole;
* ``trees + levers``: random series–parallel trees with levers (values over
  12 decades, lever ratios 1e±3) run through nodal analysis, lossless ones
  also near their poles and zeros;
* ``stiff trees``: the same with values over 20 decades and ω over 14
  decades (A(ω) beyond float64's reach, K well conditioned: the case of
  ``defect_nodal_flag1_regular``);
* ``scaled 1e±100``: trees and meshes with every element value multiplied
  by 1e100 or 1e-100 (lever ratios unchanged);
* ``meshes``: random networks that are not series–parallel, with levers,
  undamped and lightly damped;
* ``ladders``: lightly damped (r = 1e-3) and undamped ladders (45 and 201
  elements: the dense and the sparse banded path).
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import mpmath
import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from reference import mp_nodal, sp_corpus

DIGITS = 40
DISTANCES = (1e-6, -1e-9, 1e-12, -1e-14, 0.0)
U = 2.0 ** -53


def spec_text(spec) -> str:
    lines = [f"drive V {spec['drive'][0]} {spec['drive'][1]} velocity=1"]
    lines += [f"{k} e{i} {a} {b} {v!r}" for i, (k, a, b, v) in enumerate(spec["elements"])]
    lines += [f"lever {n} {p1} {p2} {s1} {s2} ratio={r!r}"
              for n, p1, p2, s1, s2, r in spec["levers"]]
    return "\n".join(lines) + "\n"


def scaled_spec(spec, factor: float):
    els = [(k, a, b, float(v * factor)) for k, a, b, v in spec["elements"]]
    return {**spec, "elements": els}


def scaled_tree(expr, factor: float):
    if expr[0] == "leaf":
        return ("leaf", expr[1], float(expr[2] * factor))
    if expr[0] == "lever":
        return ("lever", expr[1], scaled_tree(expr[2], factor))
    return (expr[0], [scaled_tree(c, factor) for c in expr[1]])


def grid_spec(rng, rows: int, cols: int, uniform: bool):
    """A rows×cols grid: mass and spring to the frame at every node, springs between
    neighbours; uniform (k = 1e4 N/m, m = 1 kg) or random (k ∈ [1e3, 1e5], m ∈ [0.1, 10])."""
    def k():
        return 1e4 if uniform else float(10 ** rng.uniform(3, 5))

    def m():
        return 1.0 if uniform else float(10 ** rng.uniform(-1, 1))
    els = []
    for i in range(rows):
        for j in range(cols):
            g = f"g{i}_{j}"
            els += [("mass", g, "0", m()), ("spring", g, "0", k())]
            if i + 1 < rows:
                els.append(("spring", g, f"g{i + 1}_{j}", k()))
            if j + 1 < cols:
                els.append(("spring", g, f"g{i}_{j + 1}", k()))
    return {"elements": els, "levers": [], "drive": ("g0_0", "0")}


def uniform_grid_modes(rows: int, cols: int):
    """Eigenfrequencies of the uniform grid in mpmath: ω² = (k/m)(1 + μ_p + μ_q), μ = 2 − 2cos(πp/n)."""
    with mpmath.workdps(DIGITS):
        mu = [[2 - 2 * mpmath.cos(mpmath.pi * p / n) for p in range(n)] for n in (rows, cols)]
        return sorted({mpmath.sqrt(mpmath.mpf(1e4) * (1 + a + b)) for a in mu[0] for b in mu[1]})


def spec_poles(spec):
    """Poles of K (zeros of 1/K) of a lossless spec without levers, to 40 digits:
    an eigen-solve of Kₛ v = ω² M v for the start, ``mpmath.findroot`` on 1/K."""
    import scipy.linalg

    names = sorted({n for _, a, b, _ in spec["elements"] for n in (a, b)} - {"0"})
    idx = {n: i for i, n in enumerate(names)}
    mats = {"mass": np.zeros((len(names),) * 2), "spring": np.zeros((len(names),) * 2)}
    for kind, a, b, v in spec["elements"]:
        A = mats[kind]
        for p, q, s in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
            if p != "0" and q != "0":
                A[idx[p], idx[q]] += s * v
    w2 = scipy.linalg.eigh(mats["spring"], mats["mass"], eigvals_only=True)
    roots = []
    with mpmath.workdps(DIGITS):
        def g(x):               # Im(1/K) at s = jx: real, zero at a pole of K
            return mpmath.im(mp_nodal.inverse_K(spec, mpmath.mpc(0, x), DIGITS))
        for w0 in np.sqrt(w2[w2 > 0]):
            try:
                r = mpmath.findroot(g, mpmath.mpf(w0))
            except (ValueError, ZeroDivisionError):
                continue
            if abs(r / w0 - 1) < 1e-6:
                roots.append(r)
    return roots


def nodal_K(spec, omega: float, dps: int = 2 * DIGITS):
    """K(ω) by a dense solve of the nodal equations in mpmath (:func:`mp_nodal._matrices`).

    The lever force unknowns are scaled by the largest admittance (Q = g·Q',
    constraint rows × g: the same K), because ``mpmath.lu_solve`` calls a
    pivot below ‖A‖·eps singular, and admittances of 1e-100 beside the
    lever's ±1 would be; 80 digits so that 40 survive cond(A) up to 1e40.
    """
    mats, c = mp_nodal._matrices(spec, dps)
    with mpmath.workdps(dps):
        s = mpmath.mpc(0, omega)
        A = mats["damper"] + mats["lever"] + s * mats["mass"] + mats["spring"] / s
        n = A.rows
        nn = n - len(spec["levers"])
        g = max((abs(A[i, j]) for i in range(nn) for j in range(nn)), default=1) or 1
        for i in range(nn, n):
            for j in range(n):
                A[i, j] *= g
                A[j, i] *= g
        try:
            x = mpmath.lu_solve(A, c)
        except ZeroDivisionError:
            return mpmath.mpc(mpmath.inf)
        return sum(c[i] * x[i] for i in range(nn))


def near(points, rng, n_generic, lo, hi):
    """(ω, relative distance to the critical point: inf for generic points): ω at the
    DISTANCES from each critical point, and n_generic log-uniform in [lo, hi]."""
    out = [(float(p * (1 + mpmath.mpf(d))), d) for p in points for d in DISTANCES]
    out += [(w, math.inf) for w in 10 ** rng.uniform(math.log10(lo), math.log10(hi), n_generic)]
    out = [(w, d) for w, d in out if lo <= w <= hi]
    return np.array([w for w, _ in out]), np.array([d for _, d in out])


def cases(size: str = "small", seed: int = 0, keep=None):
    """Yield (family, netlist text or Circuit, ω, distances, reference function ω → mpc).

    ``distances``: each ω's relative distance from the pole or zero it was
    placed at (inf for generic points).  ``keep``: only the cases of these
    indices (in the order of generation; the random draws, and so the
    cases kept, are those of the whole corpus); the others are skipped
    without their poles' search."""
    rng = np.random.default_rng(seed)
    full = size == "full"
    at = [0]                        # the index of the next case

    def wanted(step: bool = True):
        k = at[0]
        at[0] += step
        return keep is None or k in keep

    def nodal_ref(spec):
        return lambda w: nodal_K(spec, w)

    def tree_ref(expr):
        def f(w):
            with mpmath.workdps(DIGITS):
                return sp_corpus.K_mp(expr, w)
        return f

    # Uniform grids: closed-form modes, many unseen from the corner.
    for rows, cols in ([(2, 3), (3, 3), (4, 4), (6, 6)] if full else [(3, 3)]):
        spec = grid_spec(rng, rows, cols, True)
        modes = uniform_grid_modes(rows, cols)
        case = "grid poles", spec_text(spec), *near(modes, rng, 4, 50, 500), nodal_ref(spec)
        if wanted():
            yield case
    for _ in range(8 if full else 0):
        spec = grid_spec(rng, int(rng.integers(2, 5)), int(rng.integers(2, 5)), False)
        poles = spec_poles(spec) if wanted(False) else []
        case = "grid poles", spec_text(spec), *near(poles, rng, 4, 1, 1e4), nodal_ref(spec)
        if wanted():
            yield case

    # Trees with levers (undamped, lightly damped), through nodal analysis.
    for i in range(60 if full else 6):
        damped = (0.0, 0.2)[i % 2]
        expr = sp_corpus.random_tree(rng, int(rng.integers(2, 30)), damped=damped, levers=0.3)
        need = wanted(False) or (i % 3 == 0 and (keep is None or at[0] + 1 in keep))
        crit = sp_corpus.critical_points(expr, 1e-2, 1e2, 100 if full else 40) \
            if not damped and need else []
        crit = [mpmath.mpf(c) for c in crit[:6 if full else 2]]
        omega, dist = near(crit, rng, 6 if full else 3, 1e-2, 1e2)
        if wanted():
            yield "trees + levers", sp_corpus.to_circuit(expr), omega, dist, tree_ref(expr)
        if i % 3 == 0 and wanted():
            f = 1e100 if i % 2 else 1e-100
            e2 = scaled_tree(expr, f)
            yield "scaled 1e±100", sp_corpus.to_circuit(e2), omega, dist, tree_ref(e2)

    # Stiff trees: values over 20 decades, ω over 14.
    for _ in range(30 if full else 3):
        expr = sp_corpus.random_tree(rng, int(rng.integers(10, 40)), decades=20.0,
                                     damped=0.0, levers=0.3)
        omega = 10 ** rng.uniform(-6, 8, 12 if full else 5)
        if wanted():
            yield "stiff trees", sp_corpus.to_circuit(expr), omega, omega * math.inf, tree_ref(expr)

    # Meshes (not series–parallel) with levers; scaled copies.
    for i in range(30 if full else 3):
        _, spec, w_char = mp_nodal.random_network(rng, n_nodes=int(rng.integers(4, 16)),
                                                  damped=bool(i % 2), levers=i % 3)
        omega = w_char * 10 ** rng.uniform(-2, 2, 4 if full else 2)
        if wanted():
            yield "meshes", spec_text(spec), omega, omega * math.inf, nodal_ref(spec)
        if i % 2 == 0 and wanted():
            s2 = scaled_spec(spec, 1e100 if i % 4 else 1e-100)
            yield "scaled 1e±100", spec_text(s2), omega, omega * math.inf, nodal_ref(s2)

    # Ladders (issue 11's): 45 elements (dense), 201 (sparse, banded).
    for n_el in ((45, 201) if full else (45,)):
        for r in (1e-3, None):
            expr = sp_corpus.ladder(rng, n_el, r=r)
            omega = np.geomspace(2 * math.pi * 0.1, 2 * math.pi * 1e3, 101 if full else 9)
            if wanted():
                yield "ladders", sp_corpus.to_circuit(expr), omega, omega * math.inf, tree_ref(expr)


#: The references computed so far: (size, seed, keep, case number, ω) -> K_ref (mpmath).
_REFERENCES: dict = {}


def _reference(ref, w, key):
    """``ref(w)``, computed once per process for the case and ω ``key`` names.

    The references are mpmath's alone (never mechcirc's): the same corpus measured
    again (tests/test_nodal_corpus.py measures the small corpus nine times, refined
    and not, compiled and numpy) needs them again, and they were 0.18 s of CPU of
    each measurement's 0.41 s.
    """
    if key not in _REFERENCES:
        _REFERENCES[key] = ref(w)
    return _REFERENCES[key]


def measure(size: str = "small", seed: int = 0, keep=None, refine: bool = True):
    """Rows (family, ω, K, error, flag, true error, distance) over the corpus
    (or its cases ``keep``, see :func:`cases`); ``refine=False``: the plain solve.

    The true error |K − K_ref| / |K_ref| in mpmath; NaN where K is ±∞·j or 0
    (flag 1) or the reference is infinite (A(ω) exactly singular)."""
    import mechcirc

    out = []
    corpus = (size, seed, None if keep is None else frozenset(keep))
    for i, (family, net, omega, dist, ref) in enumerate(cases(size, seed, keep)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c = mechcirc.parse(net) if isinstance(net, str) else net
            s = c.sweep(omega, method="nodal", refine=refine)
        K, err, flags = s.K, s.error, s.flags
        with mpmath.workdps(DIGITS):
            for w, k, e, f, d in zip(omega, K, err, flags, dist):
                r = _reference(ref, w, (*corpus, i, float(w)))
                if not mpmath.isfinite(abs(r)) or not np.isfinite(k) or k == 0:
                    true = math.nan
                elif r == 0:
                    true = math.inf
                else:
                    true = float(abs(mpmath.mpc(k.real, k.imag) - r) / abs(r))
                out.append((family, float(w), complex(k), float(e), int(f), true, float(d)))
    return out


def statistics(rows):
    """Per family and overall: the goals of docs/accuracy.md (see there)."""
    fams = sorted({r[0] for r in rows}) + ["all"]
    table = {}
    for fam in fams:
        sel = [r for r in rows if fam == "all" or r[0] == fam]
        flag1 = [r for r in sel if r[4] == 1]
        # A pole reported at a point that is not within rounding of one.
        wrong1 = [r for r in flag1 if not abs(r[6]) <= 1e-13]
        rest = [r for r in sel if r[4] != 1 and not math.isnan(r[5])]
        true = np.array([r[5] for r in rest])
        est = np.array([r[3] for r in rest])
        flag = np.array([r[4] for r in rest])
        ratio = est / np.maximum(true, U)
        fin = ratio[np.isfinite(ratio)]
        table[fam] = {
            "points": len(sel), "flag1": len(flag1), "flag1 regular": len(wrong1),
            "singular ref": sum(1 for r in sel if r[4] != 1 and math.isnan(r[5])),
            "true>1e-6": int(np.sum(true > 1e-6)),
            "false alarms": int(np.sum((flag == 2) & (true < 1e-8))),
            "misses": int(np.sum((flag == 0) & (true > 1e-6))),
            "under": int(np.sum(est < true)),
            "median": float(np.median(fin)) if fin.size else math.nan,
            "p99": float(np.percentile(fin, 99)) if fin.size else math.nan,
            "max": float(np.max(fin)) if fin.size else math.nan,
            "inf": int(np.sum(~np.isfinite(est))),
            "max true": float(np.max(true)) if true.size else math.nan,
        }
    return table


def markdown(table) -> str:
    head = ("| family | points | flag 1 (at regular ω) | true > 1e-6 | false alarms | misses | est < true "
            "| median est/true | 99 % | max | est = inf | largest true error |")
    lines = [head, "|" + "---|" * 12]
    for fam, t in table.items():
        pts = t["points"] - t["flag1"]
        fa = f"{t['false alarms']} ({100 * t['false alarms'] / max(pts, 1):.2f} %)"
        name = f"**{fam}**" if fam == "all" else fam
        lines.append(f"| {name} | {t['points']} | {t['flag1']} ({t['flag1 regular']}) | "
                     f"{t['true>1e-6']} | {fa} | "
                     f"{t['misses']} | {t['under']} | {t['median']:.3g} | {t['p99']:.3g} | "
                     f"{t['max']:.3g} | {t['inf']} | {t['max true']:.2g} |")
    return "\n".join(lines)


if __name__ == "__main__":
    import argparse
    import time

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="full", choices=["small", "full"])
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    t0 = time.process_time()
    rows = measure(a.size, a.seed)
    print(markdown(statistics(rows)))
    bad = [r for r in rows if r[4] == 1 or (r[3] < r[5]) or (r[4] == 0 and r[5] > 1e-6)
           or (r[4] == 2 and r[5] < 1e-8) or r[3] > 1e4 * max(r[5], U)]
    for r in bad[:40]:
        print("#", r)
    print(f"# {len(rows)} points, {time.process_time() - t0:.0f} s CPU")
