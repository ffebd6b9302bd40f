"""Transients of a circuit: :func:`transient`, its start, its outputs, and clearances.

:func:`transient` takes a circuit, a drive :class:`~.waveform.Waveform` and a
time grid and returns a :class:`~.result.TransientResult`.  Linear circuits
are propagated exactly between drive samples (:mod:`.propagate`); the drive's
interpolation error is carried to x in the reported error.

Circuits with clearances integrate with the embedded Dormand–Prince 5(4) loop
of :mod:`mechcirc.transient._kernels` (contacts evaluated inside the
right-hand side; steps end on every drive sample unless the drive is constant
or harmonic, when outputs come from the method's continuous extension).  The
absolute tolerance is rtol × each state's peak (from a loose pilot run); the
run returned is at rtol/100 with a 4× smaller largest step, and its error is
estimated by its difference from the run at rtol (which errs many times more).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from typing import Callable

import numpy as np
import scipy.linalg as la

from ..circuit import Circuit, units_of
from ..errors import MechcircError, NetlistError, SolverError
from ..sources import positive_number
from .model import StateSpace, backlash_elements, drive_map, incidence, state_space
from .propagate import drive_gain, kernels, map_error, propagate_linear
from .result import TransientResult
from .waveform import Waveform, parse_waveform

__all__ = ["transient", "MAX_SAMPLES"]

#: Most output samples of one run (each node's x and v are kept for every one).
MAX_SAMPLES = 2_000_000
#: Smallest output step [s]: below it the grid's multiples are subnormal numbers.
MIN_STEP = 1e-300
#: The clearance integrator's reference run: tolerance ÷ REF_TOL, largest step
#: ÷ REF_H (see :func:`_nonlinear`).
REF_TOL, REF_H = 100.0, 4.0
#: The clearance integrator's accepted relative tolerances.
RTOL_RANGE = (1e-12, 0.1)


def _grid(t_end: float, dt: float | None, waveform: Waveform) -> np.ndarray:
    if not (positive_number(t_end)):
        raise MechcircError(f"--t-end must be a finite time > 0 [s], got {t_end}")
    if dt is None:
        dt = t_end / 2000
        per_period = {"harmonic": 40, "motion": 720}.get(waveform.kind)  # motion: 0.5° of the shaft
        if per_period:
            dt = min(dt, 2 * math.pi / waveform.omega / per_period)
    if not (positive_number(dt)):
        raise MechcircError(f"--dt must be a finite time > 0 [s], got {dt}")
    if dt > t_end:          # one step of dt would run past t_end (it ran to dt)
        raise MechcircError(f"--dt {dt:g} s is longer than --t-end {t_end:g} s; give a step "
                            "dt ≤ t_end (the default is t_end/2000)")
    if dt < MIN_STEP:
        raise MechcircError(f"the step dt = {dt:g} s is below {MIN_STEP:g} s (its multiples "
                            "would lose precision); give a larger --dt or --t-end")
    ratio = t_end / dt
    if not ratio + 1 <= MAX_SAMPLES:
        raise MechcircError(f"t_end/dt = {ratio:.3g} samples, the limit is {MAX_SAMPLES}; "
                            "give a larger --dt or a shorter --t-end")
    n = max(int(round(ratio)), 1)
    return np.linspace(0.0, n * dt, n + 1)


@np.errstate(over="ignore", invalid="ignore")     # a non-finite result is refused at the end
def transient(circuit: Circuit, t_end: float, dt: float | None = None,
              waveform: Waveform | str | Callable | None = None, *,
              amplitude: float | None = None, linearise: bool = False,
              elements: bool = True, velocities: bool = True,
              rtol: float = 1e-10, steady: bool = False,
              rpm: float | None = None) -> TransientResult:
    """Integrate ``circuit`` from its ``.ic`` state over [0, t_end] on a grid of step ``dt``.

    Parameters
    ----------
    circuit : Circuit
        Any circuit (a drive is optional).
    t_end, dt : float
        End time and output step [s] (dt default: t_end/2000, and at least 40
        samples per period of a harmonic drive).
    waveform : Waveform, str, callable or None
        The drive's waveform (see :class:`Waveform` and :func:`parse_waveform`);
        None keeps the drive at rest (velocity drive held, force drive off).
    amplitude : float
        Scales the harmonic, step and impulse waveforms (default: the drive's
        amplitude in the netlist).
    linearise : bool
        Take every clearance as closed (the frequency domain's reading).
    rtol : float
        Relative tolerance of the clearance integrator (ignored when linear).
    elements : bool
        Compute every element's force and velocity difference (default); if
        false only node and drive outputs (faster for long runs of large networks).
    velocities : bool
        Compute the node velocities ``v`` (default); with ``elements=False``
        and ``velocities=False`` only the displacements ``x`` and the drive's
        output are formed (``v`` is None): half the output work of a linear run.
    steady : bool
        Start in the periodic steady state of a harmonic drive instead of the ``.ic``
        state (linear circuits, or ``linearise``): the state that returns after every
        period, z(0) = amp · Im[(iωI − A)⁻¹ B], so no ring-down has to be waited for.
        Refused when ω is a natural frequency of an undamped part (no periodic state exists).
    rpm : float, optional
        Shaft speed [rev/min] of a drive given by its motion over one revolution
        (netlist ``drive ... motion=``): the drive's velocity is Ω·dx/dθ at θ = Ωt
        (Ω = 2π·rpm/60), from t = 0 at θ = 0.  Required for such a drive unless
        ``waveform`` is given (which then replaces the motion).

    Returns
    -------
    TransientResult
        Time, node displacements and velocities, element forces and the drive's
        output on the grid.
    """
    drive = _waveform(circuit, waveform, rpm)
    amp = getattr(circuit.drive, "amplitude", 0.0) if amplitude is None else float(amplitude)
    t = _grid(t_end, dt, drive)
    ss, u = state_model(circuit, linearise), drive.sample(t, amp)
    ss, z0, u_in, notes = _start(ss, drive, amp, u, steady, circuit, linearise)
    notes.extend(_grid_notes(t, t_end))
    _flags(elements=elements, velocities=velocities)
    if backlash_elements(circuit) and not linearise:
        return _clearance_run(ss, circuit, z0, t, (u, u_in), drive, amp, rtol, notes,
                              elements, velocities)
    return _linear_run(ss, circuit, z0, t, (u, u_in), drive, notes, elements, velocities)


def _grid_notes(t: np.ndarray, t_end: float) -> list[str]:
    """Where the grid ends, when dt does not divide t_end (else nothing)."""
    if abs(t[-1] - t_end) <= 1e-9 * t_end:
        return []
    return [f"the grid ends at {t[-1]:.6g} s: t_end/dt = {t_end / t[1]:.6g} rounded to "
            f"{t.size - 1} steps"]


def _flags(**flags) -> None:
    """Refuse a flag of :func:`transient` that is not True or False (a list of element names
    would read as True)."""
    for name, value in flags.items():
        if not isinstance(value, (bool, np.bool_)):
            raise TypeError(f"{name} must be True or False, got {value!r}")


def _clearance_run(ss, circuit, z0, t, us, drive, amp, rtol, notes, elements, velocities):
    """A run with clearances: the adaptive integrator, its outputs and separations."""
    if not RTOL_RANGE[0] <= rtol <= RTOL_RANGE[1]:
        raise MechcircError(f"--rtol must be between {RTOL_RANGE[0]:g} and "
                            f"{RTOL_RANGE[1]:g}, got {rtol:g}")
    u, u_in = us
    Z, X, method, err, more = _nonlinear(ss, circuit, z0, t, u_in, rtol,
                                      drive.rate(t, amp) if drive.kind == "motion" else None)
    notes.extend(more)
    if _interpolation(t, u, drive, drive.kind == "motion", notes) > 0.0:
        notes.append("the drive's interpolation error is not in the error estimate (the "
                     "clearances make x not linear in the drive)")
    out = _outputs(ss, circuit, t, Z, u, u_in, t[1] - t[0], drive, method, err, notes,
                   elements, None, velocities, x_ready=X)
    _require_finite(out)
    return out


def _linear_run(ss, circuit, z0, t, us, drive, notes, elements, velocities):
    """A linear run: exact propagation, its outputs and their error."""
    u, u_in = us
    h = t[1] - t[0]
    Z, T, nx, drive_y, x_ready, v_ready, x_err, err, path = propagate_linear(
        ss, z0, u_in, h, elements, velocities)
    method = f"exact (matrix exponential, first-order hold of the drive; {path.split(' (')[0]})"
    notes.append(f"linear propagation: {path}")
    interp = _interpolation(t, u, drive, False, notes)
    out = _outputs(ss, circuit, t, Z, u, u_in, h, drive, method, err, notes, elements, T,
                   velocities, nx, drive_y, x_ready, v_ready)
    with np.errstate(all="ignore"):     # (the steps' error, else map error × steps × max|x|)
        out.error = err + (x_err[0] if x_err[0] is not None else map_error(ss.A, ss.B, h) * (
            t.size - 1) * _peak(out.x))
    if interp > 0.0:        # the drive's interpolation error, carried to x
        out.error += interp * drive_gain(ss, h, t.size)
    elif out.drive_force is not None or out.drive_velocity is not None:
        out.drive_error = x_err[1]      # (w·z's; an interpolated drive's is not carried)
    # (linear: the error is finite only if x is; NaN and ±inf reach max|x| or its bound)
    _require_finite(out, x_in_error=True)
    return out


def _waveform(circuit: Circuit, drive, rpm) -> Waveform:
    """``drive`` (Waveform, text, callable or None, or the motion at ``rpm``) as a Waveform."""
    drive = _motion_drive(circuit, drive, rpm)
    if callable(drive) and not isinstance(drive, Waveform):
        drive = Waveform("callable", func=drive)
    elif not isinstance(drive, Waveform):
        drive = parse_waveform(drive)
    if circuit.drive is None and drive.kind != "rest":
        raise MechcircError(f"the netlist has no drive line, so --waveform {drive.kind} has "
                            "nothing to act on (add 'drive NAME N1 N2 force=F0')")
    return drive


def _start(ss: StateSpace, drive: Waveform, amp: float, u, steady: bool, circuit,
           linearise: bool):
    """(model, z(0), drive samples fed to it, notes): the impulse's jump, the periodic start,
    and a harmonic drive as two more states; the notes are the model's on its initial state
    and what this start implies."""
    z0, notes = ss.initial[0].copy(), list(ss.initial[1])
    if drive.kind == "impulse":
        # u = amp·δ(t) in ż = A z + B u: the state jumps by B·amp.  A force impulse
        # gives the masses momentum and, through a damper, moves a massless
        # damped node; a velocity impulse moves the drive by amp·1 s (X jumps)
        # and its dampers pass momentum on.
        z0 = z0 + ss.B * amp
    if not z0.any() and not np.any(u):
        notes.append("nothing moves: the drive is at rest and every initial state is 0 "
                     "(give a waveform: harmonic:OMEGA, step, impulse or csv:PATH, an "
                     "amplitude other than 0, or .ic lines)")
    if drive.kind == "step" and ss.kind == "velocity" and amp != 0:
        notes.append("a velocity step makes the drive's nodes jump in velocity: the force "
                     "through the drive has an impulse at t = 0 that samples cannot show")
    if steady:
        z0 = periodic_start(ss, drive, amp, circuit, linearise)
        notes.append("started in the periodic steady state of the harmonic drive")
    if drive.kind == "harmonic":
        # Exact: the sinusoid is generated by two more states (an undamped
        # oscillator), so no interpolation of the drive is needed at all.
        ss, z0 = with_oscillator(ss, z0, drive.omega, amp)
        return ss, z0, np.zeros_like(u), notes
    return ss, z0, u, notes


def _separations(t, E, W, clear: dict, drive) -> list:
    """Every opening of each clearance's contact (:func:`.contact.separations`), from the
    relative displacements and velocities ``E``, ``W`` (one row per element of ``clear``)."""
    from .contact import separations

    found = []
    for j, (e, comp) in enumerate(clear.values()):
        found += separations(t, E[j], W[j], *_law_params(e, comp), e.name,
                             drive.omega if drive.kind == "motion" else None)
    return sorted(found, key=lambda s: s.t_open)


def _law_params(spring, comp) -> tuple[float, float, float]:
    """(c, d, B) of a clearance spring and its companion damper."""
    d = comp.value * comp.eta if comp is not None else 0.0
    return spring.value * spring.eta, d, spring.backlash


def _motion_drive(circuit: Circuit, drive, rpm):
    """The waveform of a ``motion=`` drive at ``rpm``, else ``drive`` as given (checked)."""
    d = circuit.drive
    motion = d.motion if d is not None else None
    if rpm is not None:
        if not (isinstance(rpm, (int, float)) and math.isfinite(rpm) and rpm > 0):
            raise MechcircError(f"--rpm must be a finite shaft speed > 0 rev/min, got {rpm!r}")
        if motion is None:
            raise MechcircError("--rpm sets the shaft speed of a drive given by its motion "
                                "over a revolution ('drive NAME N1 N2 motion=...'); this "
                                "netlist's drive has none" if d is not None else
                                "--rpm sets the shaft speed of a motion= drive; the netlist "
                                "has no drive")
        if drive is not None:
            raise MechcircError("give either --waveform (a waveform in time) or --rpm (the "
                                f"shaft speed of the drive's {motion.spec}), not both")
        from ..periodic import rpm_to_omega

        return Waveform("motion", omega=rpm_to_omega(float(rpm)), motion=motion)
    if d is not None and d.motion is not None and drive is None:
        raise NetlistError(f"drive {d.name!r} moves by {d.motion.spec.split()[0]} over one "
                           "revolution of the shaft, and no shaft speed is given",
                           circuit.source or "<string>", d.line, d.col,
                           "a shaft speed: --rpm RPM (transient(..., rpm=RPM)), or a "
                           "--waveform in time")
    return drive


def _require_finite(r: TransientResult, x_in_error: bool = False) -> None:
    """A result with a non-finite value is a failure, never a result.

    ``x_in_error``: ``r.error`` is finite only if ``r.x`` is (not looked at again)."""
    arrays = [a for a in (r.x, r.v, r.force, r.drive_force, r.drive_velocity) if a is not None]
    # An array is finite where its max and min are (NaN and ±inf propagate to one of
    # them): two reductions instead of a boolean array as large as the outputs.
    if math.isfinite(r.error) and all(
            not a.size or (math.isfinite(float(a.max())) and math.isfinite(float(a.min())))
            for a in (arrays[1:] if x_in_error else arrays)):   # r.x first
        return
    bad = [np.flatnonzero(~np.isfinite(a).reshape(a.shape[0], -1).all(axis=1)) for a in arrays]
    first = min((int(b[0]) for b in bad if b.size), default=None)
    if first is None and math.isfinite(r.error):
        return
    where = f"from t = {r.time[first]:.3g} s on" if first is not None else "in its error estimate"
    raise MechcircError(
        f"the transient is not finite {where} (t_end = {r.time[-1]:.3g} s, step "
        f"{r.time[1] - r.time[0]:.3g} s): the values or the propagation over one step "
        f"overflow the floating-point range (±{np.finfo(float).max:.3g}); give a shorter "
        "--t-end or a smaller --dt")


def periodic_start(ss: StateSpace, drive: Waveform, amp: float, circuit, linearise):
    """z(0) of the periodic response to u = amp·sin ωt: amp · Im[(iωI − A)⁻¹ B]."""
    if drive.kind != "harmonic":
        raise MechcircError("a periodic steady state needs a harmonic drive "
                            "(--waveform harmonic:OMEGA)")
    if backlash_elements(circuit) and not linearise:
        raise MechcircError("a periodic steady state is computed for linear circuits only "
                            "(this one has clearances; linearise them or wait for it)")
    M = 1j * drive.omega * np.eye(ss.size) - ss.A
    try:
        with warnings.catch_warnings(action="error", category=la.LinAlgWarning):  # rcond below eps
            Z = la.solve(M, ss.B.astype(complex))
        if not np.all(np.isfinite(Z)):
            raise la.LinAlgError
    except (la.LinAlgError, la.LinAlgWarning, ValueError):
        raise SolverError(f"no periodic steady state at ω = {drive.omega:g} rad/s: it is a "
                            "natural frequency of an undamped part of the network "
                            "(iωI − A is singular)") from None
    return amp * Z.imag


def state_model(circuit: Circuit, linearise: bool) -> StateSpace:
    """The circuit's state-space model, built on first use and kept on the circuit.

    It depends only on the (frozen) circuit, as the nodal assembly cached on
    it does; repeated transients of one circuit skip building it.
    """
    return circuit.memo("_transient_model_closed" if linearise else "_transient_model",
                        lambda: state_space(circuit, linearise=linearise))


def with_oscillator(ss: StateSpace, z0, omega: float, amp: float):
    """ss with states w = (sin ωt, cos ωt) appended and the drive u = amp·w₁ folded in."""
    N = ss.size
    A = np.zeros((N + 2, N + 2))
    A[:N, :N] = ss.A
    A[:N, N] = ss.B * amp
    A[N, N + 1] = omega
    A[N + 1, N] = -omega

    def widen(C, Dm, E=None):
        out = np.zeros((C.shape[0], N + 2))
        out[:, :N] = C
        out[:, N] = Dm * amp
        if E is not None:
            out[:, N + 1] = E * amp * omega
        return out

    Cx = widen(ss.Cx, ss.Dx)
    Cv, zero = widen(ss.Cv, ss.Dv, ss.Ev), np.zeros(ss.Cx.shape[0])
    extra = None if ss.extra is None else np.vstack([ss.extra, np.zeros((2, ss.extra.shape[1]))])
    new = dataclasses.replace(ss, A=A, B=np.zeros(N + 2), Cx=Cx, Dx=zero, Cv=Cv, Dv=zero,
                              Ev=zero, extra=extra)
    return new, np.concatenate([z0, [0.0, 1.0]])


def _interpolation(t: np.ndarray, u: np.ndarray, drive: Waveform, hermite: bool,
                   notes: list) -> float:
    """Bound of the drive's interpolation error between samples (noted unless rounding).

    ``hermite``: cubic Hermite (the clearance integrator with a motion drive),
    h⁴/384·max|u⁗| from the fourth differences; a table (``"samples"``): exact,
    the largest gap between the table and the grid's linear interpolation, at
    the table's points (both are piecewise linear); else linear (h²/8·max|ü|).
    """
    how = "h²/8·max|ü|, from the samples' second differences"
    if hermite:
        interp = float(np.abs(np.diff(u, 4)).max() / 384.0) if u.size > 4 else 0.0
    elif drive.kind in ("rest", "step", "impulse", "harmonic") or u.size < 3:
        interp = 0.0
    elif drive.kind == "samples":
        knots, values = np.asarray(drive.times), np.asarray(drive.values)
        inside = (knots > t[0]) & (knots < t[-1])
        gap = np.abs(values[inside] - np.interp(knots[inside], t, u))
        interp = float(gap.max(initial=0.0))
        how = "exact: the largest gap at the table's points"
    else:
        interp = float(np.abs(np.diff(u, 2)).max() / 8.0)
        if drive.kind == "callable":    # and where a drive the samples do not resolve shows
            mid = np.asarray(drive.sample(t[:-1] + 0.5 * np.diff(t), 1.0), dtype=float)
            interp = max(interp, float(np.abs(mid - 0.5 * (u[:-1] + u[1:])).max()))
            how += " and the gaps at the midpoints, the larger"
    if interp > 0.05 * float(np.ptp(u)):
        how += "; the steps do not resolve the drive: a smaller dt"
    if interp > 1e-13 * float(np.abs(u).max()):      # not rounding of an exact ramp
        notes.append(f"drive interpolated by cubic Hermite between samples (exact values and "
                     f"rates of the motion): its error is at most {interp:.3g} "
                     "(h⁴/384·max|u⁗|, from the samples' fourth differences)" if hermite else
                     f"drive interpolated linearly between samples: its error is at most "
                     f"{interp:.3g} ({how})")
    else:
        interp = 0.0
    return interp



def _nonlinear(ss: StateSpace, circuit, z0, t, u, rtol, rate=None):
    """The clearance integrator; ``rate``: the drive's exact derivative at the samples
    (then the drive is interpolated by cubic Hermite between them, else linearly)."""
    kern = kernels()

    N, h = ss.size, t[1] - t[0]
    u = np.ascontiguousarray(u, dtype=float)
    mats, w_max = ss.memo("_clearance_setup", lambda: _clearance_setup(ss, circuit))
    # Steps may run across output times when the drive has no kinks there (it
    # is constant; a harmonic drive is generated by states), up to 1 rad of the
    # fastest mode with every contact closed, so no contact can be stepped over.
    dense = bool(np.all(u == u[0]))
    u = np.ascontiguousarray(np.vstack([u, rate if rate is not None else np.full(u.size, np.nan)]))
    hmax = min(1.0 / w_max, t[-1]) if w_max > 0 else t[-1]

    def run(tol, atol, hm, locate=True, out=None):
        out = np.empty((t.size, N)) if out is None else out
        steps = kern.dopri_run(z0.astype(float), 0.0, h, t.size, *mats, u, tol, atol, hm,
                               kern._A, kern._B4, kern._C, kern._D, dense, out,
                               *kern.scratch(N, mats[-1].shape[0]),
                               1e-6 * hm if locate else math.inf)
        if steps < 0:
            raise MechcircError("the clearance integrator's step fell below 1e-14 s "
                                "(the network is too stiff for it)")
        return out

    # The pilot that scales the absolute tolerance needs the states' peaks
    # only: it does not locate the kinks (which cost most of its steps: 1455
    # against 44 for the 10-mass chain of benchmarks/bench_transient.py).
    # (the pilots and the run at rtol share one array: a fresh one costs a page fault per 4 kB)
    scratch = np.empty((t.size, N))
    atol = _absolute_tolerance(lambda tol, a, hm: run(tol, a, hm, False, scratch), z0, rtol,
                               hmax)
    # Error estimate: the run asked for, and a reference at a REF_TOL× tighter
    # tolerance and 1/REF_H of the largest step (a run whose steps are limited
    # by hmax or by the drive's samples, as at loose tolerances, would
    # otherwise repeat itself).  The
    # reference is returned and the difference reported: it is about the error
    # of the run at rtol, which is many times the reference's (on the corpus of
    # tests/test_transient_estimates.py ≥ 4.6× at every rtol from 1e-3 to
    # 1e-10), so it bounds the error of what is returned.
    Z1 = run(rtol, atol, hmax, out=scratch)
    # (steps that end on every drive sample are limited by the sample step too)
    href = (hmax if dense else min(hmax, h)) / REF_H
    Z = run(rtol / REF_TOL, atol / REF_TOL, href)
    X = Z @ ss.Cx.T
    err = _peak(np.subtract(Z1, Z, out=Z1) @ ss.Cx.T)
    backend = "numba" if kern.HAVE_NUMBA else "Python"
    method = (f"Dormand-Prince 5(4) ({backend}), clearances in the RHS: rtol "
              f"{rtol / REF_TOL:g} and steps ≤ {href:.3g} s; error estimate = the "
              f"difference from the run at rtol {rtol:g} (absolute tolerance rtol × each "
              "state's peak)")
    peak_x, notes = _peak(X), []
    if err > rtol * peak_x:
        notes.append(f"the estimated error of x, {err:.2g}, is {err / max(peak_x, 1e-300):.1e} "
                     f"of the largest |x| ({peak_x:.3g}): above --rtol {rtol:g}, which is "
                     "not reached (the error adds up over the steps and contacts); a smaller "
                     "--rtol reduces it")
    return Z, X, method, err, notes


def _peak(a: np.ndarray, axis=None):
    """max |a| (over ``axis``) without forming |a| (NaN if a holds one)."""
    return np.maximum(a.max(axis=axis), -a.min(axis=axis)) if axis is not None else \
        float(max(a.max(), -a.min()))


def _absolute_tolerance(run: Callable, z0: np.ndarray, rtol: float, hmax: float) -> np.ndarray:
    """Absolute tolerance scaled to the solution, state by state: rtol × the
    state's peak over the run, from a loose pilot ``run(tol, atol, hmax)``
    (repeated once if the solution stayed far below the start's scale, so the
    pilot's absolute tolerance was too loose for it: a run from rest has no
    scale; a solution far above it was only integrated more tightly)."""
    N, scale = z0.size, max(float(np.abs(z0).max()), 0.0) or 1.0
    pilot_tol = max(rtol, 1e-4)
    for _ in range(2):
        peak = _peak(run(pilot_tol, np.full(N, pilot_tol * scale), hmax), axis=0)
        new = float(peak.max())
        if not (math.isfinite(new) and new > 0) or 0.1 * scale <= new:
            break
        scale = new
    if math.isfinite(float(peak.max())) and peak.max() > 0:
        floor = 1e-6 * peak.max()
        return rtol * np.maximum(peak, floor)
    return np.full(N, rtol * scale)


def _clearance_setup(ss: StateSpace, circuit):
    """(kernel matrices, largest |eigenvalue| with every contact closed) for :func:`_nonlinear`."""
    clear = backlash_elements(circuit)
    # each clearance's relative displacement and velocity from z and u (a row each)
    G = _incidences({n: i for i, n in enumerate(ss.nodes)}, [e for e, _ in clear],
                    len(ss.nodes)).T
    cx, dx, cv, dv = (G @ C for C in (ss.Cx, ss.Dx, ss.Cv, ss.Dv))
    prm = np.array([_law_params(e, comp) for e, comp in clear], dtype=float).reshape(-1, 3)
    extra = ss.extra
    if extra is None:
        raise ValueError("the model was built without its clearance elements' force map")
    mats = kernels().kernel_args(ss.A, ss.B, cx, dx, cv, dv, extra, prm)
    # A with every contact closed: A + Σ_e extra_e ⊗ (c_e cx_e + d_e cv_e).
    closed = ss.A + extra @ (prm[:, :1] * cx + prm[:, 1:2] * cv)
    w_max = float(np.abs(np.linalg.eigvals(closed)).max()) if ss.size else 0.0
    return mats, w_max


def _outputs(ss, circuit, t, Z, u_true, u, h, drive, method, err, notes, want=True,
             T=None, velocities=True, nx=None, drive_y=None, x_ready=None,
             v_ready=None) -> TransientResult:
    """Outputs from the states: z = Z[k] (or modal coordinates, z = T Z[k]).

    Every output is affine in z, so each is one product of Z with the output
    map (C T)ᵀ (BLAS-3 for node outputs, a vector for the drive's); terms of
    the drive that vanish are skipped.
    """
    def affine(C, Du=None, Dud=None, cols=None, Cz=None):   # C z + Du u + Dud u̇ at every sample
        if Cz is not None:              # C z already formed (in the recurrence): used in place
            out = Cz
        elif T is None:
            out = Z @ C.T
        elif cols is None:
            out = Z @ (C @ T).T
        else:                           # the other columns of Q do not reach C (x)
            out = Z[:, :cols] @ (C @ T[:, :cols]).T
        for coef, sig in ((Du, u), (Dud, udot)):
            if coef is not None and np.any(coef):
                out += np.multiply.outer(sig, coef)
        return out

    udot = np.gradient(u, h) if u.size > 1 else np.zeros_like(u)
    clear = {e.name: (e, comp) for e, comp in backlash_elements(circuit)} if ss.extra is not None else {}
    velocities = velocities or bool(want) or bool(clear)
    X = affine(ss.Cx, ss.Dx, cols=nx, Cz=x_ready)
    V = affine(ss.Cv, ss.Dv, ss.Ev, Cz=v_ready) if velocities else None
    index = {n: i for i, n in enumerate(ss.nodes)}
    if clear and V is not None:     # e and w of every clearance (V: formed when clear)
        G = _incidences(index, [e for e, _ in clear.values()], len(ss.nodes))
        Ec, Wc = G.T @ X.T, G.T @ V.T       # (rows contiguous, as the law takes them)
    law_cache = {name: _law_forces(e, comp, Ec[j], Wc[j])
                 for j, (name, (e, comp)) in enumerate(clear.items())}
    Acc = None
    if (want and any(e.kind == "mass" for e in circuit.elements)) or \
            (ss.kind == "velocity" and bool(clear)):
        # a = C_v ż + D_v u̇, with ż = A z + B u (+ the clearance forces): C_v A is
        # formed once, so the cost is one (n_t × N) · (N × n) product.
        Acc = affine(ss.Cv @ ss.A, ss.Cv @ ss.B, ss.Dv)
        if clear:                               # the clearance forces drive the masses too
            F = np.array([law_cache[name][0] for name in clear])
            Acc += F.T @ (ss.Cv @ ss.extra[:, :len(clear)]).T

    els = circuit.elements if want else ()
    force, dvm = _element_forces(els, index, X, V, Acc, clear, law_cache, t.size)
    drive_force, drive_velocity = _drive_output(ss, affine, drive_y, index, X, V, Acc, clear,
                                                law_cache)
    if ss.Ev.any() and drive.kind not in ("rest", "impulse"):
        notes.append("some nodes carry neither mass nor damping: their velocities use the "
                     "drive's derivative estimated from the samples")
    return TransientResult(time=t, nodes=ss.nodes, x=X, v=V, elements=tuple(e.name for e in els),
                           force=force, dv=dvm, drive_kind=ss.kind,
                           drive=u_true if ss.kind is not None else None,
                           drive_force=drive_force, drive_velocity=drive_velocity,
                           error=err, method=method, notes=notes, name=circuit.name,
                           drive_name=circuit.drive.name if circuit.drive is not None else None,
                           units=units_of(circuit.drive if circuit.drive is not None else
                                          all(map(circuit.rotational, circuit.elements))),
                           clearances={e.name: (e.n1, e.n2, e.backlash)
                                       for e, _ in backlash_elements(circuit)},
                           separations=_separations(t, Ec, Wc, clear, drive) if clear else [],
                           waveform=drive.label if ss.kind is not None else None)


def _drive_output(ss, affine, drive_y, index, X, V, Acc, clear: dict, law_cache: dict):
    """(force, velocity) the drive delivers, one of them None; ``affine`` as in :func:`_outputs`."""
    # linear: the drive's output is one vector, h·(M a + D v + K x) or g·v, affine in z
    dmap = drive_map(ss) if ss.kind == "force" or not clear else None
    if ss.kind != "velocity":
        return None, (affine(*dmap, Cz=drive_y) if dmap is not None else None)
    # Q = h·(M a + D v + K x + Σ g_e f_e): contracted with h first (vectors only)
    Q = affine(*dmap, Cz=drive_y) if dmap is not None else \
        sum(S @ r for S, r in zip((Acc, V, X), ss.drive_rows()))
    for name, (e, _comp) in clear.items():
        ge = incidence(index, e.n1, e.n2, len(ss.nodes))
        Q = Q + law_cache[name][0] * (ge @ ss.h)
    return Q, None


def _element_forces(els, index: dict, X, V, Acc, clear: dict, law_cache: dict, n_t: int):
    """(force, velocity difference) of every element in ``els``, (n_t, len(els)) each.

    Linear elements: value·η times the difference across them of x (springs),
    v (dampers) or a (masses), one product with the incidences for all; clearance springs and
    their companion dampers: their law's forces ``law_cache[spring name]``.
    """
    G = _incidences(index, els, len(index))
    dvm = V @ G if V is not None else np.zeros((n_t, 0))
    scale = np.array([e.value * e.eta for e in els])
    comp_of = {comp.name: e.name for e, comp in clear.values() if comp is not None}
    kinds = np.array([e.kind if e.name not in clear and e.name not in comp_of else "law"
                      for e in els])
    force = np.zeros((n_t, len(els)))
    # each kind's columns only (temporaries as wide as they are: fresh memory costs a
    # page fault per 4 kB, and a chain's full-width temporaries were half this function)
    for kind, Y in (("damper", dvm), ("spring", X), ("mass", Acc)):
        cols = np.flatnonzero(kinds == kind)
        if cols.size:                       # value·η folded into the incidences
            force[:, cols] = Y[:, cols] * scale[cols] if kind == "damper" else \
                Y @ (G[:, cols] * scale[cols])
    for j, e in enumerate(els):
        if e.name in clear or e.name in comp_of:
            sp = clear[e.name][0] if e.name in clear else clear[comp_of[e.name]][0]
            total, spring = law_cache[sp.name]
            force[:, j] = spring if e.name == sp.name else total - spring
    return force, dvm


def _incidences(index: dict, els, n: int) -> np.ndarray:
    """(n, len(els)): column j is e_n1 − e_n2 of element j (:func:`.model.incidence`), so
    Y @ G is the difference across every element at once (a product, not gathers)."""
    G = np.zeros((n, len(els)))
    for j, e in enumerate(els):
        G[:, j] = incidence(index, e.n1, e.n2, n)
    return G


def _law_forces(spring, comp, e, w):
    total, part = np.empty(e.size), np.empty(e.size)
    kernels().law_many(np.ascontiguousarray(e), np.ascontiguousarray(w),
                       *_law_params(spring, comp), total, part)
    return total, part
