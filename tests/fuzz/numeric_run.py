"""Numerical fuzz campaigns on random networks, each against an independent reference.

Not collected by pytest (a long run, as ``long_run.py``); the numbers of the
last runs are in ``docs/reliability.md`` ("Numerical campaigns").  Networks
are those of :func:`reference.mp_nodal.random_network` (meshes, levers,
values over several decades), drawn from ``--seed``::

    python tests/fuzz/numeric_run.py roots --seed 3 --count 300
    python tests/fuzz/numeric_run.py peak --seed 2 --count 300
    python tests/fuzz/numeric_run.py sensitivity --seed 1 --count 150

* ``roots``: every root of ``find_resonances`` within its stated error of the
  zero of det A (an anti-resonance, a pole of K) or of det [[A, c], [cᵀ, 0]]
  (a resonance) that mpmath finds from it (:func:`reference.mp_nodal.det_root`,
  40 digits);
* ``peak``: ``mechcirc.peak`` of |Q0| over four decades is not below the
  largest value of a dense scan (40,000 log points, then golden-section
  refinement of its five largest local maxima), |Q0| = 1/|cᵀA⁻¹c| solved here
  by ``numpy.linalg.solve`` from the element values, and equals that |Q0| at
  its own ω; where float64 says otherwise (levers can leave A ill-conditioned:
  it was off by 9e-6) both values are computed again in mpmath, and judged at
  1e-8 and 1e-10;
* ``sensitivity``: each mode's ``sensitivity`` (p/ωₙ)·∂ωₙ/∂p and
  ``zeta_sensitivity`` p·∂ζ/∂p of the first four elements, against central
  differences (p·(1 ± 1e-6)) of the determinants' roots in mpmath; an
  element left out of the dicts must move no root.

Each prints the cases outside their tolerance and a summary line.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import mechcirc  # noqa: E402
from reference import mp_nodal  # noqa: E402


def networks(seed: int, count: int, damped: bool | None = None):
    """``(index, text, spec, characteristic ω)`` of ``count`` random networks."""
    rng = np.random.default_rng(seed)
    for i in range(count):
        n = int(rng.integers(3, 8))
        d = bool(rng.random() < 0.6) if damped is None else damped
        text, spec, w = mp_nodal.random_network(rng, n_nodes=n, damped=d,
                                                levers=int(rng.integers(0, 3)),
                                                decades=float(rng.uniform(2, 10)))
        yield i, text, spec, w


def _s(r) -> complex:
    return complex(-r.zeta * r.omega, r.omega_d)


def roots(seed: int, count: int) -> int:
    bad = total = failed = 0
    for i, text, spec, _ in networks(seed, count):
        try:
            found = mechcirc.parse(text).resonances()
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            continue
        for r in found:
            total += 1
            try:
                z = mp_nodal.det_root(spec, _s(r), r.kind == "antiresonance")
            except (ValueError, ZeroDivisionError):     # mpmath's secant did not converge
                failed += 1
                continue
            if not abs(abs(z) - r.omega) <= r.error * abs(z):
                bad += 1
                print(f"net {i}: {r.kind} {r.omega!r} error {r.error:.2e}, "
                      f"true {abs(abs(z) - r.omega) / abs(z):.2e}")
    print(f"roots, seed {seed}: {count} networks, {total} roots, {bad} outside their error "
          f"({failed} without a reference: mpmath's secant did not converge)")
    return bad


def _matrices(spec):
    """Float64 nodal matrices of ``spec`` (as :func:`reference.mp_nodal._matrices`)."""
    mats, c = mp_nodal._matrices(spec, 20)
    return ({k: np.array(m.tolist(), dtype=float) for k, m in mats.items()},
            np.array(c.tolist(), dtype=float).ravel())


def _q0(mats, c, w):
    w = np.atleast_1d(np.asarray(w, dtype=float))
    A = (mats["damper"] + mats["lever"])[None] + \
        1j * (w[:, None, None] * mats["mass"][None] - mats["spring"][None] / w[:, None, None])
    x = np.linalg.solve(A, np.broadcast_to(c.astype(complex), (w.size, c.size))[..., None])
    with np.errstate(all="ignore"):
        return np.abs(1 / (x[..., 0] @ c))


def _golden_max(f, a, b, steps=80):
    """``(x, f(x))`` at the maximum of a unimodal ``f`` on [a, b]."""
    for _ in range(steps):
        m1, m2 = a + 0.382 * (b - a), a + 0.618 * (b - a)
        a, b = (m1, b) if f(m1) < f(m2) else (a, m2)
    return 0.5 * (a + b), f(0.5 * (a + b))


def peak(seed: int, count: int) -> int:
    bad = refused = 0
    for i, text, spec, wc in networks(seed, count, damped=True):
        lo, hi = wc / 100, wc * 100
        try:
            p = mechcirc.peak(mechcirc.parse(text), lo, hi)
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            refused += 1
            continue
        if p.unbounded:
            continue
        mats, c = _matrices(spec)
        w = np.geomspace(lo, hi, 40000)
        q = np.nan_to_num(_q0(mats, c, w), nan=0.0, posinf=0.0)
        local = np.flatnonzero((q[1:-1] >= q[:-2]) & (q[1:-1] >= q[2:])) + 1
        best, at_best = q.max(), w[np.argmax(q)]
        for k in local[np.argsort(q[local])[-5:]]:
            x, v = _golden_max(lambda x: _q0(mats, c, x)[0], w[k - 1], w[k + 1])
            if v > best:
                best, at_best = v, x
        at = _q0(mats, c, p.omega)[0]
        if not (best > p.value * (1 + 1e-8) or abs(at - p.value) > 1e-6 * p.value):
            continue
        # float64's solve can be off by 1e-5 where levers make A ill-conditioned:
        # the suspects again in mpmath (40 digits)
        best, at = (float(1 / abs(mp_nodal.K(spec, 1j * x, 40))) for x in (at_best, p.omega))
        if best > p.value * (1 + 1e-8) or abs(at - p.value) > 1e-10 * p.value:
            bad += 1
            print(f"net {i}: peak {p.value:.10g} at {p.omega:.8g} (|Q0| there {at:.10g}); "
                  f"scan {best:.10g} at {at_best:.8g}; note {p.note!r}")
    print(f"peak, seed {seed}: {count} networks ({refused} refused), {bad} below the scan "
          "or off their own value")
    return bad


def _scaled(spec, name: str, factor: float):
    out = dict(spec)
    out["elements"] = [(k, a, b, v * factor if e == name else v)
                       for (k, a, b, v), e in zip(spec["elements"], _names(spec))]
    out["levers"] = [lv[:5] + (lv[5] * factor if lv[0] == name else lv[5],)
                     for lv in spec["levers"]]
    return out


def _names(spec):
    return [f"e{i}" for i in range(len(spec["elements"]))]


def sensitivity(seed: int, count: int, h: float = 1e-6) -> int:
    bad = checked = 0
    for i, text, spec, _ in networks(seed, count):
        try:
            modes = mechcirc.parse(text).modes()
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            continue
        omegas = [m.resonance.omega for m in modes]
        for m in modes:
            r = m.resonance
            if r.omega_d == 0 or sum(abs(w / r.omega - 1) < 1e-3 for w in omegas) > 1:
                continue            # overdamped, or a close pair (not smooth in p)
            pole = r.kind == "antiresonance"
            for name in _names(spec)[:4]:
                try:
                    up, down = (mp_nodal.det_root(_scaled(spec, name, 1 + f), _s(r), pole)
                                for f in (h, -h))
                except (ValueError, ZeroDivisionError):     # no reference: not counted
                    continue
                fd = (abs(up) - abs(down)) / (2 * h * r.omega)
                fz = (-up.real / abs(up) + down.real / abs(down)) / (2 * h)
                s = m.sensitivity.get(name)
                sz = m.zeta_sensitivity.get(name)
                checked += 1
                if s is None:       # left out: the element must move no root
                    ok = abs(fd) < 1e-9 and abs(fz) < 1e-9
                else:
                    ok = abs(s - fd) <= 1e-6 + 1e-5 * abs(fd) and \
                        abs(sz - fz) <= 1e-6 + 1e-5 * abs(fz)
                if not ok:
                    bad += 1
                    print(f"net {i}: {r.kind} {r.omega:.8g} ({name}): sensitivity {s} "
                          f"against {fd:.8g}; of zeta {sz} against {fz:.8g}")
    print(f"sensitivity, seed {seed}: {count} networks, {checked} checked, {bad} off")
    return bad


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", choices=("roots", "peak", "sensitivity"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--count", type=int, default=100)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    return 1 if globals()[args.campaign](args.seed, args.count) else 0


if __name__ == "__main__":
    sys.exit(main())
