"""Numerical fuzz campaigns on random networks, each against an independent reference.

Not collected by pytest (a long run, as ``long_run.py``); the numbers of the
last runs are in ``docs/reliability.md`` ("Numerical campaigns").  Networks
are those of :func:`reference.mp_nodal.random_network` (meshes, levers,
values over several decades), drawn from ``--seed``::

    python tests/fuzz/numeric_run.py roots --seed 3 --count 300
    python tests/fuzz/numeric_run.py peak --seed 2 --count 300
    python tests/fuzz/numeric_run.py sensitivity --seed 1 --count 150
    python tests/fuzz/numeric_run.py periodic --seed 1 --count 150
    python tests/fuzz/numeric_run.py modes --seed 2 --count 200
    python tests/fuzz/numeric_run.py sweep_sensitivity --seed 2 --count 150
    python tests/fuzz/numeric_run.py errors --seed 2 --count 300
    python tests/fuzz/numeric_run.py periodic_table --seed 1 --count 150
    python tests/fuzz/numeric_run.py transient --seed 1 --count 200
    python tests/fuzz/numeric_run.py batch --seed 1 --count 100
    python tests/fuzz/numeric_run.py peak_k --seed 3 --count 300
    python tests/fuzz/numeric_run.py clearance --seed 1 --count 80
    python tests/fuzz/numeric_run.py crosscheck --seed 2 --count 300
    python tests/fuzz/numeric_run.py propagation --seed 2 --count 300

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
  element left out of the dicts must move no root;
* ``periodic``: ``mechcirc.periodic`` of a damped network driven by a cam
  cycle (cycloidal, 3-4-5 or harmonic law, random angles, stroke and speed),
  within its estimated error of the sum of 32,768 harmonics: the textbook
  law's dx/dθ by FFT (2²⁰ samples), K by ``numpy.linalg.solve`` of the
  element matrices (that reference's own tail is added to the allowance);
* ``modes``: each mode shape (nodes on a loaded path) against the null vector
  of A(s) or [[A, c], [cᵀ, 0]] at the determinant's zero (mpmath's SVD, 40
  digits), within 1e-7 of its largest entry, and the energy shares from that
  vector within 1e-8 (close pairs and overdamped roots left out);
* ``sweep_sensitivity``: p·∂K/∂p of ``sweep_sensitivity`` at three ω against
  central differences p·(1 ± 1e-12) of K in mpmath (60 digits), within 1e-8
  of max(|K|, |p·∂K/∂p|);
* ``errors``: K of ``sweep`` (``method="auto"`` and ``"nodal"``) at eight ω
  within its ``error`` of K in mpmath (40 digits);
* ``periodic_table``: as ``periodic``, the cycloidal or 3-4-5 cycle given as a
  table of 181, 361 or 721 rows (the cubic spline, or the quintic Hermite with
  the law's slope and curvature), within the estimate that includes the
  table's interpolation;
* ``transient``: the linear transient of a damped network without levers
  under a force step (exact propagation) within its ``error`` of scipy's
  DOP853 at rtol 1e-12 on M ẍ + D ẋ + K x = f assembled here, plus ten times
  that reference's own change from rtol 1e-11;
* ``batch``: six designs of each network (its first three values made
  ``.param``\ s, scaled by up to 10^±0.5) through ``mechcirc.designs``: K of
  the batched sweep within its ``error`` of K in mpmath, and the batched roots
  within their errors of the determinants' zeros, design by design;
* ``clearance``: free vibration of random chains (1–5 masses to the frame, up
  to two springs more) with clearances (the ElastoBacklash law) over 2–8
  periods of the slowest mode, at rtol 1e-4 … 1e-11: x within its ``error``
  of DOP853 at 1e-13 with every kink a terminal event, cross-checked against
  DOP853 stepping over the kinks (no reference where the two differ by more
  than 1e-7 of max|x|); where x is off by more than rtol × max|x| a note must
  say that rtol is not reached;
* ``crosscheck``: ``mechcirc.transient.crosscheck`` on random networks; both
  domains are exact to their stated errors (the campaigns above), so a line
  that disagrees is a defect of one of them or of the check;
* ``propagation``: each impulse response ``crosscheck`` runs (levers, rigid-body
  pairs, slow modes beside stiff ones) within its ``error`` of mpmath's
  propagation of the same state model (``expm`` of A·h at 40 digits).

Each prints the cases outside their tolerance and a summary line.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from pathlib import Path

import mpmath
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


def peak(seed: int, count: int, quantity: str = "Q0") -> int:
    bad = refused = 0
    for i, text, spec, wc in networks(seed, count, damped=True):
        lo, hi = wc / 100, wc * 100
        try:
            p = mechcirc.peak(mechcirc.parse(text), lo, hi, quantity)
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            refused += 1
            continue
        if p.unbounded:
            continue
        mats, c = _matrices(spec)
        power = -1 if quantity == "K" else 1        # |Q0| = |S| = 1/|K| at V0 = 1

        def f(x, mats=mats, c=c, power=power):
            return _q0(mats, c, x) ** power

        w = np.geomspace(lo, hi, 40000)
        q = np.nan_to_num(f(w), nan=0.0, posinf=0.0)
        local = np.flatnonzero((q[1:-1] >= q[:-2]) & (q[1:-1] >= q[2:])) + 1
        best, at_best = q.max(), w[np.argmax(q)]
        for k in local[np.argsort(q[local])[-5:]]:
            x, v = _golden_max(lambda x, f=f: f(x)[0], w[k - 1], w[k + 1])
            if v > best:
                best, at_best = v, x
        at = f(p.omega)[0]
        if not (best > p.value * (1 + 1e-8) or abs(at - p.value) > 1e-6 * p.value):
            continue
        # float64's solve can be off by 1e-5 where levers make A ill-conditioned:
        # the suspects again in mpmath (40 digits)
        best, at = (float(abs(mp_nodal.K(spec, 1j * x, 40)) ** -power) for x in (at_best, p.omega))
        if best > p.value * (1 + 1e-8) or abs(at - p.value) > 1e-10 * p.value:
            bad += 1
            print(f"net {i}: peak {p.value:.10g} at {p.omega:.8g} (|{quantity}| there "
                  f"{at:.10g}); scan {best:.10g} at {at_best:.8g}; note {p.note!r}")
    print(f"peak of |{quantity}|, seed {seed}: {count} networks ({refused} refused), {bad} "
          "below the scan or off their own value")
    return bad


def peak_k(seed: int, count: int) -> int:
    return peak(seed, count, "K")


def peak_s(seed: int, count: int) -> int:
    return peak(seed, count, "S")


def _scaled(spec, name: str, factor: float):
    out = dict(spec)
    out["elements"] = [(k, a, b, v * factor if e == name else v)
                       for (k, a, b, v), e in zip(spec["elements"], _names(spec))]
    out["levers"] = [lv[:5] + (lv[5] * factor if lv[0] == name else lv[5],)
                     for lv in spec["levers"]]
    return out


def _names(spec):
    return [f"e{i}" for i in range(len(spec["elements"]))]


def _isolated_modes(seed: int, count: int):
    """``(index, spec, Mode)`` of the modes of the random networks that are neither
    overdamped (no shape) nor one of a close pair (1e-3: not smooth in the values)."""
    for i, text, spec, _ in networks(seed, count):
        try:
            found = mechcirc.parse(text).modes()
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            continue
        omegas = [m.resonance.omega for m in found]
        for m in found:
            if m.resonance.omega_d > 0 and \
                    sum(abs(w / m.resonance.omega - 1) < 1e-3 for w in omegas) == 1:
                yield i, spec, m


def sensitivity(seed: int, count: int, h: float = 1e-6) -> int:
    bad = checked = 0
    for i, spec, m in _isolated_modes(seed, count):
        r = m.resonance
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


def _law_rate(name: str, u):
    """d/du of the normalised rise of a cam law, the textbook formulas (not mechcirc's)."""
    if name == "cycloidal":
        return 1 - np.cos(2 * np.pi * u)
    if name == "polynomial_345":
        return 30 * u**2 - 60 * u**3 + 30 * u**4
    return np.pi / 2 * np.sin(np.pi * u)                  # harmonic


def _cycle_offset(spec, Omega: float, rate, r, kref: int = 1 << 15) -> tuple[float, float]:
    """How far the periodic result ``r`` is from the sum of ``kref`` harmonics of
    dx/dθ = ``rate`` (samples over one turn, by FFT) through K solved here from the
    element values, and that sum's own tail beyond kref/2: both relative to its peak."""
    k = np.arange(1, kref + 1)
    mats, c = _matrices(spec)
    w = k * Omega
    A = (mats["damper"] + mats["lever"])[None] + 1j * (
        w[:, None, None] * mats["mass"][None] - mats["spring"][None] / w[:, None, None])
    x = np.linalg.solve(A, np.broadcast_to(c.astype(complex), (w.size, c.size))[..., None])
    Qk = 2 * Omega * (np.fft.rfft(rate) / rate.size)[1:kref + 1] / (x[..., 0] @ c)
    Q = np.real(np.exp(1j * np.outer(np.radians(r.angle_deg), k)) @ Qk)
    peak = np.abs(Q).max()
    return np.abs(Q - r.Q).max() / peak, np.abs(Qk[kref // 2:]).sum() / peak


def _null_vector(spec, s, held: bool, dps: int = 40) -> dict:
    """Node velocities of the null vector of A(s) (``held``: of [[A, c], [cᵀ, 0]]) in mpmath."""
    mats, c = mp_nodal._matrices(spec, dps)
    names = sorted(({x for _, a, b, _ in spec["elements"] for x in (a, b)} |
                    {x for lv in spec["levers"] for x in lv[1:5]}) - {"0"})
    size = c.rows + held
    with mpmath.workdps(dps):
        A = mats["damper"] + mats["lever"] + s * mats["mass"] + mats["spring"] / s
        B = mpmath.zeros(size, size)
        for i in range(c.rows):
            for j in range(c.rows):
                B[i, j] = A[i, j]
            if held:
                B[i, c.rows] = B[c.rows, i] = c[i]
        _, S, V = mpmath.svd_c(B)
        k = min(range(size), key=lambda i: abs(S[i]))
        return {x: complex(mpmath.conj(V[k, i])) for i, x in enumerate(names)}


def modes(seed: int, count: int) -> int:
    bad = checked = 0
    for i, spec, m in _isolated_modes(seed, count):
        r = m.resonance
        held = r.kind == "resonance"
        try:
            ref = _null_vector(spec, mp_nodal.det_root(spec, _s(r), not held), held)
        except (ValueError, ZeroDivisionError):     # no reference: not counted
            continue
        keys = sorted(m.shape)          # (nodes on no loaded path are left out)
        a, b = (np.array([d[x] for x in keys]) for d in (ref, m.shape))
        j = int(np.argmax(np.abs(b)))
        off = float(np.max(np.abs(a / a[j] - b / b[j])))
        v = dict(ref, **{"0": 0})
        energy = {f"e{t}": 0.5 * y * abs(v[p] - v[q]) ** 2 / (r.omega ** 2 if kind == "spring"
                                                              else 1.0)
                  for t, (kind, p, q, y) in enumerate(spec["elements"]) if kind != "damper"}
        total = sum(energy.values())
        share = max(abs(m.energy.get(x, 0.0) - e / total) for x, e in energy.items())
        checked += 1
        if off > 1e-7 or share > 1e-8:
            bad += 1
            print(f"net {i}: {r.kind} {r.omega:.8g}: shape off by {off:.2e} of its "
                  f"largest, energy shares by {share:.2e}")
    print(f"modes, seed {seed}: {count} networks, {checked} modes checked, {bad} off")
    return bad


def sweep_sensitivity(seed: int, count: int) -> int:
    from mechcirc.modes import sweep_sensitivity as sweep_sensitivity_of

    rng = np.random.default_rng(seed + 77)
    h = mpmath.mpf(10) ** -12
    bad = checked = 0
    for i, text, spec, wc in networks(seed, count):
        omega = wc * 10 ** rng.uniform(-1.5, 1.5, 3)
        names = _names(spec)[:4] + [lv[0] for lv in spec["levers"]]
        try:
            got = sweep_sensitivity_of(mechcirc.parse(text), omega, names)
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            continue
        for name in names:
            def K(f, w, name=name, spec=spec):
                el = [(kd, a, b, mpmath.mpf(y) * (f if f"e{t}" == name else 1))
                      for t, (kd, a, b, y) in enumerate(spec["elements"])]
                lv = [x[:5] + (mpmath.mpf(x[5]) * (f if x[0] == name else 1),)
                      for x in spec["levers"]]
                return mp_nodal.K({**spec, "elements": el, "levers": lv}, 1j * w, 60)
            for k, w in enumerate(omega):
                with mpmath.workdps(60):
                    d = complex((K(1 + h, w) - K(1 - h, w)) / (2 * h))
                    K0 = complex(K(mpmath.mpf(1), w))
                off = abs(got.dK[name][k] - d) / max(abs(K0), abs(d), 1e-300)
                checked += 1
                if not off <= 1e-8:
                    bad += 1
                    print(f"net {i}: {name} at {w:.6g} rad/s: p dK/dp {got.dK[name][k]:.10g} "
                          f"against {d:.10g} (K {K0:.4g}), off by {off:.2e}")
    print(f"sweep_sensitivity, seed {seed}: {count} networks, {checked} derivatives checked, "
          f"{bad} off by more than 1e-8 of max(|K|, |p dK/dp|)")
    return bad


def errors(seed: int, count: int) -> int:
    rng = np.random.default_rng(seed + 5)
    bad = checked = 0
    worst = 0.0
    for i, text, spec, wc in networks(seed, count):
        c = mechcirc.parse(text)
        w = np.sort(wc * 10 ** rng.uniform(-2, 2, 8))
        for method in ("auto", "nodal"):
            try:
                s = c.sweep(w, method=method)
                err = s.error
            except mechcirc.MechcircError:      # e.g. levers that hold the drive
                continue
            for k in np.flatnonzero(np.isfinite(err) & np.isfinite(s.K)):
                ref = complex(mp_nodal.K(spec, 1j * w[k], 40))
                if ref == 0 or not np.isfinite(abs(ref)):
                    continue
                true = abs(s.K[k] - ref) / abs(ref)
                checked += 1
                worst = max(worst, true / max(err[k], 1e-300))
                if true > err[k]:
                    bad += 1
                    print(f"net {i} ({method}) at {w[k]:.6g} rad/s: K off by {true:.2e}, "
                          f"its error {err[k]:.2e}")
    print(f"errors, seed {seed}: {count} networks, {checked} values of K checked, {bad} off by "
          f"more than their error (the largest ratio {worst:.2f})")
    return bad


def _law_cycle(law: str, rise, dwell, ret, h, t):
    """x, dx/dθ, d²x/dθ² of a rise–dwell–return cycle at θ = ``t`` (textbook formulas)."""
    lift = {"cycloidal": lambda u: u - np.sin(2 * np.pi * u) / (2 * np.pi),
            "polynomial_345": lambda u: 10 * u**3 - 15 * u**4 + 6 * u**5,
            "harmonic": lambda u: (1 - np.cos(np.pi * u)) / 2}[law]
    bend = {"cycloidal": lambda u: 2 * np.pi * np.sin(2 * np.pi * u),
            "polynomial_345": lambda u: 60 * u - 180 * u**2 + 120 * u**3,
            "harmonic": lambda u: np.pi ** 2 / 2 * np.cos(np.pi * u)}[law]
    x, dx, ddx = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
    up, back = t < rise, (t >= rise + dwell) & (t < rise + dwell + ret)
    x[(t >= rise) & (t < rise + dwell)] = h
    for part, beta, sign, t0 in ((up, rise, 1.0, 0.0), (back, ret, -1.0, rise + dwell)):
        u = (t[part] - t0) / beta
        x[part] = h * (lift(u) if sign > 0 else 1 - lift(u))
        dx[part] = sign * h / beta * _law_rate(law, u)
        ddx[part] = sign * h / beta ** 2 * bend(u)
    return x, dx, ddx


def periodic(seed: int, count: int, table: bool = False) -> int:
    from mechcirc.motion_laws import motion_table
    from mechcirc.periodic import periodic as run

    rng = np.random.default_rng(seed + (2000 if table else 1000))
    bad = checked = skipped = 0
    th = 2 * np.pi * np.arange(1 << 20) / (1 << 20)
    for i, text, spec, wc in networks(seed, count, damped=True):
        law = str(rng.choice(["cycloidal", "polynomial_345"] + ([] if table else ["harmonic"])))
        rise, dwell, ret = (np.radians(x) for x in rng.uniform([40, 0, 40], [150, 60, 150]))
        h, Omega = float(10 ** rng.uniform(-3, 0)), wc * 10 ** rng.uniform(-2, -0.5 * table)
        motion, what = None, law
        if table:
            rows, hermite = int(rng.choice([181, 361, 721])), bool(rng.random() < 0.5)
            ang = np.linspace(0, 360, rows)
            x, dx, ddx = _law_cycle(law, rise, dwell, ret, h, np.radians(ang) % (2 * np.pi))
            motion = motion_table(ang, x, slope=dx if hermite else None,
                                  curvature=ddx if hermite else None)
            what = f"{law}, a table of {rows} rows ({'quintic' if hermite else 'cubic'})"
        else:
            text = text.replace("drive V n1 0 velocity=1", (
                f"drive V n1 0 motion={law} rise={float(np.degrees(rise))!r} dwell="
                f"{float(np.degrees(dwell))!r} return={float(np.degrees(ret))!r} stroke={h!r}"))
        try:
            r = run(mechcirc.parse(text), Omega * 30 / np.pi, motion=motion)
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            r = None
        if r is None or not np.isfinite(r.error):
            skipped += 1
            continue
        off, own = _cycle_offset(spec, Omega, _law_cycle(law, rise, dwell, ret, h, th)[1], r)
        checked += 1
        if off > r.error + own + 1e-12:
            bad += 1
            print(f"net {i}: {what} at {Omega * 30 / np.pi:.6g} rpm, {r.harmonics} harmonics: "
                  f"off by {off:.2e} of the peak, estimated {r.error:.2e}")
    print(f"periodic{'_table' * table}, seed {seed}: {checked} checked ({skipped} with no "
          f"finite estimate or refused), {bad} beyond their estimate")
    return bad


def periodic_table(seed: int, count: int) -> int:
    return periodic(seed, count, table=True)


def transient(seed: int, count: int) -> int:
    from scipy.integrate import solve_ivp

    from mechcirc.transient import transient as run

    rng = np.random.default_rng(seed)
    bad = checked = 0
    for i in range(count):                  # (no levers: the reference has no constraints)
        text, spec, wc = mp_nodal.random_network(rng, n_nodes=int(rng.integers(2, 6)),
                                                 damped=True, decades=float(rng.uniform(1, 4)))
        mats, _ = _matrices(spec)
        M, D, K = (mats[k] for k in ("mass", "damper", "spring"))
        if np.linalg.cond(M) > 1e8:         # (massless nodes: not an ODE in x here)
            continue
        names = sorted({x for _, a, b, _ in spec["elements"] for x in (a, b)} - {"0"})
        f = np.zeros(len(names))
        f[names.index("n1")] = 1.0
        Minv = np.linalg.inv(M)
        T = 20 / wc
        try:
            r = run(mechcirc.parse(text.replace("velocity=1", "force=1")), T, T / 400, "step")
        except mechcirc.MechcircError:
            continue

        def rhs(t, y, f=f, Minv=Minv, D=D, K=K):
            n = f.size
            return np.concatenate([y[n:], Minv @ (f - D @ y[n:] - K @ y[:n])])

        ref, loose = (solve_ivp(rhs, (0, r.time[-1]), np.zeros(2 * len(names)), method="DOP853",
                                rtol=tol, atol=1e-22, t_eval=r.time).y[:len(names)].T
                      for tol in (1e-12, 1e-11))
        x = r.x[:, [r.nodes.index(nm) for nm in names]]
        # (``error`` is in x's unit: both sides absolute)
        off, own = np.max(np.abs(x - ref)), 10 * np.max(np.abs(loose - ref))
        checked += 1
        if off > r.error + own:
            bad += 1
            print(f"net {i}: x off by {off:.2e} m, estimated {r.error:.2e} (the reference's "
                  f"own allowance {own:.1e}; max|x| {np.max(np.abs(ref)):.2e})")
    print(f"transient, seed {seed}: {checked} networks checked, {bad} beyond their estimate")
    return bad


def _plain_reference(m, springs, y0, t, rtol=1e-13):
    """x on ``t`` of DOP853 at ``rtol`` on the whole law, stepping over its kinks."""
    from reference.transient_corpus import _law
    from scipy.integrate import solve_ivp

    n, m = len(m), np.asarray(m, float)

    def rhs(_, y):
        a = np.zeros(n)
        for i, j, c, d, b in springs:
            xi, vi = (y[i], y[n + i]) if i >= 0 else (0.0, 0.0)
            xj, vj = (y[j], y[n + j]) if j >= 0 else (0.0, 0.0)
            f = _law(xi - xj, vi - vj, c, b, d)
            if i >= 0:
                a[i] -= f
            if j >= 0:
                a[j] += f
        return np.concatenate([y[n:], a / m])

    return solve_ivp(rhs, (0, t[-1]), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-3,
                     t_eval=t).y[:n].T


def clearance(seed: int, count: int) -> int:
    """Free vibration of random chains with clearances (the ElastoBacklash law) from random
    initial velocities, at a random ``rtol``: x within its ``error`` of the event-located
    reference of ``tests/test_transient_kinks.py`` (DOP853 at rtol 1e-13, every kink a
    terminal event), plus ten times that reference's change from rtol 1e-12 and its
    distance from DOP853 stepping over the kinks; where x is off by more than ``rtol`` ×
    max|x|, a note must say that ``rtol`` is not reached."""
    from test_transient_kinks import _event_reference

    from mechcirc.transient import transient as run

    rng = np.random.default_rng(seed + 5000)
    bad = checked = 0
    for i in range(count):
        n = int(rng.integers(1, 6))
        m = [float(x) for x in 10 ** rng.uniform(-1, 1, n)]
        springs, lines = [], [f"mass m{k} n{k} 0 {m[k]!r}" for k in range(n)]
        # the chain from the frame, then up to two springs more (to the frame or across)
        pairs = [(k - 1, k) for k in range(n)] + [
            tuple(sorted(rng.choice(np.arange(-1, n), 2, replace=False)))
            for _ in range(int(rng.integers(0, 3)))]
        v0 = [float(x) for x in rng.uniform(-1, 1, n)]
        for j, (a, b) in enumerate(pairs):
            a, b = int(a), int(b)
            c = float(10 ** rng.uniform(3, 5))
            zeta = 0.0 if rng.random() < 0.2 else float(10 ** rng.uniform(-3, -0.5))
            d = 2 * zeta * math.sqrt(c * m[max(a, b)])
            amp = 1 / math.sqrt(c / m[max(a, b)])         # (a speed of 1 against this spring)
            gap = 0.0 if rng.random() < 0.3 else amp * float(10 ** rng.uniform(-3, 0.3))
            springs.append((a, b, c, d, gap))
            extra = (f" backlash={gap!r}" if gap else "") + (f" damping={d!r}" if d else "")
            ends = ["0" if k < 0 else f"n{k}" for k in (a, b)]
            lines.append(f"spring k{j} {ends[0]} {ends[1]} {c!r}{extra}")
        if not any(s[4] for s in springs):
            continue
        lines += [f".ic n{k} v={v0[k]!r}" for k in range(n)]
        w_max = max(math.sqrt(c / min(m)) for _, _, c, _, _ in springs)
        T = float(rng.uniform(2, 8)) * 2 * math.pi / math.sqrt(
            min(c for *_, c, _, _ in springs) / max(m))
        T = min(T, 4000 / w_max)                  # (a bounded number of steps)
        rtol = 10.0 ** -int(rng.integers(4, 12))
        c_ = mechcirc.parse("\n".join(lines) + "\n", require_drive=False)
        try:
            r = run(c_, T, T / 500, rtol=rtol)
        except mechcirc.MechcircError as err:
            print(f"net {i}: refused: {err}")
            continue
        y0 = np.concatenate([np.zeros(n), v0])
        ref, loose = (_event_reference(m, springs, y0, r.time, rtol=tol)
                      for tol in (1e-13, 1e-12))
        # The events are found where their function changes sign between two steps: one
        # that crosses twice inside a step is missed (seed 1, network 29: 2.3e-6 off
        # from t = 1.31 s).  DOP853 stepping over the kinks at 1e-13 is the second
        # reference; where the two differ by more than 1e-7 of max|x|, neither is used.
        plain = _plain_reference(m, springs, y0, r.time)
        x = np.column_stack([r.node(f"n{k}")[0] for k in range(n)])
        scale = np.abs(ref).max()
        if np.abs(plain - ref).max() > 1e-7 * scale:
            print(f"net {i}: no reference (the event-located and the plain one differ by "
                  f"{np.abs(plain - ref).max() / scale:.1e} of max|x|)")
            continue
        off = np.abs(x - ref).max()
        own = 10 * np.abs(loose - ref).max() + np.abs(plain - ref).max()
        said = any("not reached" in note for note in r.notes)
        checked += 1
        if off > r.error + own or (off > rtol * scale + own and not said):
            bad += 1
            print(f"net {i} ({n} masses, rtol {rtol:.0e}): x off by {off:.2e}, estimated "
                  f"{r.error:.2e} (the references' own allowance {own:.1e}); rtol x max|x| "
                  f"{rtol * scale:.2e}, 'not reached' said: {said}")
    print(f"clearance, seed {seed}: {checked} networks checked, {bad} beyond their estimate "
          "or over rtol unsaid")
    return bad


def crosscheck(seed: int, count: int) -> int:
    """``mechcirc.transient.crosscheck`` on random networks: the frequency domain and the
    transients are each exact to their stated errors (the ``roots``, ``errors`` and
    ``transient`` campaigns), so a line that *disagrees* is a false alarm of the check;
    also counts the lines that cannot be measured, with their reasons."""
    from collections import Counter

    from mechcirc.transient import crosscheck as check

    bad = checked = lines = 0
    why: Counter = Counter()
    for i, text, _, _ in networks(seed, count):
        try:
            cc = check(mechcirc.parse(text), n_steady=2)
        except mechcirc.MechcircError as err:
            why[f"refused: {str(err)[:60]}"] += 1
            continue
        checked += 1
        for row in cc.resonances + cc.steady_state:
            lines += 1
            if row["verdict"] == "disagrees":
                bad += 1
                print(f"net {i}: disagrees: {row}")
            elif row["verdict"] != "agrees":
                why[str(row.get("why"))[:70]] += 1
    print(f"crosscheck, seed {seed}: {checked} networks, {lines} lines, {bad} disagree; "
          f"not measured or refused: {dict(why.most_common(8))}")
    return bad


def propagation(seed: int, count: int, dps: int = 40) -> int:
    """The linear transient's ``error`` against mpmath's propagation of its own state
    model (``expm`` of A·h at ``dps`` digits, z₀ = the initial state + B): the impulse
    responses ``crosscheck`` rings (levers, rigid-body pairs, stiff and slow modes; the
    ``transient`` campaign has none of these), models of up to 14 states."""
    from mechcirc.transient import _crosscheck
    from mechcirc.transient.model import drive_map
    from mechcirc.transient.simulate import state_model

    runs: list = []
    original = _crosscheck.transient

    def spy(*args, **kw):
        r = original(*args, **kw)
        if args[3] == "impulse":
            runs.append((args[0], r))
        return r

    _crosscheck.transient = spy
    bad = checked = 0
    ratios: list = []
    drive_ratios: list = []
    try:
        for i, text, _, _ in networks(seed, count):
            runs.clear()
            try:
                _crosscheck.crosscheck(mechcirc.parse(text), n_steady=0)
            except mechcirc.MechcircError:
                continue
            for circuit, r in runs:
                ss = state_model(circuit, True)
                if ss.A.shape[0] > 14 or r.time.size < 2 or not math.isfinite(r.error):
                    continue
                y = r.drive_force if r.drive_force is not None else r.drive_velocity
                rows = ss.Cx if r.drive_error is None else np.vstack([ss.Cx, drive_map(ss)[0]])
                with mpmath.workdps(dps):
                    P = mpmath.expm(mpmath.matrix(ss.A.tolist())
                                    * mpmath.mpf(float(r.time[1] - r.time[0])))
                    z = mpmath.matrix((ss.initial[0] + ss.B).tolist())
                    C, X = mpmath.matrix(rows.tolist()), []
                    for _ in range(r.time.size):
                        X.append([float(v) for v in C * z])
                        z = P * z
                X = np.array(X)
                true = float(np.abs(r.x - X[:, :ss.Cx.shape[0]]).max())
                checked += 1
                ratios.append(true / r.error if r.error > 0 else math.inf)
                if true > r.error:
                    bad += 1
                    print(f"net {i}: error {true:.3g} above its estimate {r.error:.3g} "
                          f"({r.method})")
                if r.drive_error is not None:       # the drive's output w·z, its own error
                    true_y = float(np.abs(y - X[:, -1]).max())
                    drive_ratios.append(true_y / r.drive_error if r.drive_error > 0 else math.inf)
                    if true_y > r.drive_error:
                        bad += 1
                        print(f"net {i}: the drive's output {true_y:.3g} off, above its "
                              f"estimate {r.drive_error:.3g} ({r.method})")
    finally:
        _crosscheck.transient = original
    print(f"propagation, seed {seed}: {checked} runs, {bad} above their error (x or the "
          f"drive's output); true/estimate largest {max(ratios, default=0):.3g}, median "
          f"{np.median(ratios or [0]):.3g}; the drive's output ({len(drive_ratios)} runs) "
          f"largest {max(drive_ratios, default=0):.3g}")
    return bad


def batch(seed: int, count: int, designs: int = 6) -> int:
    rng = np.random.default_rng(seed + 4000)
    bad = checked = 0
    for i, text, spec, wc in networks(seed, count):
        lines = text.splitlines()
        base = [v for _, _, _, v in spec["elements"][:3]]
        for t in range(3):                  # the first three values become .params
            lines[t + 1] = " ".join(lines[t + 1].split()[:4] + [f"{{p{t}}}"])
        text = "\n".join([f".param p{t}={v!r}" for t, v in enumerate(base)] + lines) + "\n"
        scale = 10 ** rng.uniform(-0.5, 0.5, (3, designs))
        params = {f"p{t}": base[t] * scale[t] for t in range(3)}
        w = np.sort(wc * 10 ** rng.uniform(-1.5, 1.5, 4))
        try:
            ds = mechcirc.designs(text, params)
            sw, res = ds.sweep(w), ds.resonances()
        except mechcirc.MechcircError:      # e.g. levers that hold the drive
            continue
        for d in range(designs):
            one = {**spec, "elements": [(k, a, b, float(params[f"p{t}"][d]) if t < 3 else v)
                                        for t, (k, a, b, v) in enumerate(spec["elements"])]}
            for k in range(w.size) if d not in sw.failed else ():
                ref = complex(mp_nodal.K(one, 1j * w[k], 40))
                if not np.isfinite(sw.error[d, k]) or ref == 0 or not np.isfinite(abs(ref)):
                    continue
                checked += 1
                if abs(sw.K[d, k] - ref) > sw.error[d, k] * abs(ref):
                    bad += 1
                    print(f"net {i} design {d}: K at {w[k]:.6g} off by "
                          f"{abs(sw.K[d, k] - ref) / abs(ref):.2e}, its error {sw.error[d, k]:.2e}")
            for j in range(int(res.count[d])) if d not in res.failed else ():
                kind, wn, wd, z, e = (res.kind[d, j], res.omega[d, j], res.omega_d[d, j],
                                      res.zeta[d, j], res.error[d, j])
                try:
                    root = mp_nodal.det_root(one, complex(-z * wn, wd), kind == "antiresonance")
                except (ValueError, ZeroDivisionError):     # no reference: not counted
                    continue
                checked += 1
                if not abs(abs(root) - wn) <= e * abs(root):
                    bad += 1
                    print(f"net {i} design {d}: {kind} {wn!r} error {e:.2e}, true "
                          f"{abs(abs(root) - wn) / abs(root):.2e}")
    print(f"batch, seed {seed}: {count} networks of {designs} designs, {checked} values of K "
          f"and roots checked, {bad} outside their error")
    return bad


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", choices=("roots", "peak", "sensitivity", "periodic", "modes",
                                         "sweep_sensitivity", "errors", "periodic_table",
                                         "transient", "batch", "peak_k", "peak_s",
                                         "clearance", "crosscheck", "propagation"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--count", type=int, default=100)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    return 1 if globals()[args.campaign](args.seed, args.count) else 0


if __name__ == "__main__":
    sys.exit(main())
