"""Cross-check of the frequency domain of any netlist against its transients.

(a) Every resonance (K = 0: the network with the drive's nodes held) and
anti-resonance (K = ∞: the drive released, no force through it) below ω_max
against the ringing of the matching free response after an impulse: the
drive's force when held (a velocity impulse, then the drive held), the
drive's velocity when released (a force impulse).  The ringing frequencies
and decay rates are measured from the sampled time series by the matrix
pencil method (Hua & Sarkar 1990: a sum of damped exponentials fitted to the
samples), not taken from the system's eigenvalues.  The sampling step is set
by the oscillating modes only (an overdamped mode, e.g. the first-order time
constant c/k of a massless damped node, has no ringing to resolve); modes
more than ``GROUP_RATIO`` apart in frequency get records of their own, so
every record spans several periods of each mode it checks.

(b) |Q0(ω)| (velocity drive) or |v0(ω)| (force drive) from the sweep against
the amplitude of the harmonic transient at several ω, one of them near the
first resonance.  The transient is not waited on to ring down (a lightly
damped mode needs thousands of periods): it starts in the periodic steady
state of the linear model (``transient(..., steady=True)``) and runs three
periods; the amplitude is the least-squares sinusoid at ω, and the record's
departure from that sinusoid (it would grow if the time stepping did not
keep the state periodic) is part of the check.

Every line carries a verdict (:func:`mechcirc.verdict.judge`): ``agrees``
(difference within the stated tolerance), ``disagrees`` (beyond it) or
``cannot be measured`` (and why); :func:`mechcirc.verdict.summarise` gives the
overall verdict, shared with the scene and sley cross-checks.  Clearances
are taken closed (the frequency domain's reading), and said so.
"""

from __future__ import annotations

import cmath
import dataclasses
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la

from ..circuit import Circuit
from ..errors import MechcircError
from ..identify import fit_sinusoid, judge_pole, nearest_pole, pole_of, pole_weights, poles
from ..verdict import DISAGREES, checked_repr, judge, summarise
from .model import backlash_elements
from .propagate import ROUNDING_PER_STEP, step_maps
from .simulate import periodic_start, state_model, transient, with_oscillator
from .waveform import Waveform

__all__ = ["CrossCheck", "crosscheck"]

#: Samples handed to the matrix pencil (:func:`mechcirc.identify.poles`; its SVD costs O(n³)).
PENCIL_SAMPLES = 600
#: Largest ratio of the fastest to the slowest mode checked on one record
#: (600 samples at 5 per period of the fastest: ≥ 4 periods of the slowest).
GROUP_RATIO = 25.0
#: Tolerance of a ringing pole, |s_time − s_freq| / |s_freq| (the samples are
#: exact: achieved ≤ 1.3e-13 on the shipped netlists and the regression cases in tests/;
#: widened to 10× the resonance's own error estimate when that is larger).
TOL_RINGING = 1e-9
#: Tolerance of a steady-state amplitude and of the record's departure from a
#: sinusoid, relative (achieved ≤ 1.6e-13; widened to 10× the sweep's error bound).
TOL_STEADY = 1e-9
#: A resonance this close (relative, in the s-plane) to an anti-resonance
#: nearly cancels at the drive and cannot be measured there.
CANCEL = 1e-6
#: ... and within this, where the record holds no ringing of its own (:func:`_judge_mode`)
WEAK = 1e-4
#: Largest relative spread of a pole between two records for it to be measured.
MAX_SPREAD = 1e-3

@dataclass
class CrossCheck:
    """Result of :func:`crosscheck` (plain data); ``verdict`` as
    :func:`mechcirc.verdict.summarise`."""

    __repr__ = checked_repr

    name: str
    drive_kind: str
    resonances: list = field(default_factory=list)
    steady_state: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    @property
    def verdict(self) -> dict:
        return summarise(self.resonances + self.steady_state)

    def to_json(self) -> dict:
        return {"name": self.name, "drive_kind": self.drive_kind,
                "verdict": self.verdict["verdict"], "summary": self.verdict,
                "resonances": self.resonances, "steady_state": self.steady_state,
                "notes": self.notes}


def _groups(modes, ratio=GROUP_RATIO):
    """Oscillating modes in groups of frequency spread ≤ ``ratio`` (ascending)."""
    out = []
    for r in sorted(modes, key=lambda r: r.omega):
        if out and r.omega <= ratio * out[-1][0].omega:
            out[-1].append(r)
        else:
            out.append([r])
    return out


