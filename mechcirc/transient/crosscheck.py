"""Cross-check of the frequency domain of any netlist against its transients.

(a) Every resonance (K = 0: the network with the drive's nodes held) and
anti-resonance (K = ∞: the drive released, no force through it) below ω_max
against the ringing of the matching free response after an impulse: the
drive's force when held (a velocity impulse, then the drive held), the
drive's velocity when released (a force impulse).  The ringing frequencies
and decay rates are measured from the sampled time series by the matrix
pencil method (Hua & Sarkar 1990: a sum of damped exponentials fitted to the
samples), not taken from the system's eigenvalues.

(b) |Q0(ω)| (velocity drive) or |v0(ω)| (force drive) from the sweep against
the amplitude of the steady state of the harmonic transient at several ω,
one of them near the first resonance.  The steady-state amplitude is the
coefficient of the forcing frequency in a least-squares fit of the record by
the forcing sinusoid plus the damped exponentials the pencil finds in it, so
modes that have not rung down (light or no damping) do not bias it.

Clearances are taken closed (the frequency domain's reading), and said so.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..circuit import Circuit, Drive
from ..errors import MechcircError
from .simulate import transient

__all__ = ["CrossCheck", "crosscheck", "matrix_pencil"]

#: Samples handed to the matrix pencil (its SVD costs O(n³)).
PENCIL_SAMPLES = 600


@dataclass
class CrossCheck:
    """Result of :func:`crosscheck` (plain data)."""

    name: str
    drive_kind: str
    resonances: list = field(default_factory=list)
    steady_state: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def to_json(self) -> dict:
        return {"name": self.name, "drive_kind": self.drive_kind,
                "resonances": self.resonances, "steady_state": self.steady_state,
                "notes": self.notes}


def matrix_pencil(y: np.ndarray, dt: float, rel: float = 1e-9, max_order: int = 60):
    """Poles s [1/s] and complex amplitudes of y_k ≈ Σ c_i exp(s_i k dt) (Hua & Sarkar)."""
    y = np.asarray(y, float)
    n = y.size
    L = n // 3
    H = np.lib.stride_tricks.sliding_window_view(y, L + 1)       # (n − L, L + 1)
    R = np.linalg.qr(H, mode="r")          # same right singular vectors, cheaper SVD
    _, sv, Vh = np.linalg.svd(R, full_matrices=False)
    if sv[0] == 0:
        return np.zeros(0, complex), np.zeros(0, complex)
    order = int(min(max_order, np.sum(sv > rel * sv[0])))
    V = Vh[:order].T                                                 # (L + 1, order)
    z = np.linalg.eigvals(np.linalg.pinv(V[:-1]) @ V[1:])
    z = z[np.abs(z) > 1e-12]
    s = np.log(z) / dt
    amps = _amplitudes(y, s, dt)
    return s, amps


def _amplitudes(y, s, dt):
    k = np.arange(y.size)[:, None]
    Vd = np.exp(np.outer(k[:, 0] * dt, s))
    return np.linalg.lstsq(Vd, y.astype(complex), rcond=None)[0]


def _variant(circuit: Circuit, kind: str) -> Circuit:
    d = circuit.drive
    if d.kind == kind:
        new = d
    else:
        new = Drive(d.name, d.n1, d.n2, kind, 1.0, d.line, d.col)
    return dataclasses.replace(circuit, drive=new, initial=())


def _grid(omegas_lo: float, omega_hi: float, decay: float | None):
    """(t_end, dt) to see the slowest mode ring ~20 periods with the fastest resolved."""
    dt = math.pi / (2.5 * omega_hi)
    t_end = 20 * 2 * math.pi / omegas_lo
    n = t_end / dt
    if n > PENCIL_SAMPLES:
        t_end = PENCIL_SAMPLES * dt
    return t_end, dt


def crosscheck(circuit: Circuit, omega_max: float | None = None,
               n_steady: int = 4, progress=None) -> CrossCheck:
    """Run both checks on ``circuit`` (it needs a drive); see the module docstring.

    ``progress``, if given, is a :class:`mechcirc.progress.Progress`: its
    ``total`` is set to the number of transient runs and it is updated after each.
    """
    if circuit.drive is None:
        raise MechcircError("crosscheck needs a drive line in the netlist (the port whose "
                            "K(ω) is checked); 'mechcirc transient' runs without one")
    from .model import backlash_elements

    out = CrossCheck(circuit.name, circuit.drive.kind)
    if backlash_elements(circuit):
        out.notes.append("clearances (backlash=) taken as closed in both domains: the "
                         "frequency domain is linearised with contact closed")
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = circuit.resonances(None)
    out.notes.extend(str(w.message) for w in caught)
    all_omega = [r.omega for r in res if r.omega > 0]
    if omega_max is None:
        omega_max = 1.5 * max(all_omega) if all_omega else 1.0
    checked = [r for r in res if r.omega <= omega_max]
    top = max([r.omega for r in res] + [omega_max])
    first = min([r.omega for r in checked if r.kind == "resonance"] or
                [r.omega for r in checked] or [omega_max / 3])
    omegas = sorted({0.5 * first, 0.97 * first, 1.6 * first, 0.8 * omega_max}
                    if n_steady >= 4 else {0.5 * first, 0.97 * first})
    if progress is not None:
        progress.total = len({r.kind for r in checked}) + len(omegas)
    for kind, drive_kind, signal in (("resonance", "velocity", "drive_force"),
                                     ("antiresonance", "force", "drive_velocity")):
        modes = [r for r in checked if r.kind == kind]
        if not modes:
            continue
        variant = _variant(circuit, drive_kind)
        lo = min(r.omega for r in modes)
        t_end, dt = _grid(lo, top, None)
        run = transient(variant, t_end, dt, "impulse", amplitude=1.0, linearise=True)
        if progress is not None:
            progress.update()
        y = getattr(run, signal)
        # Skip the first sample: a velocity impulse makes the held drive's force
        # an impulse at t = 0 that the samples cannot carry.
        s, amps = matrix_pencil(y[1:], dt)
        # Keep the poles that carry amplitude (noise poles have ~0).
        weight = np.abs(amps)
        keep = weight > 1e-8 * (weight.max() if weight.size else 1.0)
        s = s[keep]
        for r in modes:
            entry = {"kind": kind, "omega": r.omega, "omega_d": r.omega_d, "zeta": r.zeta,
                     "ringing_omega": None, "decay": None, "rel_error": None,
                     "decay_expected": r.zeta * r.omega, "decay_rel_error": None,
                     "status": "ok", "note": ""}
            if r.omega_d <= 0:
                entry["status"] = "overdamped"
                entry["note"] = "overdamped mode: no ringing to measure"
                out.resonances.append(entry)
                continue
            cand = s[s.imag > 0]
            if cand.size == 0:
                entry["status"] = "not seen"
                entry["note"] = "no ringing component found in the response"
                out.resonances.append(entry)
                continue
            best = cand[np.argmin(np.abs(cand.imag - r.omega_d))]
            entry["ringing_omega"] = float(best.imag)
            entry["decay"] = float(-best.real)
            entry["rel_error"] = abs(best.imag - r.omega_d) / r.omega_d
            sigma = r.zeta * r.omega
            if sigma > 0:
                entry["decay_rel_error"] = abs(-best.real - sigma) / sigma
            if sigma * t_end < 0.5:
                entry["status"] = "does not ring down"
                entry["note"] = (f"decay time 1/σ = {1 / sigma if sigma > 0 else math.inf:.3g} s "
                                 f"exceeds the simulated {t_end:.3g} s: the frequency is "
                                 "measured, the decay is not meaningful")
            out.resonances.append(entry)
    # (b) steady state at several ω, one near the first resonance.
    d = circuit.drive
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")         # already reported above
        sweep = circuit.sweep(np.array(omegas))
    expected = np.abs(sweep.Q0 if d.kind == "velocity" else sweep.v0)
    for w, exp in zip(omegas, expected):
        t_end, dt = _grid(min([w] + [r.omega for r in res if r.omega > 0] or [w]),
                          max(top, w), None)
        dt = min(dt, math.pi / (4 * w))
        t_end = max(t_end, 30 * 2 * math.pi / w)
        t_end = min(t_end, PENCIL_SAMPLES * dt * 2)
        run = transient(circuit, t_end, dt, f"harmonic:{w!r}", linearise=True)
        if progress is not None:
            progress.update()
        y = run.drive_force if d.kind == "velocity" else run.drive_velocity
        measured = _steady_amplitude(y, run.time, w)
        rel = abs(measured - exp) / exp if exp > 0 else math.inf
        out.steady_state.append({"omega": float(w), "expected": float(exp),
                                 "measured": float(measured), "rel_error": float(rel)})
    return out


def _steady_amplitude(y, t, w):
    """Amplitude of the ω component: LSQ on sin/cos ω t plus the pencil's other poles."""
    dt = t[1] - t[0]
    step = max(1, -(-y.size // PENCIL_SAMPLES))
    ys, ts = y[1::step], t[1::step]
    s, _ = matrix_pencil(ys, ts[1] - ts[0])
    s = s[np.abs(s - 1j * w) > 0.02 * w]
    s = s[np.abs(s + 1j * w) > 0.02 * w]
    cols = [np.sin(w * t[1:]), np.cos(w * t[1:])]
    for si in s:
        e = np.exp(si * (t[1:] - t[1]))
        if np.all(np.isfinite(e)) and np.abs(e).max() < 1e12:
            cols.append(e.real)
            cols.append(e.imag)
    Bm = np.column_stack(cols)
    c = np.linalg.lstsq(Bm, y[1:], rcond=None)[0]
    del dt
    return float(math.hypot(c[0], c[1]))
