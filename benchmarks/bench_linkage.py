"""Benchmark: ``Linkage.solve`` / ``Linkage.motion`` against the closed form and the old path (issue 14 §5).

Measured in one run, on the same machine:

* the four-bar of Mrázek's beat-up drive (29/37/188/189 mm) written as a
  linkage TOML, 3,600 positions over one turn: ``Linkage.motion`` (closed-form
  dyads) and ``method="newton"`` against ``FourBar.evaluate`` (the closed form);
* the FNF two-crank six-bar (``examples/fnf_sixbar.toml``, a class-III group, so
  Newton): per position at 360 and 3,600 positions over one turn;
* the baselines, re-implemented here as they were before: the old path
  (a continuation step of ≤ 2° per position and point, Newton with
  ``np.linalg.solve`` restarted from the Taylor predictor, cond(J) by SVD at
  every step, a ``LinkageState`` built per position) and
  ``scipy.optimize.fsolve`` with the analytic Jacobian at every step;
* ``Linkage.solve`` (a list of ``LinkageState``) against the old path per
  position: the issue's "≥ 50× faster".

Each timing is the median of several repeats (the closed form and each
linkage path alternately); the machine is shared, so the ratios (same run) are
what to read.  The Newton path is the compiled loop when numba is installed
(the ``fast`` extra), and the batched numpy fallback is timed beside it.
Agreement with the old path is printed.

Run:  python benchmarks/bench_linkage.py
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from linkage_reference import jac, phi  # noqa: E402  (Φ and its Jacobian, written out)
from timing import wall  # noqa: E402

FOURBAR_TOML = """
name = "Mrázek beat-up four-bar"
[points]
A = [0.0, 0.0]
B = [{bx!r}, {by!r}]
C = [{cx!r}, {cy!r}]
D = [189.0, 0.0]
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 100.0
"""


CPU = {}


def interleaved(fa, fb, repeat=30, label=None):
    """Median wall times of two functions run alternately (same load for both) [s].

    The median CPU times of this process are kept in ``CPU[label]`` (the
    other jobs on the shared machine disturb them less).
    """
    ta, tb, ca, cb = [], [], [], []
    for _ in range(repeat):
        c0, t0 = time.process_time(), time.perf_counter()
        fa()
        ta.append(time.perf_counter() - t0)
        ca.append(time.process_time() - c0)
        c0, t0 = time.process_time(), time.perf_counter()
        fb()
        tb.append(time.perf_counter() - t0)
        cb.append(time.process_time() - c0)
    if label:
        CPU[label] = (float(np.median(ca)), float(np.median(cb)))
    return float(np.median(ta)), float(np.median(tb))


# ------------------------------------------------------------ the old path
def old_solve(lk, thetas, max_step_deg=2.0, use_fsolve=False):
    """The pre-issue-14 continuation, verbatim in its numerics; returns q per position."""
    from scipy.optimize import fsolve

    local, idx, rows = lk.local_offsets(), lk.link_index(), lk.constraint_rows()
    n = 3 * len(lk.links)
    nc = len(lk.cranks)
    w1 = lk.cranks[0].omega
    wmax = max(abs(c.omega) for c in lk.cranks)
    tol = 1e-12 * lk.length_scale()
    PERP = np.array([[0.0, -1.0], [1.0, 0.0]])

    def rot(phi):
        c, s = math.cos(phi), math.sin(phi)
        return np.array([[c, -s], [s, c]])

    def gamma(q, qdot):
        g = np.zeros(n)
        k = 0
        for p, a, b in rows:
            for body, sign in ((a, 1.0), (b, -1.0)):
                if body == "ground":
                    continue
                i = idx[body]
                g[k:k + 2] += sign * (rot(q[3 * i + 2]) @ local[body][p]) * qdot[3 * i + 2] ** 2
            k += 2
        return g

    def derivatives(q):
        J = jac(lk, q, local, idx, rows)
        cond = np.linalg.cond(J)
        if not np.isfinite(cond) or cond > 1e12:
            return J, None, None, None
        rhs = np.zeros((n, nc))
        for j, c in enumerate(lk.cranks):
            rhs[n - nc + j, j] = c.omega
        parts = np.linalg.solve(J, rhs)
        qdot = parts.sum(axis=1)
        return J, qdot, np.linalg.solve(J, gamma(q, qdot)), parts

    def newton(q, angles):
        if use_fsolve:
            sol, info, ier, _ = fsolve(lambda x: phi(lk, x, angles, local, idx, rows), q,
                                       fprime=lambda x: jac(lk, x, local, idx, rows),
                                       full_output=True, xtol=1e-13)
            return sol, ier == 1
        # the first release's Newton (the Linkage method it was, written out here)
        previous = np.inf
        for k in range(30):
            r = phi(lk, q, angles, local, idx, rows)
            size = np.max(np.abs(r))
            if size < tol:
                return q, True
            if k >= 2 and size > previous:
                return q, False
            previous = size
            try:
                q = q - np.linalg.solve(jac(lk, q, local, idx, rows), r)
            except np.linalg.LinAlgError:
                return q, False
            if not np.all(np.isfinite(q)):
                return q, False
        return q, np.max(np.abs(phi(lk, q, angles, local, idx, rows))) < tol

    q, t_now = lk.q0(), 0.0
    J, qdot, qddot, parts = derivatives(q)
    out = []
    for th in thetas:
        t_target = th / w1
        while t_now != t_target:
            dt_max = math.radians(max_step_deg) / wmax
            dt = max(-dt_max, min(dt_max, t_target - t_now))
            while True:
                guess = q + qdot * dt + 0.5 * qddot * dt * dt
                q_new, ok = newton(guess, [c.omega * (t_now + dt) for c in lk.cranks])
                if ok:
                    _, qd_n, qdd_n, _ = derivatives(q_new)
                    if qd_n is not None:
                        break
                dt *= 0.5
            q, qdot, qddot, t_now = q_new, qd_n, qdd_n, t_now + dt
        # the old per-position LinkageState: one dict entry per point
        for p, x in lk.pose.items():
            owner = next((l for l, ps in lk.links.items() if p in ps), None)
            if owner is not None:
                i = idx[owner]
                Rs = rot(q[3 * i + 2]) @ local[owner][p]
                _ = (q[3 * i:3 * i + 2] + Rs, qdot[3 * i:3 * i + 2] + qdot[3 * i + 2] * (PERP @ Rs))
        out.append(q.copy())
    return np.array(out)


def main() -> None:
    from mechcirc.kinematics import FourBar, load_linkage, parse_linkage

    load = os.getloadavg()
    print(f"load average at start: {load[0]:.2f} (2 cores shared)")
    fb = FourBar(29.0, 37.0, 188.0, 189.0)
    th0 = 0.0
    phi4 = fb.rocker_angle(th0)
    lk4 = parse_linkage(FOURBAR_TOML.format(bx=29.0, by=0.0, cx=189 + 188 * math.cos(phi4),
                                            cy=188 * math.sin(phi4)))
    theta = np.linspace(0.0, 2 * math.pi, 3600, endpoint=False)
    lk4.motion(theta[:10])                                   # warm (imports)

    from mechcirc import _jit
    from mechcirc.kinematics import linkage_solver

    def numpy_newton(lk, th):
        _jit.COMPILED = False
        try:
            return lk.motion(th, method="newton")
        finally:
            _jit.COMPILED = None

    lk4.motion(theta[:10], method="newton")                  # compile (or load) the kernel
    compiled = linkage_solver._compiled("newton_path")
    t_closed, t_dyads = interleaved(lambda: fb.evaluate(theta), lambda: lk4.motion(theta),
                                    repeat=100, label="dyads")
    t_closed2, t_newton4 = interleaved(lambda: fb.evaluate(theta),
                                       lambda: lk4.motion(theta, method="newton"), repeat=15,
                                       label="newton")
    t_np4 = wall(lambda: numpy_newton(lk4, theta), repeat=3)[0]
    n_old = 120
    t_old4 = wall(lambda: old_solve(lk4, theta[:n_old]), repeat=3)[0] / n_old * 3600
    t_solve4 = wall(lambda: lk4.solve(theta), repeat=5)[0]
    m = lk4.motion(theta)
    ref = old_solve(lk4, theta[:n_old])
    st = fb.evaluate(theta)
    C = m.points[:, list(m.point_names).index("C")]
    phi4_lk = np.arctan2(C[:, 1], C[:, 0] - 189.0)
    err_phi = np.max(np.abs((phi4_lk - st.phi4 + np.pi) % (2 * np.pi) - np.pi))
    i4 = list(m.link_names).index("rocker")
    err_mu = np.max(np.abs(m.angular_velocities[:, i4] / 100.0 - st.mu))
    err_nu = np.max(np.abs(m.angular_accelerations[:, i4] / 100.0 ** 2 - st.nu))

    print("\nfour-bar 29/37/188/189 mm as a linkage TOML, 3,600 positions (one turn)")
    print(f"  FourBar.evaluate (closed form)        {t_closed * 1e3:9.3f} ms")
    print(f"  Linkage.motion, dyads (closed form)   {t_dyads * 1e3:9.3f} ms   "
          f"{t_dyads / t_closed:6.2f}× the closed form (goal ≤ 3×)")
    print(f"    in CPU time: {CPU['dyads'][1] / CPU['dyads'][0]:.2f}× the closed form "
          f"({CPU['dyads'][0] * 1e3:.3f} and {CPU['dyads'][1] * 1e3:.3f} ms)")
    print(f"  Linkage.motion, method='newton'       {t_newton4 * 1e3:9.3f} ms   "
          f"{t_newton4 / t_closed2:6.2f}× the closed form "
          f"({'compiled' if compiled else 'numpy: numba not installed'})")
    print(f"  ... batched numpy Newton (no numba)   {t_np4 * 1e3:9.3f} ms   "
          f"{t_np4 / t_closed:6.2f}× the closed form")
    print(f"  Linkage.solve (LinkageState list)     {t_solve4 * 1e3:9.3f} ms   "
          f"({t_solve4 / 3600 * 1e6:.2f} µs per position)")
    print(f"  old path (measured on {n_old}, scaled)    {t_old4 * 1e3:9.1f} ms   "
          f"({t_old4 / 3600 * 1e6:.0f} µs per position)")
    print(f"  speed-up over the old path: motion {t_old4 / t_dyads:7.0f}×, "
          f"solve {t_old4 / t_solve4:6.0f}× (goal ≥ 50×)")
    print(f"  agreement with FourBar: φ4 {err_phi:.1e} rad, μ {err_mu:.1e}, ν {err_nu:.1e} 1/rad;"
          f" with the old path: q {np.max(np.abs(m.q[:n_old] - ref)):.1e}")

    six = load_linkage(ROOT / "examples" / "fnf_sixbar.toml")
    six.motion(np.radians([1.0, 2.0]))
    print("\nFNF six-bar (class-III group: Newton), one turn of crank 1")
    for n in (360, 3600):
        th = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
        t_new = wall(lambda: six.motion(th), repeat=9)[0]
        t_sol = wall(lambda: six.solve(th), repeat=9)[0]
        t_np = wall(lambda: numpy_newton(six, th), repeat=3)[0]
        print(f"  {n:5d} positions: motion {t_new / n * 1e6:6.1f} µs per position "
              f"(goal ≤ 50), solve {t_sol / n * 1e6:6.1f} µs; batched numpy Newton "
              f"{t_np / n * 1e6:6.1f} µs")
    n_ref = 60
    th = np.linspace(0.0, 2 * math.pi, 360, endpoint=False)[:n_ref]
    t_old6 = wall(lambda: old_solve(six, th), repeat=3)[0] / n_ref
    t_fs6 = wall(lambda: old_solve(six, th, use_fsolve=True), repeat=3)[0] / n_ref
    t_new6 = wall(lambda: six.solve(np.linspace(0.0, 2 * math.pi, 360,
                                                endpoint=False)), repeat=3)[0] / 360
    q_new = six.motion(th).q
    q_fs = old_solve(six, th, use_fsolve=True)
    print(f"  old path {t_old6 * 1e6:7.0f} µs, fsolve + analytic Jacobian {t_fs6 * 1e6:7.0f} µs "
          f"per position (1° steps)")
    print(f"  speed-up of solve at 360 positions: {t_old6 / t_new6:5.0f}× the old path, "
          f"{t_fs6 / t_new6:5.0f}× fsolve; agreement with fsolve: q "
          f"{np.max(np.abs(q_new - q_fs)):.1e}")
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