def _poles(rec, dt):
    """Oscillating poles that carry amplitude (noise poles have ~0) in the record ``rec``."""
    if not np.any(rec):
        return np.zeros(0, complex)
    s = poles(rec, dt)
    weight = pole_weights(rec, dt, s)
    return s[(weight > 1e-8 * (weight.max() if weight.size else 1.0)) & (s.imag > 0)]


def _ringing(circuit, kind, modes, others, out, progress):
    """Judge the ringing of ``modes`` (all of one ``kind``) into ``out.resonances``.

    ``others``: the modes of the other kind.  A mode with one of them within
    ``CANCEL`` (relative) nearly cancels at the drive (its residue there is
    about their distance): it cannot be measured.  The pencil runs on the whole
    record and on its first and last two thirds; the largest distance of the
    poles found is the measurement's uncertainty (tolerance ≥ 100× it; above ``MAX_SPREAD``
    the mode is too weak in the record to be measured).
    """
    drive_kind, signal = (("velocity", "drive_force") if kind == "resonance"
                          else ("force", "drive_velocity"))
    # the circuit driven by drive_kind: the other kind at unit amplitude; rotary stays
    # rotary (its labels), a motion law belongs to the velocity drive only
    d = circuit.require_drive()
    variant = dataclasses.replace(circuit, initial=(), drive=d if d.kind == drive_kind else
                                  dataclasses.replace(d, kind=drive_kind, amplitude=1.0,
                                                      motion=None))
    rows = {}
    for r in modes:
        rows[id(r)] = {"kind": kind, "omega": r.omega, "omega_d": r.omega_d, "zeta": r.zeta,
                       "ringing_omega_d": None, "decay": None, "decay_expected": r.zeta * r.omega,
                       "rel_error": None, "decay_rel_error": None}
        if r.omega_d <= 0:
            judge(rows[id(r)], None, TOL_RINGING,
                  f"overdamped (time constant {1 / r.omega:.3g} s): no ringing to measure")
    for group in _groups([r for r in modes if r.omega_d > 0]):
        lo, top = group[0].omega, group[-1].omega
        dt = math.pi / (2.5 * top)
        t_end = min(20 * 2 * math.pi / lo, PENCIL_SAMPLES * dt)
        run = transient(variant, t_end, dt, "impulse", amplitude=1.0, linearise=True,
                        elements=False)
        if progress is not None:
            progress.update()
        # Skip the first sample: a velocity impulse makes the held drive's force
        # an impulse at t = 0 that the samples cannot carry.
        y = getattr(run, signal)[1:]
        if not np.all(np.isfinite(y)):
            for r in group:
                judge(rows[id(r)], None, TOL_RINGING, "the impulse response is not finite")
            continue
        third = y.size // 3
        s, parts = _poles(y, dt), (_poles(y[:2 * third], dt), _poles(y[third:], dt))
        same = [r for r in modes if r.omega_d > 0]
        faster = [r for r in same if r.omega > top]
        maps = step_maps((ss := state_model(variant, True)).A, ss.B, dt)
        mapped = [] if maps is None else [la.eigvals(P[:ss.size, :ss.size]) for P in maps[0]]
        for r in group:
            _judge_mode(rows[id(r)], r, others, s, parts, dt, same, faster, mapped)
    out.resonances.extend(rows[id(r)] for r in modes)


