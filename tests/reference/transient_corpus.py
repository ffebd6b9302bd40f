"""A corpus for the clearance integrator's error estimate, with independent references.

Every case is a plain description (masses to the frame, springs between
nodes with an optional clearance and its damping, a drive, the initial
state); mechcirc gets it as netlist text, and the reference integrates
equations written here from the same description — the ElastoBacklash law
from the Modelica documentation, the drive's waveform by hand — with
scipy's ``solve_ivp`` (DOP853, rtol 1e-13, atol 1e-13 × the scale of each
state), never mechcirc's code.  The law has kinks; the reference steps
across them under its error control (no event location), so its own
accuracy is checked by a second reference at rtol 1e-12: :func:`reference`
returns both, and the corpus only counts runs whose true error is at
least 10× the two references' distance.

Families: a stiff stop (contact 1e9 N/m against 1e3), a soft one (5 and
50 N/m, periods of seconds), a micrometre
clearance under a harmonic velocity drive, a 10-mass chain with gaps in
every other spring, a damped stop chattering under a constant force, the
MSL backlash example (rotational) and a velocity drive given by samples.
``python tests/reference/transient_corpus.py`` prints the table of
``docs/transient.md``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)


def _sampled(t):
    return 1e-2 * np.sin(50 * t) + 1e-3 * np.sin(130 * t)


#: name -> (masses {node: m}, springs [(p, q, k, backlash, damping)],
#: drive (node, "velocity" | "force", amplitude, waveform) or None,
#: initial state {node: (x, v)}, t_end, dt).  The waveform: ("harmonic", ω),
#: ("step",) or ("callable", f).
CASES = {
    "stiff stop": ({"a": 1.0}, [("a", "0", 1e3, 0.0, 0.0), ("a", "0", 1e9, 2e-3, 0.0)],
                   None, {"a": (0.0, 0.1)}, 0.2, 1e-4),
    # a soft spring and a soft stop: slow motions of decimetres (periods of seconds)
    "soft stop": ({"a": 2.0}, [("a", "0", 5.0, 0.0, 0.0), ("a", "0", 50.0, 0.05, 0.5)],
                  None, {"a": (0.0, 0.3)}, 10.0, 1e-2),
    "µm clearance": ({"a": 0.5}, [("b", "a", 1e5, 1e-6, 5.0), ("a", "0", 1e3, 0.0, 0.0)],
                     ("b", "velocity", 1e-4, ("harmonic", 50.0)), {}, 0.3, 1e-4),
    "chain with gaps": ({f"n{i}": 1.0 for i in range(10)},
                        [(f"n{i}", f"n{i + 1}", 1e4, 1e-3 if i % 2 == 0 else 0.0, 0.0)
                         for i in range(9)] + [("n9", "0", 1e4, 0.0, 0.0)],
                        None, {"n0": (0.0, 0.5)}, 0.5, 1e-3),
    "chatter": ({"a": 1.0}, [("a", "0", 1e7, 2e-3, 20.0)], ("a", "force", 10.0, ("step",)),
                {"a": (0.0, -0.3)}, 0.3, 1e-4),
    "MSL backlash": ({"phi": 5.0, "phi2": 5.0},
                     [("phi", "0", 20e3, math.pi / 4, 50.0), ("phi2", "0", 20e3, 0.0, 50.0)],
                     None, {"phi": (math.pi / 2, 0.0), "phi2": (math.pi / 2, 0.0)}, 1.0, 1e-3),
    "sampled drive": ({"a": 0.5}, [("b", "a", 1e5, 1e-4, 5.0), ("a", "0", 1e3, 0.0, 0.0)],
                      ("b", "velocity", 1.0, ("callable", _sampled)), {}, 0.1, 1e-5),
}


def netlist(case) -> str:
    masses, springs, drive, ic, _, _ = case
    lines = [f"mass m{i} {n} 0 {m!r}" for i, (n, m) in enumerate(masses.items())]
    for i, (p, q, k, b, d) in enumerate(springs):
        extra = f" backlash={b!r} damping={d!r}" if b else (f" damping={d!r}" if d else "")
        lines.append(f"spring k{i} {p} {q} {k!r}{extra}")
    if drive:
        node, kind, amp, _ = drive
        lines.append(f"drive D {node} 0 {kind}={amp!r}")
    lines += [f".ic {n} x={x!r} v={v!r}" for n, (x, v) in ic.items()]
    return "\n".join(lines) + "\n"


def waveform(case):
    """What mechcirc's ``transient`` is given as the drive (None: at rest)."""
    drive = case[2]
    if drive is None:
        return None
    wave = drive[3]
    return {"harmonic": lambda: f"harmonic:{wave[1]!r}", "step": lambda: "step",
            "callable": lambda: wave[1]}[wave[0]]()


def _law(e, v, k, b, d):
    """Force of an ElastoBacklash (Modelica docs) or a spring ∥ damper (b = 0)."""
    if not b:
        return k * e + d * v
    if e > b / 2:
        fc, fd = k * (e - b / 2), d * v
        return 0.0 if fc + fd <= 0 else fc + min(fc, fd)
    if e < -b / 2:
        fc, fd = k * (e + b / 2), d * v
        return 0.0 if fc + fd >= 0 else fc + max(fc, fd)
    return 0.0


