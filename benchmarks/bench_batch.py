"""Many designs at once (issue 21): the batched core against a hand-written numpy floor.

``netlists/stb_heald.mcir`` with its four lever ratios eta1…eta4 drawn at
random over D designs (D = 1e3, 1e4 and, with ``--big``, 1e5), 200 log points
10 … 10⁴ rad/s, and per design: K on the grid, the exact resonances and
anti-resonances, and the extremes of |K| and |Q0| over the band.  Timed in the
same run (CPU time, ``time.process_time``, median of ``--repeats``):

* ``floor``: what a careful analyst writes by hand for this one netlist: K(ω)
  of eq. (1) broadcast over designs in real arithmetic (K = jX), the nodal mass
  and stiffness matrices of all designs from precomputed patterns, the drive
  held (resonances) and released (anti-resonances, its one massless direction
  condensed out), both reduced by a Cholesky factor of M and solved in ONE
  stacked ``numpy.linalg.eigvalsh`` call, and the extremes from the roots and
  the band's ends (Foster).  No error bounds, no flags, no polishing.
* ``mechcirc``: :func:`mechcirc.batch.designs` (the ``.param`` expressions over
  arrays), ``Designs.sweep`` (K, error bound and flags), ``Designs.resonances``
  (stacked eigenproblems, every root polished on its design's K) and
  ``Designs.extremes``.

It checks that both agree (K, roots) and prints the per-design times and their
ratio (goal ≤ 2×).  The compiled kernel is loaded before timing.  It prints; it
asserts nothing.  Run from the repository root::

    python benchmarks/bench_batch.py [--big] [--repeats N] [--no-numba] [--nodal | --damped | --levers]

``--nodal``: instead, a bridge network (not series–parallel: the nodal path)
over a grid of three parameters, D = 100 and 1,000 designs (and 10,000 with
``--big``: from about 1,700 designs at 200 ω the stacked residual is the
compiled kernel's, numba installed), 200 ω, K with its
error bound and flags: ``Designs.sweep`` (the designs' A(ω) stacked, one batched
inverse per chunk of points) against the same designs one by one through
``mechcirc.sweep`` (what ``Designs.sweep`` did before), same run, with the
largest difference of K and of the error bound between the two; then the
resonances of the bridge (damped; without its damper; and undamped with a mass
across the bridge, whose roots are all polished), D = 100 and 1,000
over a grid of two parameters: ``Designs.resonances`` (stacked eigenproblems,
every root polished on its design's K by the stacked nodal solve) against
``find_resonances`` one design at a time (timed on 100 designs of the grid),
same run, per design, with the largest difference of ω between the two.

``--damped``: instead, ``netlists/heald_damped.mcir`` (series–parallel, damped,
a massless direction with the drive released) over a grid of eta1 and eta3,
D = 100 and 1,000: its resonances stacked against ``find_resonances`` one
design at a time, as for the bridge, and its extremes over 50 … 5,000 rad/s
(resonances given) against ``mechcirc.peak`` design by design.

``--levers``: instead, ``docs/examples/lever.mcir`` with its lever ratio r and first
mass made parameters (with and without a damper across its spring) over a grid of
r and the mass, D = 100 and 1,000: resonances stacked (a constraint basis per
design) against ``find_resonances`` one by one.

``--no-numba`` hides numba (``sys.modules["numba"] = None`` before mechcirc is
imported), as in an install without it: the batch then runs in numpy.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from pathlib import Path

if "--no-numba" in sys.argv:
    sys.modules["numba"] = None  # type: ignore[assignment]

import numpy as np

import mechcirc
from mechcirc.batch import designs
from timing import cpu

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "stb_heald.mcir"
OMEGA = np.geomspace(10.0, 1e4, 200)

# The netlist's elements (value, η as a function of eta1..eta4): eq. (1),
# K = m1 + m2 + m3 + m4 + (k4 | (m5 + k5) | (m6 + ... + m12 + k0)).
SERIES_MASSES = [(2.0, lambda e: 1.0), (1.5, lambda e: e[0] ** 2),
                 (1.2, lambda e: e[0] ** 2 * e[1]), (0.9, lambda e: e[0] ** 2 * e[1] * e[2] ** 2)]
CHAIN = [(0.6, 0), (0.5, 0), (0.7, 0), (0.4, 1), (0.3, 1), (0.5, 0), (3.0, 1)]   # (m, η = eta4?)


def floor_K(eta, omega):
    """X with K = jX over (D, W) by eq. (1), in real arithmetic."""
    e1, e2, e3, e4 = eta
    inv_w = 1.0 / omega[None, :]
    w = omega[None, :]
    a = sum(1.0 / (m * f(eta)) for m, f in SERIES_MASSES)          # Σ 1/(mη)
    etaC = e1 ** 2 * e2 * e3 ** 2
    b3 = sum(1.0 / (m * (e4 if s else 1.0)) for m, s in CHAIN)
    X_k4 = w / (2.0e6 * etaC)[:, None]
    X_b2 = -inv_w / 0.8 + w / 1.5e6
    X_b3 = -inv_w * b3[:, None] + w / (4.0e4 * e4)[:, None]
    return -inv_w * a[:, None] + 1.0 / (1.0 / X_k4 + 1.0 / X_b2 + 1.0 / X_b3)


def floor_matrices(eta):
    """Nodal M and K (D, 13, 13) of the held and released problems, condensed, as
    (D, 12, 12) pencils: nodes T A B C D E F G H I J L M, frame 0."""
    e1, e2, e3, e4 = eta
    D = e1.size
    nodes = "T A B C D E F G H I J L M".split()
    ix = {n: i for i, n in enumerate(nodes)}
    etaB, etaC = e1 ** 2 * e2, e1 ** 2 * e2 * e3 ** 2
    one = np.ones(D)
    masses = [("T", "A", 2.0 * one), ("A", "B", 1.5 * e1 ** 2), ("B", "C", 1.2 * etaB),
              ("C", "D", 0.9 * etaC), ("D", "E", 0.8 * one), ("D", "F", 0.6 * one),
              ("F", "G", 0.5 * one), ("G", "H", 0.7 * one), ("H", "I", 0.4 * e4),
              ("I", "J", 0.3 * e4), ("J", "L", 0.5 * one), ("L", "M", 3.0 * e4)]
    springs = [("D", "0", 2.0e6 * etaC), ("E", "0", 1.5e6 * one), ("M", "0", 4.0e4 * e4)]
    n = len(nodes)
    M = np.zeros((D, n, n))
    K = np.zeros((D, n, n))
    for X, items in ((M, masses), (K, springs)):
        for a, b, v in items:
            for p, q, s in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                if p != "0" and q != "0":
                    X[:, ix[p], ix[q]] += s * v
    # Held: T is fixed (drop it).  Released: the uniform motion of all nodes has no
    # mass (masses only between nodes): condense it out statically.
    Mh, Kh = M[:, 1:, 1:], K[:, 1:, 1:]
    u = np.ones(n) / np.sqrt(n)
    Q = np.linalg.qr(np.column_stack([u, np.eye(n)[:, 1:]]))[0][:, 1:]   # ⊥ u
    Mr = Q.T @ M @ Q
    Ku = K @ u                                   # (D, n)
    Kqu = Ku @ Q                                 # (D, n - 1)
    Kr = Q.T @ K @ Q - Kqu[:, :, None] * Kqu[:, None, :] / (Ku @ u)[:, None, None]
    return np.concatenate([Mh, Mr]), np.concatenate([Kh, Kr])


def floor(eta, omega):
    """K, roots and extremes of all designs, by hand."""
    D = eta[0].size
    X = floor_K(eta, omega)
    M, K = floor_matrices(eta)
    L = np.linalg.cholesky(M)
    Li = np.linalg.inv(L)
    lam = np.linalg.eigvalsh(Li @ K @ np.swapaxes(Li, 1, 2))    # one stacked call
    w = np.sqrt(np.maximum(lam, 0.0))
    res, anti = w[:D], w[D:]
    lo, hi = omega[0], omega[-1]
    has_zero = ((res >= lo) & (res <= hi)).any(axis=1)
    has_pole = ((anti >= lo) & (anti <= hi)).any(axis=1)
    ends = np.abs(X[:, [0, -1]])
    K_min = np.where(has_zero, 0.0, ends.min(axis=1))
    K_max = np.where(has_pole, np.inf, ends.max(axis=1))
    with np.errstate(divide="ignore"):
        Q0_max = 0.1 / K_min
    return X, res, anti, K_min, K_max, Q0_max


def core(eta, omega, text):
    ds = designs(text, dict(zip(("eta1", "eta2", "eta3", "eta4"), eta)), source="stb")
    s = ds.sweep(omega)
    flags = s.flags
    r = ds.resonances(omega_max=omega[-1] * (1 + 1e-9))
    ex = ds.extremes(omega, r, s)
    return s, flags, r, ex


BRIDGE = """\
.param k5=3e4 m1=1.2 c=5
drive V a 0 velocity=0.1
mass  ma a 0 0.5
spring k1 a b 1e5
spring k2 a c 6e4
spring k5 b c {k5}
mass  m1 b 0 {m1}
mass  m2 c 0 0.8
damper d1 c 0 {c}
"""


def nodal(repeats, big=False):
    """The bridge's designs stacked on the nodal path against one by one (see --nodal;
    with ``--big`` also D = 10,000, where the stacked residual takes the compiled kernel
    by default)."""
    for D in (100, 1_000) + ((10_000,) if big else ()):
        n = round(D ** (1 / 3))
        g = np.meshgrid(np.geomspace(1e3, 1e6, n), np.linspace(0.5, 3, n),
                        np.geomspace(1e-2, 50, D // (n * n)))
        params = dict(zip(("k5", "m1", "c"), (x.ravel() for x in g)))
        ds = designs(BRIDGE, params)
        times: list = [[], []]
        for _ in range(repeats):             # alternated
            t_b, s = cpu(lambda p=params: designs(BRIDGE, p).sweep(OMEGA), 1)
            t_1, ref = cpu(lambda ds=ds: [mechcirc.sweep(ds.design(d), OMEGA)
                                          for d in range(ds.size)], 1)
            times[0].append(t_b)
            times[1].append(t_1)
        t_b, t_1 = (float(np.median(t)) for t in times)
        dK = max(float(np.max(np.abs(s.K[d] - r.K) / np.abs(r.K))) for d, r in enumerate(ref))
        de = max(float(np.max(np.abs(s.error[d] - r.error) / r.error))
                 for d, r in enumerate(ref))
        print(f"D = {ds.size:>5,}: stacked {1e3 * t_b / ds.size:6.3f} ms/design, one by one "
              f"{1e3 * t_1 / ds.size:6.3f} ms/design, ratio {t_1 / t_b:4.2f}x; stacked "
              f"{ds.size - s.single.size}/{ds.size}; K differs by {dK:.1e}, error bound by "
              f"{de:.1e} (relative)")
    nodal_resonances(repeats)


def nodal_resonances(repeats):
    """Resonances of the bridge's designs: stacked against one by one (see --nodal)."""
    undamped = BRIDGE.replace("damper d1 c 0 {c}\n", "")
    # a mass across the bridge: a mass matrix that is not diagonal, every root polished
    across = undamped.replace("mass  m2 c 0 0.8", "mass  m2 c 0 0.8\nmass  m3 b c 0.3")
    for label, text in (("damped", BRIDGE), ("undamped", undamped), ("across", across)):
        for D in (100, 1_000):
            n = round(D ** 0.5)
            g = np.meshgrid(np.geomspace(1e3, 1e6, n), np.linspace(0.5, 3, D // n))
            resonances_against_one_by_one(label, text, dict(zip(("k5", "m1"), (
                x.ravel() for x in g))), repeats)


def damped_heald(repeats):
    """``netlists/heald_damped.mcir`` over eta1 × eta3: stacked against one by one (--damped)."""
    text = (Path(__file__).parents[1] / "netlists" / "heald_damped.mcir").read_text()
    for D in (100, 1_000):
        n = round(D ** 0.5)
        g = np.meshgrid(np.linspace(0.6, 1.0, n), np.linspace(0.7, 1.1, D // n))
        params = dict(zip(("eta1", "eta3"), (x.ravel() for x in g)))
        resonances_against_one_by_one("heald", text, params, repeats)
        extremes_against_one_by_one(text, params, repeats)


def levers(repeats):
    """Designs whose lever ratio varies (--levers): stacked against one by one, on
    ``docs/examples/lever.mcir`` with its ratio and first mass made parameters."""
    lever = (Path(__file__).resolve().parents[1] / "docs" / "examples" / "lever.mcir").read_text()
    undamped = ".param r=0.5 m=2\n" + lever.replace("ratio=0.5", "ratio=r").replace(
        "a 0 2 kg", "a 0 {m} kg")
    for label, text in (("damped", undamped + "damper d b c 3 N*s/m\n"), ("undamped", undamped)):
        for D in (100, 1_000):
            n = round(D ** 0.5)
            g = np.meshgrid(np.linspace(0.3, 4.0, n), np.geomspace(0.3, 3.0, D // n))
            resonances_against_one_by_one(label, text, dict(zip(("r", "m"), (
                x.ravel() for x in g))), repeats)


def extremes_against_one_by_one(text, params, repeats, band=(50.0, 5000.0), alone=100):
    """``Designs.extremes`` (resonances given) against ``mechcirc.peak`` (K, S and Q0)
    design by design on ``alone`` of them, alternated, per design, with the largest
    difference of the extremes' values between the two."""
    import warnings

    from mechcirc import peak

    ds = designs(text, params)
    res = ds.resonances()
    part = np.linspace(0, ds.size - 1, min(alone, ds.size)).astype(int)

    def one_by_one():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return [[peak(ds.design(d), *band, quantity=q, resonances=res.list(d))
                     for q in ("K", "S", "Q0")] for d in part]

    times: list = [[], []]
    for _ in range(repeats):             # alternated
        t_b, ex = cpu(lambda: ds.extremes(band, resonances=res), 1)
        t_1, ref = cpu(one_by_one, 1)
        times[0].append(t_b / ds.size)
        times[1].append(t_1 / part.size)
    t_b, t_1 = (float(np.median(t)) for t in times)
    dv = max(max(abs(ex.K_max[d] / k.value - 1), abs(ex.K_min[d] * s.value - 1),
                 abs(ex.Q0_max[d] / q.value - 1)) for d, (k, s, q) in zip(part, ref))
    print(f"extremes,   heald, D = {ds.size:>5,}: stacked {1e3 * t_b:6.3f} ms/design, one by "
          f"one {1e3 * t_1:6.3f} ms/design ({part.size} designs), ratio {t_1 / t_b:5.1f}x; "
          f"searched {ds.size - ex.single.size}/{ds.size}; values differ by {dv:.1e} (relative)")


def resonances_against_one_by_one(label, text, params, repeats, alone=100):
    """``Designs.resonances`` against ``find_resonances`` on ``alone`` of the designs,
    alternated, per design, with the largest difference of ω between the two."""
    import warnings

    from mechcirc.resonances import find_resonances

    ds = designs(text, params)
    part = np.linspace(0, ds.size - 1, min(alone, ds.size)).astype(int)

    def one_by_one():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return [find_resonances(ds.design(d)) for d in part]

    times: list = [[], []]
    for _ in range(repeats):             # alternated
        t_b, res = cpu(lambda: designs(text, params).resonances(), 1)
        t_1, ref = cpu(one_by_one, 1)
        times[0].append(t_b / ds.size)
        times[1].append(t_1 / part.size)
    t_b, t_1 = (float(np.median(t)) for t in times)
    dw = max((abs(a.omega - b.omega) / b.omega for d, r in zip(part, ref)
              for a, b in zip(res.list(d), r)), default=0.0)
    same = all([a.kind for a in res.list(d)] == [b.kind for b in r] for d, r in zip(part, ref))
    print(f"resonances, {label:>8}, D = {ds.size:>5,}: stacked {1e3 * t_b:6.3f} "
          f"ms/design, one by one {1e3 * t_1:6.3f} ms/design ({part.size} designs), "
          f"ratio {t_1 / t_b:5.1f}x; stacked {ds.size - res.single.size}/{ds.size}; "
          f"kinds {'equal' if same else 'DIFFER'}, ω differs by {dw:.1e} (relative)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--big", action="store_true", help="also 1e5 designs")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--nodal", action="store_true",
                    help="a bridge network on the nodal path: stacked against one by one")
    ap.add_argument("--damped", action="store_true",
                    help="heald_damped.mcir's resonances: stacked against one by one")
    ap.add_argument("--levers", action="store_true",
                    help="a lever whose ratio varies: resonances stacked against one by one")
    ap.add_argument("--no-numba", action="store_true",
                    help="hide numba (read before import, see the docstring)")
    args = ap.parse_args()
    import scipy

    text = NETLIST.read_text()
    try:
        import numba
        compiled = f"numba {numba.__version__}"
    except ImportError:
        compiled = "no numba (the numpy path over designs)"
    print(f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}, scipy {scipy.__version__}, {compiled}; "
          f"load {os.getloadavg()[0]:.2f}")
    if args.nodal or args.damped or args.levers:
        if args.nodal:
            nodal(args.repeats, args.big)
        else:
            (damped_heald if args.damped else levers)(args.repeats)
        print(f"load after: {os.getloadavg()[0]:.2f}")
        return
    rng = np.random.default_rng(21)
    core(tuple(rng.uniform(0.7, 1.1, (4, 10))), OMEGA, text)        # load the kernel
    sizes = [1_000, 10_000] + ([100_000] if args.big else [])
    for D in sizes:
        eta = tuple(rng.uniform(lo, hi, D) for lo, hi in
                    ((0.6, 1.0), (1.0, 1.5), (0.7, 1.1), (0.8, 1.2)))
        # Interleaved, in chunks of at most 20,000 designs each (memory).
        t_floor = t_core = 0.0
        worst_K = worst_w = 0.0
        same = True
        for start in range(0, D, 20_000):
            part = tuple(e[start:start + 20_000] for e in eta)
            tf, (X, res, _, K_min, K_max, _) = cpu(lambda p=part: floor(p, OMEGA),
                                                   args.repeats)
            tc, (s, _, r, ex) = cpu(lambda p=part: core(p, OMEGA, text), args.repeats)
            t_floor += tf
            t_core += tc
            worst_K = max(worst_K, float(np.max(np.abs(s.K.imag - X) / np.abs(X))))
            lo = OMEGA[0]
            mine_res = np.sort(np.where(r.kind == "resonance", r.omega, np.inf), axis=1)
            ref = np.sort(np.where(res >= lo, res, np.inf), axis=1)
            cols = min(ref.shape[1], mine_res.shape[1])
            mine_res, ref = mine_res[:, :cols], ref[:, :cols]
            k = np.isfinite(mine_res) & np.isfinite(ref)
            worst_w = max(worst_w, float(np.max(np.abs(mine_res[k] - ref[k]) / ref[k])))
            same &= bool(np.array_equal(ex.K_max == np.inf, K_max == np.inf)) and \
                bool(np.array_equal(ex.K_min == 0, K_min == 0))
        print(f"D = {D:>7,}: floor {1e6 * t_floor / D:7.1f} µs/design, mechcirc "
              f"{1e6 * t_core / D:7.1f} µs/design, ratio {t_core / t_floor:5.2f}x (goal ≤ 2x); "
              f"{D / t_core:,.0f} designs per CPU-second; batched {D - r.single.size}/{D} "
              f"of the last chunk")
        print(f"    agreement: K {worst_K:.1e}, resonance ω {worst_w:.1e} (floor unpolished), "
              f"0/inf extremes identical: {same}")
    print(f"load after: {os.getloadavg()[0]:.2f}; mechcirc {mechcirc.__version__}")


if __name__ == "__main__":
    main()