def _judge_mode(row: dict, r, others, s: np.ndarray, parts: tuple, dt: float,
                same=(), faster=(), mapped=()) -> None:
    """Judge mode ``r`` by the poles ``s`` of the whole record and ``parts`` of its thirds.

    Within :data:`CANCEL` of one of the ``others`` (the other kind) ``r`` hardly rings at
    the drive; within :data:`WEAK`, with no pole in the record nearer it than another of
    the ``same`` kind, its ringing is below the record's noise (seed 5, network 218: a
    resonance 1.3e-6 from its anti-resonance was not among the record's poles, the
    weakest of which was 4.9e-7 of the strongest): either way it cannot be measured.
    Nor where the pole nearest it is nearer the alias of a ``faster`` mode (a slow
    group's record is sampled every ``dt`` = π/(2.5 ω_top)): 13.024 rad/s sampled every
    80.9 s rings at 0.02498 and was matched to a weak mode at 0.01553 (5 of 6 gross
    mismatches on 600 random networks); the alias of 1283.38 rad/s sampled every 20.4 s,
    0.078763, rang 6e-6 from it (26,000 rad a sample times the fast mode's small error).

    ``mapped``: the eigenvalues of the record's step map computed three ways
    (:func:`~.propagate.step_maps`, beside a stiff mode); the record rings at the map's
    pole, so the tolerance is at least three times their spread at ``r`` (seed 3,
    network 280: a pole at 0.0248 rad/s 1.3e-8 off in the record, as the map's own
    eigenvalue, which the spread bounds at 3e-8; 15 of 17 disagreements were such)."""
    expected = pole_of(r)
    near = min((abs(pole_of(o) - expected) for o in others), default=math.inf)
    if near < CANCEL * abs(expected):
        judge(row, None, TOL_RINGING,
              f"an anti-resonance/resonance {near / abs(expected):.1e} away (relative)"
              " nearly cancels it at the drive: it hardly rings there")
        return
    tol = max(TOL_RINGING, 10 * r.error)
    if len(mapped):
        z = np.exp(expected * dt)
        at = [mu[np.argmin(np.abs(mu - z))] for mu in mapped]
        tol = max(tol, 3 * float(max(abs(m - at[0]) for m in at[1:]) / abs(at[0] * dt * expected)))
    best = nearest_pole(s, expected, dt) if s.size else None
    if near < WEAK * abs(expected) and (best is None or any(
            abs(best - pole_of(o)) < abs(best - expected) for o in same if o is not r)):
        judge(row, None, tol, f"an anti-resonance/resonance {near / abs(expected):.1e} away "
                              "(relative) nearly cancels it: the record holds no ringing of it")
        return
    if best is None:
        # the frequency domain has a mode at the port; the record shows no ringing
        row.update(verdict=DISAGREES, tol=tol, why="no ringing at all in the impulse response")
        return
    with np.errstate(all="ignore"):         # (a mode decayed within dt: exp 0, no alias)
        alias = [(complex(np.log(np.exp(pole_of(f) * dt)) / dt), f) for f in faster]
    off = [(abs(best - complex(a.real, abs(a.imag))), f) for a, f in alias if cmath.isfinite(a)]
    if off and (hit := min(off, key=lambda o: o[0]))[0] < abs(best - expected):
        judge(row, None, tol, f"the record's pole nearest it is the alias of the mode at "
                              f"{hit[1].omega_d:.6g} rad/s (sampled every {dt:.3g} s)")
        return
    spread = max((abs(nearest_pole(p, expected, dt) - best) if p.size else math.inf)
                 for p in parts) / abs(expected)
    why = None if spread <= MAX_SPREAD else (
        f"too weak in the record to be measured: its pole moves by {spread:.1e} (relative) "
        "between the whole record and its first or last two thirds")
    judge_pole(row, expected, s, dt, tol, spread=0.0 if why else spread, why=why)
    sigma = r.zeta * r.omega
    if sigma > 0:
        row["decay_rel_error"] = float(abs(row["decay"] - sigma) / sigma)


def _row_rounding(circuit, w, amp):
    """Rounding of forming the drive's output y = row·z of a steady run (the run's
    ``drive_error`` has its propagation): 4ε Σ |terms| of each coefficient times the
    state's amplitude, √(z² + (ż/ω)²) of the steady sinusoid, a stiff spring's force from
    two node motions that differ by 1e-7 of their size (seed 3, network 137 of the
    crosscheck campaign: 2e-9 of the force)."""
    ss = state_model(circuit, True)
    z0 = periodic_start(ss, Waveform("harmonic", omega=w), amp, circuit, True)
    aug, z0 = with_oscillator(ss, z0, w, amp)
    # the output's rows on a, v, x (a force drive's output is the velocity g·v)
    rows = aug.drive_rows() if aug.kind == "velocity" else (0 * aug.g, aug.g, 0 * aug.g)
    terms = sum(np.abs(r) @ np.abs(C) for r, C in zip(rows, (aug.Cv @ aug.A, aug.Cv, aug.Cx)))
    return float(ROUNDING_PER_STEP / 2 * terms @ np.hypot(z0, (aug.A @ z0) / w))  # (4ε)