def _prescribed(case):
    """(x(t), v(t)) of a velocity-driven node, by hand: sin for a harmonic drive
    (x = A(1 − cos ωt)/ω), the samples on the output grid interpolated linearly
    (x their exact integral) for a function of t."""
    _, _, (node, kind, amp, wave), _, t_end, dt = case
    if wave[0] == "harmonic":
        w = wave[1]
        return lambda t: (amp * (1 - math.cos(w * t)) / w, amp * math.sin(w * t))
    ts = np.arange(int(round(t_end / dt)) + 1) * dt
    vs = amp * wave[1](ts)
    xs = np.concatenate([[0.0], np.cumsum((vs[1:] + vs[:-1]) / 2 * np.diff(ts))])

    def f(t):
        i = min(max(int(np.searchsorted(ts, t, side="right")) - 1, 0), ts.size - 2)
        s = t - ts[i]
        slope = (vs[i + 1] - vs[i]) / (ts[i + 1] - ts[i])
        return xs[i] + vs[i] * s + slope * s * s / 2, vs[i] + slope * s
    return f


def reference(case, rtol: float = 1e-13):
    """x of every mass node on the output grid, shape (n_t, n_masses), by solve_ivp."""
    masses, springs, drive, ic, t_end, dt = case
    names = list(masses)
    idx = {n: i for i, n in enumerate(names)}
    m = np.array([masses[n] for n in names])
    n = len(names)
    pres = _prescribed(case) if drive and drive[1] == "velocity" else None
    force = drive[2] if drive and drive[1] == "force" else 0.0

    def f(t, y):
        x, v = y[:n], y[n:]
        xd, vd = pres(t) if pres else (0.0, 0.0)

        def at(node):
            if node == "0":
                return 0.0, 0.0
            if node in idx:
                return x[idx[node]], v[idx[node]]
            return xd, vd
        acc = np.zeros(n)
        for p, q, k, b, d in springs:
            (xp, vp), (xq, vq) = at(p), at(q)
            F = _law(xp - xq, vp - vq, k, b, d)      # tension: pulls q towards p
            if p in idx:
                acc[idx[p]] -= F
            if q in idx:
                acc[idx[q]] += F
        if force:
            acc[idx[drive[0]]] += force
        return np.concatenate([v, acc / m])

    y0 = np.zeros(2 * n)
    for node, (x0, v0) in ic.items():
        y0[idx[node]], y0[n + idx[node]] = x0, v0
    t = np.arange(int(round(t_end / dt)) + 1) * dt
    t[-1] = min(t[-1], t_end)
    # atol: rtol × a scale of each state (a loose first run gives it).
    loose = solve_ivp(f, (0, t[-1]), y0, method="DOP853", rtol=1e-6, atol=1e-12, t_eval=t)
    scale = np.maximum(np.abs(loose.y).max(axis=1), 1e-300)
    sol = solve_ivp(f, (0, t[-1]), y0, method="DOP853", rtol=rtol, atol=rtol * scale, t_eval=t)
    return t, sol.y[:n].T


#: The references solved so far: (repr of the case, rtol) -> (t, x).
_REFERENCES: dict = {}


def _reference_once(case, rtol: float = 1e-13):
    """:func:`reference` (SciPy's, never mechcirc's), solved once per process for a case
    and rtol: tests/test_transient_estimates.py measures the µm clearance twice."""
    key = (repr(case), rtol)
    if key not in _REFERENCES:
        _REFERENCES[key] = reference(case, rtol)
    t, x = _REFERENCES[key]
    return t.copy(), x.copy()


def measure(names=None, rtols=RTOLS):
    """Rows (case, rtol, estimate, true error, reference's own spread, peak |x|, 'not
    reached' said) for every case and rtol."""
    import warnings

    import mechcirc
    from mechcirc.transient import transient

    rows = []
    for name in names or CASES:
        case = CASES[name]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c = mechcirc.parse(netlist(case), require_drive=False)
        t, ref = _reference_once(case)
        _, ref2 = _reference_once(case, 1e-12)
        spread = float(np.abs(ref - ref2).max())
        for rtol in rtols:
            r = transient(c, case[4], case[5], waveform(case), rtol=rtol)
            x = np.column_stack([r.node(nd)[0] for nd in case[0]])
            true = float(np.abs(x - ref).max())
            said = any("not reached" in s for s in r.notes)
            rows.append((name, rtol, float(r.error), true, spread,
                         float(np.abs(ref).max()), said))
    return rows


def markdown(rows) -> str:
    out = ["| case | rtol | estimate | true error | estimate / true | true / max\\|x\\| "
           "| said \"not reached\" |", "|---|---|---|---|---|---|---|"]
    for name, rtol, est, true, _, peak, said in rows:
        ratio = est / true if true > 0 else math.inf
        out.append(f"| {name} | {rtol:.0e} | {est:.2e} | {true:.2e} | {ratio:.3g} | "
                   f"{true / peak:.1e} | {'yes' if said else 'no'} |")
    return "\n".join(out)


if __name__ == "__main__":
    import time

    t0 = time.process_time()
    rows = measure()
    print(markdown(rows))
    usable = [r for r in rows if r[3] >= 10 * r[4]]
    under = [r for r in usable if r[2] < r[3]]
    print(f"\n# {len(rows)} runs, {len(usable)} with a true error ≥ 10× the references' "
          f"spread; estimate < true in {len(under)}; estimate 0 in "
          f"{sum(r[2] == 0 for r in rows)}; {time.process_time() - t0:.0f} s CPU")
    for r in under:
        print("# under:", r)
