"""Cross-checks of the time-domain sley model against the mechanical circuit.

(a) :func:`resonance_check` -- the resonances (K = 0) of the netlist from
    :func:`~mechcirc.sley.linear.to_netlist` against the eigenfrequencies of the
    linearised equations of motion at a crank angle θ0.
(b) :func:`ringing_check` -- the frequency of the sley's ringing after the
    beat-up pulse, measured from a simulated ε4P, against the damped natural
    frequency predicted at that crank angle.
(c) :func:`harmonic_check` -- harmonic forcing of that netlist stepped in the time
    domain (:func:`mechcirc.transient.transient`: exact steps e^{AΔ} from its
    periodic steady state) against |Q0(ω)| of its sweep (the tree reduction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolverError
from ..identify import fit_sinusoid
from ..verdict import judge, summarise
from .linear import eigenfrequencies, to_circuit, to_netlist
from .models import ParameterError, SleyParameters

#: Tolerances of the three checks' verdicts (:func:`mechcirc.verdict.judge`):
#: (a) exact algebra on both sides, achieved ≤ 1.5e-15 over every preset;
#: (b) a frozen-θ prediction against the ringing of the moving sley (its frequency
#: changes with the crank angle over the measured half periods), achieved ≤ 5.1e-3
#: over every preset with the clearance closed; (c) exact steps (e^{AΔ}) from the periodic
#: state against the tree reduction, achieved ≤ 2.7e-11 over the 14 presets at 12 crank
#: angles and 5 ω each.
TOL_RESONANCE, TOL_RINGING, TOL_HARMONIC = 1e-12, 1e-2, 1e-9

#: Below this |μ| the drive hardly sees the sley's mode: its resonance and anti-resonance
#: in the netlist cancel within rounding (missed up to |μ| = 1.5e-7, found from 3.4e-7).
NEAR_DEAD_CENTRE = 1e-6

#: Why a line of check (c) is not measured: a forcing frequency on a natural frequency of
#: an undamped part has no periodic steady state.
HARMONIC_UNSETTLED = ("no periodic steady state at this frequency: a natural frequency of an "
                      "undamped part of the netlist")

#: Beat-up moment [N·m] of the pulse that makes the sley ring in check (b), for a
#: variant that has none (M0 = 0): the ringing frequency does not depend on it.
RINGING_M0 = 500.0

__all__ = ["resonance_check", "ringing_check", "harmonic_check", "ResonanceCheck",
           "RingingCheck", "HarmonicCheck", "circuit_resonances", "crosscheck_sley",
           "RINGING_M0"]


@dataclass(frozen=True)
class ResonanceCheck:
    """Eigenfrequencies of the linearised model against the circuit's resonances.

    Attributes
    ----------
    theta0 : float
        Crank angle [rad].
    damping : bool
        Whether the dampers were included.
    eigen : tuple of float
        |λ| of the linearised model's modes, ascending [rad/s] (ω_n when undamped).
    eigen_d : tuple of float
        Im λ, the damped natural frequencies [rad/s].
    circuit : tuple of float
        ω_n = |s| of the netlist's resonances (K = 0) [rad/s].
    circuit_d : tuple of float
        Their damped frequencies Im s [rad/s].
    rel_error : float
        Largest relative difference over both.
    how : str
        ``"Circuit.resonances"``: what found the netlist's resonances.
    netlist : str
        The netlist used.
    """

    theta0: float
    damping: bool
    eigen: tuple[float, ...]
    eigen_d: tuple[float, ...]
    circuit: tuple[float, ...]
    circuit_d: tuple[float, ...]
    rel_error: float
    how: str
    netlist: str


def circuit_resonances(circuit, omega_max: float):
    """Resonances (K = 0) of a circuit below ``omega_max`` [rad/s]: ((ω_n, ω_d), …), how.

    Uses ``circuit.resonances()`` (the roots of kind ``"resonance"``, sorted).

    Parameters
    ----------
    circuit : Circuit
        The circuit to solve.
    omega_max : float
        Upper end of the search [rad/s].

    Returns
    -------
    tuple of (tuple, str)
    """
    found = [(float(r.omega), float(r.omega_d)) for r in circuit.resonances(omega_max=omega_max)
             if r.kind == "resonance"]
    return tuple(sorted(found)), "Circuit.resonances"


def resonance_check(params: SleyParameters, theta0: float, *,
                    damping: bool = False) -> ResonanceCheck:
    """(a): resonances of the netlist at ``theta0`` [rad] against the eigenfrequencies.

    Undamped (default): ω_n of K v = ω² M v against the zeros of K(ω).  Damped:
    |λ| and Im λ of the state matrix against ω_n = |s| and ω_d of the circuit's
    complex resonances.

    Parameters
    ----------
    params : SleyParameters
        The sley whose netlist resonances are compared with its eigenfrequencies.
    theta0 : float
        Crank angle [rad] at which the model is linearised and the netlist written.
    damping : bool
        Compare the damped roots instead of the undamped ones.

    Returns
    -------
    ResonanceCheck
    """
    modes = eigenfrequencies(params, theta0)
    if damping:
        eigen = tuple(abs(m.eigenvalue) for m in modes)
        eigen_d = tuple(m.omega_d for m in modes)
    else:
        eigen = eigen_d = tuple(m.omega_n for m in modes)
    circuit = to_circuit(params, theta0, damping=damping)
    text = to_netlist(params, theta0, damping=damping)
    found, how = circuit_resonances(circuit, 4.0 * max(eigen))
    wn, wd = tuple(w for w, _ in found), tuple(w for _, w in found)
    rel = math.inf if len(found) != len(eigen) else \
        max(abs(a - b) / b for a, b in zip(wn + wd, eigen + eigen_d))
    return ResonanceCheck(float(theta0), damping, eigen, eigen_d, wn, wd, rel, how, text)


@dataclass(frozen=True)
class RingingCheck:
    """Measured ringing of ε4P after the beat-up against the predicted damped frequency.

    Attributes
    ----------
    theta_mid : float
        Crank angle at the middle of the fitted window [rad].
    omega_measured : float
        Angular frequency of the damped sinusoid fitted to ε4P − ε4T [rad/s].
    omega_predicted : float
        Damped natural frequency of the sley mode at ``theta_mid`` [rad/s].
    rel_error : float
        |measured − predicted| / predicted.
    """

    theta_mid: float
    omega_measured: float
    omega_predicted: float
    rel_error: float


def ringing_check(params: SleyParameters, *, half_periods: int = 4, revolutions: int = 2,
                  method: str | None = None) -> RingingCheck:
    """(b): frequency of the sley's ringing after the beat-up pulse of a simulation.

    Two simulations, with the beat-up moment M0 and without it, differ by the
    response to the pulse alone (exactly so without clearance, where the model
    is linear in the sley's deformation); after the window closes that
    difference of ε4P is a free, damped oscillation of the sley mode, whose zero
    crossings are π/ω_d apart.  ω_d is measured over ``half_periods`` half
    periods from the first crossing after the window, and compared with the
    lowest damped natural frequency of the linearised model at the crank angle
    in the middle of that stretch.

    Parameters
    ----------
    params : SleyParameters
        The sley.
    half_periods, revolutions : int
        Half periods of the ringing measured; revolutions of each simulation.
    method : str, optional
        As :func:`mechcirc.sley.simulate`.

    Returns
    -------
    RingingCheck

    Raises
    ------
    ParameterError
        ``params.M0`` is 0 (there is no pulse).
    SolverError
        Fewer than ``half_periods + 1`` zero crossings follow the window.
    """
    if params.M0 <= 0:
        raise ParameterError("the ringing check needs a beat-up moment M0 > 0")
    a, b = _with_and_without_pulse(params, revolutions, method)
    end = a.phiP + params.alpha / 2
    rel = (a.crank_angle - end) % (2 * math.pi)
    order = np.argsort(rel)
    rel = rel[order]
    diff = (a.eps4P - b.eps4P)[order]
    before_start = rel < (a.theta0 - end) % (2 * math.pi)       # stay inside one revolution
    rel, diff = rel[before_start], diff[before_start]
    idx = np.flatnonzero(np.sign(diff[:-1]) * np.sign(diff[1:]) < 0)
    if idx.size < half_periods + 1:
        raise SolverError(f"ringing: {idx.size} zero crossing(s) of the pulse response after "
                          f"the beat-up window, {half_periods + 1} needed to measure its "
                          "frequency (the ringing dies out or is too slow within one "
                          "revolution)", status="too few crossings")
    idx = idx[:half_periods + 1]
    cross = rel[idx] - diff[idx] * (rel[idx + 1] - rel[idx]) / (diff[idx + 1] - diff[idx])
    t = cross / params.omega
    w_meas = math.pi * half_periods / (t[-1] - t[0])
    theta_mid = (end + 0.5 * (cross[0] + cross[-1])) % (2 * math.pi)
    w_pred = eigenfrequencies(params, theta_mid)[0].omega_d
    return RingingCheck(theta_mid, w_meas, w_pred, abs(w_meas - w_pred) / w_pred)


def _with_and_without_pulse(params: SleyParameters, revolutions: int, method):
    """The simulations of :func:`ringing_check`: with the beat-up moment M0 and with M0 = 0
    (14,400 points per revolution, no error estimate)."""
    import warnings

    from .simulation import SleyAccuracyWarning, simulate_params

    # the difference of two runs with the same transient: periodicity is not needed here
    with warnings.catch_warnings(action="ignore", category=SleyAccuracyWarning):
        return tuple(simulate_params(p, revolutions, method, points_per_revolution=14400,
                                     error_estimate=False)
                     for p in (params, params.replace(M0=0.0)))


@dataclass(frozen=True)
class HarmonicCheck:
    """|Q0(ω)| from time-domain forcing of the linear model against the netlist.

    Attributes
    ----------
    omega : ndarray
        Forcing frequencies [rad/s].
    q0_time : ndarray
        Amplitude of the shaft moment in the time domain, per unit shaft-velocity
        amplitude [N·m·s/rad].
    q0_circuit : ndarray
        |Q0/V0| = 1/|K| of the netlist (or of :meth:`LinearModel.drive_moment`
        when the netlist core is missing) [N·m·s/rad].
    rel_error : float
        Largest |q0_time − q0_circuit| / q0_circuit over ``omega``.
    how : str
        Which netlist path gave ``q0_circuit``.
    """

    omega: np.ndarray
    q0_time: np.ndarray
    q0_circuit: np.ndarray
    rel_error: float
    how: str


def forced_amplitude(circuit, omega: float) -> float:
    """|drive moment| per unit shaft velocity of the sley's netlist under φ̇2 = cos(ω t) in
    its periodic steady state, stepped in time: :func:`mechcirc.transient.transient`
    started in that state (exact steps e^{AΔ}, Δ = T/400), its amplitude fitted over four
    periods (:func:`mechcirc.identify.fit_sinusoid`).  NaN where there is no steady state
    (:data:`HARMONIC_UNSETTLED`)."""
    from ..transient import transient

    period = 2 * math.pi / omega
    try:
        run = transient(circuit, 4 * period, period / 400, f"harmonic:{float(omega)!r}",
                        steady=True, elements=False)
    except SolverError:             # ω on a natural frequency of an undamped part
        return math.nan
    return fit_sinusoid(run.time, run.drive_force, omega)[0]


def harmonic_check(params: SleyParameters, theta0: float, omegas) -> HarmonicCheck:
    """(c): time-domain harmonic forcing of the sley's netlist against |Q0| of its sweep.

    Parameters
    ----------
    params : SleyParameters
        The sley forced harmonically, in the time domain and through its netlist.
    theta0 : float
        Crank angle [rad] at which its coefficients are frozen for both.
    omegas : array_like
        Forcing frequencies [rad/s].

    Returns
    -------
    HarmonicCheck
    """
    circuit, omegas = to_circuit(params, theta0, velocity=1.0), np.asarray(omegas, dtype=float)
    q_time = np.array([forced_amplitude(circuit, w) for w in omegas])
    q_circ = np.abs(circuit.sweep(omegas).Q0)
    rel = float(np.max(np.abs(q_time - q_circ) / q_circ))
    return HarmonicCheck(omegas, q_time, q_circ, rel, "netlist sweep Q0")


def _ringing_row(params: SleyParameters) -> dict:
    """Check (b) as a judged row; a variant without beat-up pulse gets :data:`RINGING_M0`,
    and the clearance is closed (with it the motion is nonlinear and rings below the
    linear prediction); both said in ``notes``."""
    notes = []
    if params.M0 <= 0:
        params = params.replace(M0=RINGING_M0)
        notes.append(f"variant has M0 = 0; used M0 = {RINGING_M0:g} N m for the pulse")
    if params.clearance > 0:
        notes.append(f"clearance {params.clearance:g} rad closed for the ringing (with it "
                     "the motion is nonlinear and rings below the linear prediction)")
        params = params.replace(clearance=0.0)
    try:
        ring, why = ringing_check(params), None
    except SolverError as exc:      # (b) cannot be measured; (a) and (c) still stand
        ring, why = None, str(exc)
    row = {"theta_mid_deg": math.degrees(ring.theta_mid) if ring else None,
           "omega_measured": ring.omega_measured if ring else None,
           "omega_predicted": ring.omega_predicted if ring else None,
           "rel_error": ring.rel_error if ring else None, "notes": notes}
    return judge(row, ring.rel_error if ring else None, TOL_RINGING, why)


def crosscheck_sley(params: SleyParameters, theta0: float, *, on_step=None):
    """The three cross-checks of the sley at crank angle ``theta0`` [rad], judged.

    Parameters
    ----------
    params : SleyParameters
        The sley (a preset or its variant).
    theta0 : float
        Crank angle of the linearisation [rad].
    on_step : callable, optional
        Called with no argument after each of the four computations (progress).

    Returns
    -------
    doc : dict
        JSON-ready: ``label``, ``theta_deg``, ``verdict``, ``summary``
        (:func:`mechcirc.verdict.summarise`), ``resonances`` (undamped and damped
        rows of (a)), ``ringing`` (the row of (b)) and ``harmonic`` (c), each row
        with its ``verdict``.
    netlist : str
        The damped netlist whose resonances were compared in (a).
    """
    step = on_step or (lambda: None)
    checks, res_rows = {}, []
    for d in (False, True):
        c = checks[d] = resonance_check(params, theta0, damping=d)     # (checks theta0)
        mu = abs(float(params.fourbar().transfer(c.theta0)[1]))
        step()
        row = {"damping": d, "eigen_omega": list(c.eigen), "eigen_omega_d": list(c.eigen_d),
               "circuit_omega": list(c.circuit), "circuit_omega_d": list(c.circuit_d),
               "rel_error": c.rel_error, "how": c.how}
        judge(row, c.rel_error, TOL_RESONANCE, None if mu >= NEAR_DEAD_CENTRE else (
            f"|mu| = {mu:.2g}: so near a dead centre the drive hardly sees the sley's mode, "
            "whose resonance and anti-resonance in the netlist cancel within rounding"))
        if len(c.circuit) != len(c.eigen) and mu >= NEAR_DEAD_CENTRE:
            row["why"] = (f"{len(c.circuit)} resonances of the netlist against {len(c.eigen)} "
                          "modes of the linearised model")
        res_rows.append(row)
    ring_row = _ringing_row(params)
    step()
    eigen = checks[False].eigen
    harm = harmonic_check(params, theta0, np.array(sorted([0.5 * eigen[0], eigen[0],
                                                           eigen[-1]])))
    step()
    harm_rows = [judge({"omega": float(w), "q0_time": float(qt), "q0_circuit": float(qc),
                        "rel_error": float(abs(qt - qc) / qc)},
                       float(abs(qt - qc) / qc), TOL_HARMONIC,
                       None if math.isfinite(qt) else HARMONIC_UNSETTLED)
                 for w, qt, qc in zip(harm.omega, harm.q0_time, harm.q0_circuit)]
    summary = summarise(res_rows + [ring_row] + harm_rows)
    doc = {"label": params.label, "theta_deg": math.degrees(theta0),
           "verdict": summary["verdict"], "summary": summary,
           "resonances": res_rows, "ringing": ring_row,
           "harmonic": {"omega": harm.omega, "q0_time": harm.q0_time,
                        "q0_circuit": harm.q0_circuit, "rel_error": harm.rel_error,
                        "how": harm.how, "rows": harm_rows}}
    return doc, checks[True].netlist