def crosscheck(circuit: Circuit, omega_max: float | None = None,
               n_steady: int = 4, progress=None) -> CrossCheck:
    """Run both checks on ``circuit`` (it needs a drive); see the module docstring.

    Parameters
    ----------
    circuit : Circuit
        With a drive line.
    omega_max : float, optional
        Check resonances up to this ω [rad/s] (default 1.5 × the highest
        oscillating one).
    n_steady : int
        4 steady-state frequencies (½, 0.97, 1.6 × the first resonance and
        0.8 ω_max), or 2 (the first two).
    progress : mechcirc.progress.Progress, optional
        Its ``total`` is set to the number of transient runs and it is updated
        after each.

    Returns
    -------
    CrossCheck
        Rows judged by :func:`mechcirc.verdict.judge`; ``result.verdict``
        summarises them.
    """
    if circuit.drive is None:
        raise MechcircError("crosscheck needs a drive line in the netlist (the port whose "
                            "K(ω) is checked); 'mechcirc transient' runs without one")
    from ..resonances import check_omega_max      # (the analysis needs it anyway)

    check_omega_max(omega_max)
    out = CrossCheck(circuit.name, circuit.drive.kind)
    if backlash_elements(circuit):
        out.notes.append("clearances (backlash=) taken as closed in both domains: the "
                         "frequency domain is linearised with contact closed")
    with warnings.catch_warnings(record=True, action="always") as caught:
        res = circuit.resonances(None)
    out.notes.extend(str(w.message) for w in caught)
    ringing = [r.omega for r in res if r.omega_d > 0] or [r.omega for r in res if r.omega > 0]
    if omega_max is None:
        omega_max = 1.5 * max(ringing) if ringing else 1.0
    checked = [r for r in res if r.omega <= omega_max]
    first = min([r.omega for r in checked if r.kind == "resonance"] or
                [r.omega for r in checked] or [omega_max / 3])
    omegas = sorted({0.5 * first, 0.97 * first, 1.6 * first, 0.8 * omega_max}
                    if n_steady >= 4 else {0.5 * first, 0.97 * first})
    if progress is not None:
        progress.total = len(omegas) + sum(
            len(_groups([r for r in checked if r.kind == k and r.omega_d > 0]))
            for k in ("resonance", "antiresonance"))
    for kind in ("resonance", "antiresonance"):
        modes = [r for r in checked if r.kind == kind]
        if modes:
            _ringing(circuit, kind, modes, [r for r in res if r.kind != kind], out, progress)
    # (b) steady state at several ω, one near the first resonance.
    with warnings.catch_warnings(action="ignore"):  # already reported above
        sweep = circuit.sweep(np.array(omegas))
    _steady(circuit, omegas, sweep, out, progress)
    return out


def _steady(circuit: Circuit, omegas: list, sweep, out: CrossCheck, progress) -> None:
    """Judge the periodic response at each of ``omegas`` against ``sweep`` into
    ``out.steady_state``: amplitude of the drive's output fitted over three periods."""
    d = circuit.drive
    assert d is not None                # (checked by crosscheck)
    expected = np.abs(sweep.Q0 if d.kind == "velocity" else sweep.v0)
    for w, exp, err in zip(omegas, expected, sweep.error):
        row = {"omega": float(w), "expected": float(exp), "measured": None,
               "rel_error": None, "periodic_deviation": None}
        out.steady_state.append(row)
        tol = max(TOL_STEADY, 10 * float(err)) if math.isfinite(err) else TOL_STEADY
        if not (math.isfinite(exp) and exp > 0):
            judge(row, None, tol, f"the sweep gives |{'Q0' if d.kind == 'velocity' else 'v0'}|"
                                  f" = {exp:g} here (a pole or zero of K)")
            continue
        period = 2 * math.pi / w
        try:
            run = transient(circuit, 3 * period, period / 64, f"harmonic:{w!r}",
                            linearise=True, steady=True, elements=False)
        except MechcircError as exc:
            judge(row, None, tol, str(exc))
            continue
        finally:
            if progress is not None:
                progress.update()
        y = run.drive_force if d.kind == "velocity" else run.drive_velocity
        assert y is not None            # a driven circuit's run has the drive's output
        t = run.time
        # the time domain's own error of y: its propagation (the run's drive_error: heavily
        # weighted small states; None where not finite), and the rounding of forming it
        if run.drive_error is None:
            judge(row, None, tol, "the transient's error of the drive's output is not finite")
            continue
        tol = max(tol, (run.drive_error + _row_rounding(circuit, w, d.amplitude)) / exp)
        measured, departure = fit_sinusoid(t, y, w)
        row["measured"] = float(measured)
        rel = row["rel_error"] = float(abs(measured - exp) / exp)
        dev = row["periodic_deviation"] = departure / max(measured, 1e-300)
        judge(row, max(rel, dev), tol)
