"""Time-domain simulation of the sley models: :func:`simulate` and :func:`simulate_batch`.

Start (as the paper): at the first crank angle θ0 ∈ [0, 2π) where the rigid
sley acceleration ν(θ0) ω² is zero, no deformation, rigid-body velocities
(ω2P = ω, ω4P = μ(θ0) ω).  The crank shaft turns at constant ω.  R revolutions
are integrated; the last one (crank angles θ0 + 2π(R−1) … θ0 + 2πR) is tabulated
on a uniform grid and reported against the crank angle φ2 mod 2π.

Methods
-------
``"rk4"`` (default)
    Classical RK4 at a fixed step chosen from the linearised model's largest
    eigenvalue |λ|max over the cycle (``steps_per_period`` steps per 2π/|λ|max);
    output points between steps by cubic Hermite interpolation.
    Clearance dead zones and the beat-up window are evaluated inside the
    right-hand side (no restarts).  Compiled with numba when the ``fast`` extra is
    installed, else the same code runs as pure Python (``result.backend`` and
    ``result.notes`` say which).
``"rk4-python"``
    The same, forced pure Python.
``"DOP853"``, ``"RK45"``, ``"LSODA"``
    ``scipy.integrate.solve_ivp`` with a Python right-hand side and ``rtol``
    (default 1e-10, the reference), ``atol = rtol × scale`` per state.

Transfer functions: φ4(θ), μ, ν are tabulated from
:meth:`mechcirc.kinematics.FourBar.evaluate` (the exact closed form) at
``table_points`` crank angles and interpolated by quintic Hermite pieces (value,
first and second derivative matched at every node), so μ and ν are the exact
derivatives of the interpolated φ4; :func:`table_error` measures the
interpolation error against the closed form (ν to about 2e-9 relative with the
default 1024 intervals).
"""

from __future__ import annotations

import math
import os
import time
import warnings
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from ..errors import MechcircWarning, SolverError
from .models import ParameterError, SleyParameters

__all__ = ["SleyResult", "simulate", "simulate_params", "simulate_batch", "METHODS",
           "table_error", "start_angle", "SleyAccuracyWarning", "ACCURACY_GOAL"]

METHODS = ("rk4", "rk4-python", "DOP853", "RK45", "LSODA")
_SCIPY_METHODS = ("DOP853", "RK45", "LSODA")
TWO_PI = 2.0 * math.pi

#: Default RK4 steps per period of the fastest linearised mode.
DEFAULT_STEPS_PER_PERIOD = 50
#: Default output points per revolution (0.05° in crank angle).
DEFAULT_POINTS = 7200
#: Relative error estimate / periodicity above which a result is flagged (issue 11 §8).
ACCURACY_GOAL = 1e-3


class SleyAccuracyWarning(MechcircWarning):
    """A sley result may be inaccurate (error estimate, periodicity or too few steps)."""


#: Above this many RK4 steps per revolution the run is refused (see the message).
MAX_STEPS_PER_REV = 20_000_000


@dataclass(frozen=True)
class SleyResult:
    """One simulated revolution of a sley model, against crank angle.

    Attributes
    ----------
    params : SleyParameters
        The model (α, clearance, … included).
    crank_angle : ndarray, shape (n,)
        Driven-shaft crank angle φ2 mod 2π [rad], ascending.
    eps2P, eps4P, eps4T : ndarray, shape (n,)
        Angular accelerations of crank 2P, sley 4P and the rigid rocker
        ε4T = ν(φ2) ω² [rad/s²].
    M2V : ndarray, shape (n,)
        Driving moment in rod 2, C2 Δ(φ2 − φ2P) + k2 (ω − ω2P) [N·m].
    M4 : ndarray, shape (n,)
        Beat-up moment acting on the sley [N·m] (−M4 of eq. (4) with the
        default ``beat_sign=-1``).
    eps5P, M5V : ndarray or None
        The same for crank 5 (both-sides drive only).
    states : ndarray, shape (n, 4) or (n, 6)
        [δ2, ω2P, φ4P − φ̄4, ω4P] (both sides: [δ2, ω2P, δ5, ω5P, φ4P − φ̄4, ω4P]).
    extrema : dict
        ``name -> (min, max)`` for eps2P, eps4P, eps4T, M2V (, eps5P, M5V); eps4T
        is the exact extreme of ν ω² over the revolution (Brent-refined).
    revolution : int
        Which revolution is tabulated (1-based; the last simulated).
    theta0, phiP : float
        Start crank angle (ν = 0) and beat-up crank angle [rad].
    method, backend : str
        Method asked for; what ran (``"numba"``, ``"python"``, ``"scipy"``).
    wall_time : float
        Integration time [s] (compilation excluded when numba was warm; see
        ``compile_time``).
    compile_time : float
        Time of the first call's numba compilation or cache load [s], else 0.
    n_steps, nfev : int
        Steps taken and right-hand-side evaluations.
    notes : tuple of str
        Readings and fall-backs that apply (α, σ = α, numba missing, …), and
        the accuracy warnings.
    error_estimate : float or None
        RK4 methods: the largest change of an extremum (eps2P, eps4P, M2V, …)
        when the run is repeated at half the step, relative to that quantity's
        largest magnitude (``docs/sley.md`` compares it with the true error);
        None for the scipy methods and with ``error_estimate=False``.
    periodicity : float or None
        The same change from the previous revolution (None for R = 1).
    """

    params: SleyParameters
    crank_angle: NDArray[np.float64]
    eps2P: NDArray[np.float64]
    eps4P: NDArray[np.float64]
    eps4T: NDArray[np.float64]
    M2V: NDArray[np.float64]
    M4: NDArray[np.float64]
    eps5P: NDArray[np.float64] | None
    M5V: NDArray[np.float64] | None
    states: NDArray[np.float64]
    extrema: dict
    revolution: int
    theta0: float
    phiP: float
    method: str
    backend: str
    wall_time: float
    compile_time: float
    n_steps: int
    nfev: int
    notes: tuple[str, ...] = field(default=())
    error_estimate: float | None = None
    periodicity: float | None = None

    @property
    def alpha_deg(self) -> float:
        """Beat-up interval α [deg] used."""
        return math.degrees(self.params.alpha)

    def columns(self) -> dict[str, NDArray[np.float64]]:
        """Output arrays by name, crank angle in degrees first (for CSV)."""
        cols = {"crank_angle_deg": np.degrees(self.crank_angle), "eps2P": self.eps2P,
                "eps4P": self.eps4P, "eps4T": self.eps4T, "M2V": self.M2V}
        if self.eps5P is not None:
            cols["eps5P"] = self.eps5P
            cols["M5V"] = self.M5V
        cols["M4"] = self.M4
        return cols

    def summary(self) -> dict:
        """Plain-data summary for JSON output."""
        return {"label": self.params.label, "drive": self.params.drive,
                "alpha_deg": self.alpha_deg, "revolution": self.revolution,
                "method": self.method, "backend": self.backend,
                "extrema": {k: list(v) for k, v in self.extrema.items()},
                "theta0_deg": math.degrees(self.theta0), "phiP_deg": math.degrees(self.phiP),
                "wall_time_s": self.wall_time, "compile_time_s": self.compile_time,
                "n_steps": self.n_steps, "nfev": self.nfev, "notes": list(self.notes),
                "error_estimate": self.error_estimate, "periodicity": self.periodicity,
                "parameters": self.params.as_dict()}


# --------------------------------------------------------------------- set-up
_TABLE_CACHE: dict = {}


def _table(params: SleyParameters, n: int):
    """Quintic Hermite pieces of φ4(θ) − φ̄4 on n uniform intervals over [0, 2π)."""
    key = (params.l2P, params.l3, params.l4, params.d, params.branch, n)
    if key in _TABLE_CACHE:
        return _TABLE_CACHE[key]
    fb = params.fourbar()
    th = np.linspace(0.0, TWO_PI, n + 1)
    st = fb.evaluate(th)
    ref = 0.5 * (st.phi4.max() + st.phi4.min())
    f, f1, f2 = st.phi4 - ref, st.mu, st.nu
    h = TWO_PI / n
    a0, a1, a2 = f[:-1], f1[:-1], 0.5 * f2[:-1]
    r0 = f[1:] - (a0 + a1 * h + a2 * h * h)
    r1 = f1[1:] - (a1 + 2 * a2 * h)
    r2 = f2[1:] - 2 * a2
    A = np.array([[h ** 3, h ** 4, h ** 5], [3 * h ** 2, 4 * h ** 3, 5 * h ** 4],
                  [6 * h, 12 * h ** 2, 20 * h ** 3]])
    a345 = np.linalg.solve(A, np.vstack([r0, r1, r2]))
    tab = np.ascontiguousarray(np.column_stack([a0, a1, a2, a345[0], a345[1], a345[2]]))
    _TABLE_CACHE[key] = (tab, float(ref))
    return tab, float(ref)


def table_error(params: SleyParameters | None = None, n: int = 1024,
                samples: int = 100_003) -> dict:
    """Largest error of the tabulated φ4, μ, ν against the closed form of ``FourBar``.

    Returns
    -------
    dict
        ``phi4`` [rad], ``mu`` [1], ``nu`` [1/rad] absolute maxima over
        ``samples`` crank angles (interval midpoints and odd points included), and
        ``nu_rel`` = max |Δν| / max |ν|.
    """
    from . import _kernels

    kern = _kernels.load_python()
    params = params or SleyParameters()
    tab, ref = _table(params, n)
    th = np.linspace(0.0, TWO_PI, samples, endpoint=False) + 0.37 * TWO_PI / samples
    st = params.fourbar().evaluate(th)
    got = np.array([kern.transfer(float(t), tab) for t in th])
    err = {"phi4": float(np.max(np.abs(got[:, 0] + ref - st.phi4))),
           "mu": float(np.max(np.abs(got[:, 1] - st.mu))),
           "nu": float(np.max(np.abs(got[:, 2] - st.nu)))}
    err["nu_rel"] = err["nu"] / float(np.max(np.abs(st.nu)))
    return err


def start_angle(params: SleyParameters) -> float:
    """First crank angle θ0 in [0, 2π) with ν(θ0) = 0 (zero rigid sley acceleration) [rad]."""
    return _start_angle(params.l2P, params.l3, params.l4, params.d, params.branch)


@lru_cache(maxsize=64)
def _start_angle(l2P, l3, l4, d, branch) -> float:
    from scipy.optimize import brentq

    from .models import fourbar_of_lengths

    fb = fourbar_of_lengths(l2P, l3, l4, d, branch)
    th = np.linspace(0.0, TWO_PI, 721)
    nu = fb.evaluate(th).nu
    idx = np.flatnonzero(np.sign(nu[:-1]) * np.sign(nu[1:]) <= 0)
    i = int(idx[0])
    if nu[i] == 0.0:
        return float(th[i])
    return float(brentq(lambda t: fb.transfer(t)[2], th[i], th[i + 1], xtol=1e-14))


def _param_vector(params: SleyParameters, theta0: float, phiP: float):
    from . import _kernels as k

    v = np.zeros(k.N_PARAMS)
    p = params
    v[k.P_OMEGA], v[k.P_THETA0] = p.omega, theta0
    v[k.P_I2P], v[k.P_I4], v[k.P_I4P] = p.I2P, p.I4, p.I4P
    v[k.P_C2], v[k.P_C4], v[k.P_K2], v[k.P_K4] = p.C2, p.C4, p.k2, p.k4
    # the kernel subtracts M0 sin(…) from the sley's moments, as eq. (4) prints it
    v[k.P_CL], v[k.P_M0], v[k.P_PHIP] = p.clearance, -p.beat_sign * p.M0, phiP
    v[k.P_ALPHA], v[k.P_SIGMA] = p.alpha, p.sigma
    if p.drive == "both-sides":
        v[k.P_I5P], v[k.P_I7], v[k.P_C5] = p.I5P, p.I7, p.C5
        v[k.P_C7], v[k.P_K5], v[k.P_K7] = p.C7, p.k5, p.k7
    return v


def _initial_state(params: SleyParameters, theta0: float, ref: float):
    phi4, mu, _ = params.fourbar().transfer(theta0)
    w = params.omega
    if params.drive == "one-side":
        return np.array([0.0, w, phi4 - ref, mu * w])
    return np.array([0.0, w, 0.0, w, phi4 - ref, mu * w])


_PY_KERNELS = None
_COMPILED = False


def _kernels_for(method: str):
    """(kernel module, backend name, note) for an RK4 method."""
    global _PY_KERNELS
    note = ""
    if method == "rk4":
        from . import _kernels

        if _kernels.HAVE_NUMBA:
            return _kernels, "numba", note
        note = ("numba is not importable (install the 'fast' extra: pip install "
                "'mechcirc[fast]'); ran the same RK4 as pure Python, about 100x slower")
    if _PY_KERNELS is None:
        from . import _kernels

        _PY_KERNELS = _kernels.load_python()
    return _PY_KERNELS, "python", note


# ----------------------------------------------------------------- simulate
def simulate(drive: str = "one-side", variant: int = 3, revolutions: int = 5,
             method: str | None = None, *, params: SleyParameters | None = None,
             points_per_revolution: int = DEFAULT_POINTS,
             steps_per_period: float | None = None, rtol: float | None = None,
             table_points: int = 1024, revolution: int | None = None,
             progress: Callable[[int, int], None] | None = None,
             error_estimate: bool = True, **overrides) -> SleyResult:
    """Simulate a preset variant (Table 1 or 2) or given parameters over R revolutions.

    Parameters
    ----------
    drive : {"one-side", "both-sides"}
        Table 1 (eq. 4) or Table 2 (eq. 9); ignored when ``params`` is given.
    variant : int
        Preset 1 … 7; ignored when ``params`` is given.
    revolutions : int
        R ≥ 1 revolutions from the start; the last one is tabulated.
    method : str, optional
        One of :data:`METHODS`; default ``"rk4"``.
    params : SleyParameters, optional
        Explicit parameters instead of a preset.
    points_per_revolution : int
        Uniform output grid in crank angle (default 7200, i.e. 0.05°).
    steps_per_period : float, optional
        RK4 steps per period 2π/|λ|max of the fastest linearised mode
        (default 50); more is more accurate.
    rtol : float, optional
        Relative tolerance of the scipy methods (default 1e-10).
    table_points : int
        Intervals of the φ4/μ/ν table (default 1024).
    revolution : int, optional
        Tabulate this revolution (1 … R) instead of the last; the integration
        stops after it (later revolutions cannot change it).
    progress : callable, optional
        ``progress(done, total)`` after each revolution.
    **overrides
        :class:`SleyParameters` fields, e.g. ``alpha=math.radians(30)``,
        ``clearance=0.01``, ``omega=120``.

    Returns
    -------
    SleyResult

    Raises
    ------
    ParameterError
        Bad parameter, unknown method or option (ω ≤ 0 included).
    GeometryError
        The four-bar cannot be assembled or is not a crank-rocker.
    SolverError
        The integration failed or would need too many steps (the message says
        what to change).

    Examples
    --------
    >>> r = simulate("one-side", 1, revolutions=1, points_per_revolution=720)
    >>> [round(x) for x in r.extrema["eps4T"]]
    [-2319, 2915]
    """
    if params is None:
        from .presets import preset

        params = preset(drive, variant, **overrides)
    elif overrides:
        params = params.replace(**overrides)
    return simulate_params(params, revolutions, method,
                           points_per_revolution=points_per_revolution,
                           steps_per_period=steps_per_period, rtol=rtol,
                           table_points=table_points, revolution=revolution,
                           progress=progress, error_estimate=error_estimate)


def simulate_params(params: SleyParameters, revolutions: int = 5, method: str | None = None,
                    *, points_per_revolution: int = DEFAULT_POINTS,
                    steps_per_period: float | None = None, rtol: float | None = None,
                    table_points: int = 1024, revolution: int | None = None,
                    progress: Callable[[int, int], None] | None = None,
                    error_estimate: bool = True) -> SleyResult:
    """:func:`simulate` for explicit :class:`SleyParameters` (same options).

    ``error_estimate`` (rk4 methods): repeat the run at half the step and keep
    the relative change of the extrema as ``result.error_estimate`` (about
    three times the cost).  A :class:`SleyAccuracyWarning` is issued when it or
    the periodicity exceeds 1e-3, or fewer steps per period than the default
    are used.
    """
    method = "rk4" if method is None else method
    if method not in METHODS:
        raise ParameterError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if isinstance(revolutions, bool) or not isinstance(revolutions, (int, np.integer)) \
            or revolutions < 1:
        raise ParameterError(f"revolutions must be an integer >= 1, got {revolutions!r}")
    if revolution is not None:
        if isinstance(revolution, bool) or not isinstance(revolution, (int, np.integer)) \
                or not 1 <= revolution <= revolutions:
            raise ParameterError(f"revolution must be an integer in 1..{revolutions}, "
                                 f"got {revolution!r}")
        revolutions = int(revolution)       # later revolutions cannot change this one
    if int(points_per_revolution) < 16:
        raise ParameterError(f"points_per_revolution must be >= 16, got {points_per_revolution!r}")
    if method in _SCIPY_METHODS:
        if steps_per_period is not None:
            raise ParameterError(f"steps_per_period applies to the rk4 methods, not {method}")
        rtol = 1e-10 if rtol is None else float(rtol)
        if not 1e-14 <= rtol < 1:
            raise ParameterError(f"rtol must be in [1e-14, 1), got {rtol!r}")
    else:
        if rtol is not None:
            raise ParameterError(f"rtol applies to the scipy methods, not {method}; "
                                 "use steps_per_period")
        steps_per_period = DEFAULT_STEPS_PER_PERIOD if steps_per_period is None \
            else float(steps_per_period)
        if not steps_per_period >= 1:
            raise ParameterError(f"steps_per_period must be >= 1, got {steps_per_period!r}")

    npts = int(points_per_revolution)
    fb = params.fourbar()
    theta0 = start_angle(params)
    phiP = fb.dead_centres()[0].theta
    tab, ref = _table(params, int(table_points))
    pvec = _param_vector(params, theta0, phiP)
    y = _initial_state(params, theta0, ref)
    both = params.drive == "both-sides"
    period = TWO_PI / params.omega
    notes = [f"alpha = {math.degrees(params.alpha):g} deg (beat-up interval; sigma = alpha)"]
    if params.M0 > 0:
        notes.append("beat-up moment enters the sley equation as " +
                     ("-M4 (eq. 4 as printed)" if params.beat_sign < 0 else
                      "+M4 (beat_sign=+1: along the rigid acceleration at beat-up)"))

    compile_time = 0.0
    estimate = periodicity = None
    warn = []
    if method in _SCIPY_METHODS:
        ts, ys, n_steps, nfev, backend, wall = _run_scipy(
            method, rtol, both, pvec, tab, y, period, revolutions, npts, params, progress)
        kern, _, _ = _kernels_for("rk4-python")
    else:
        kern, backend, note = _kernels_for(method)
        if note:
            notes.append(note)
        if backend == "numba":
            compile_time = _warm_up(kern, both, pvec, tab, y)
        from .linear import max_rate

        rate = max_rate(params)
        need = period * rate * steps_per_period / TWO_PI      # steps per revolution
        if need > MAX_STEPS_PER_REV:
            raise SolverError(
                f"the stiffest linearised mode (|lambda| = {rate:.4g} 1/s) needs "
                f"{need:.3g} RK4 steps per revolution at steps_per_period="
                f"{steps_per_period:g}, more than the limit {MAX_STEPS_PER_REV:.0e}: "
                "lower the stiffest rigidity (C2, C4, ...), raise the inertias, or use "
                "method='LSODA'", status="too-stiff")
        per_rev = max(int(math.ceil(need)), 16)
        h = period / per_rev
        y_start = y.copy()
        ts, ys, prev, wall = _rk4_pass(kern, both, pvec, tab, y, period, per_rev, revolutions,
                                       npts, progress, steps_per_period)
        if revolutions >= 2:
            periodicity = _rel_change(_extrema_of(kern, both, pvec, tab, ts, ys),
                                      _extrema_of(kern, both, pvec, tab, *prev))
        if error_estimate:
            fts, fys, _, _ = _rk4_pass(kern, both, pvec, tab, y_start.copy(), period,
                                       2 * per_rev, revolutions, npts, None,
                                       2 * steps_per_period)
            estimate = _rel_change(_extrema_of(kern, both, pvec, tab, ts, ys),
                                   _extrema_of(kern, both, pvec, tab, fts, fys))
        if steps_per_period < DEFAULT_STEPS_PER_PERIOD:
            warn.append(f"{steps_per_period:g} RK4 steps per period of the fastest mode, fewer "
                        f"than the default {DEFAULT_STEPS_PER_PERIOD}: the extrema may be far "
                        "off (raise steps_per_period)")
        n_steps = per_rev * revolutions
        nfev = 4 * n_steps + revolutions          # + the first stage of each call
        notes.append(f"RK4 step {h:.4g} s ({per_rev} steps per revolution)")

    if estimate is not None and estimate > ACCURACY_GOAL:
        warn.append(f"error estimate {estimate:.2g} > {ACCURACY_GOAL:g}: the extrema change by "
                    "that much (relative) at half the step; raise steps_per_period or use "
                    "method='DOP853'")
    if periodicity is not None and periodicity > ACCURACY_GOAL:
        warn.append(f"not periodic yet: the extrema changed by {periodicity:.2g} (relative) "
                    f"from revolution {revolutions - 1} to {revolutions}; raise revolutions")
    for w in warn:
        warnings.warn(f"{params.label or params.drive}: {w}", SleyAccuracyWarning, stacklevel=3)
    notes += [f"warning: {w}" for w in warn]
    result = _assemble(params, kern, both, pvec, tab, ts, ys, theta0, phiP, revolutions,
                       method, backend, wall, compile_time, n_steps, nfev, notes)
    return replace(result, error_estimate=estimate, periodicity=periodicity)


def _rk4_pass(kern, both, pvec, tab, y, period, per_rev, revolutions, npts, progress, spp):
    """R revolutions of RK4 from y (in place): (ts, ys) of the last, (ts, ys) of the one
    before (or None), wall time."""
    h = period / per_rev
    rec_y, rec_t = np.empty((npts, y.size)), np.empty(npts)
    prev = (np.empty(npts), np.empty((npts, y.size))) if revolutions >= 2 else None
    dummy_y, dummy_t = np.empty((0, y.size)), np.empty(0)
    t_start = time.perf_counter()
    for r in range(revolutions):
        if r == revolutions - 1:
            ry, rt = rec_y, rec_t
        elif r == revolutions - 2:
            rt, ry = prev
        else:
            ry, rt = dummy_y, dummy_t
        t_end, rows, ok = kern.rk4_run(both, pvec, tab, y, r * period, h, per_rev,
                                       r * period, period / npts, ry, rt)
        if not ok:
            raise SolverError(
                f"RK4 diverged at t = {t_end:.6g} s (revolution {r + 1}) with step "
                f"{h:.3g} s: raise steps_per_period (now {spp:g})", status="diverged")
        if ry.shape[0] and rows != npts:
            raise SolverError(f"internal: RK4 stored {rows} of {npts} output points",
                              status="output")
        if progress is not None:
            progress(r + 1, revolutions)
    return rec_t, rec_y, prev, time.perf_counter() - t_start


def _extrema_of(kern, both, pvec, tab, ts, ys) -> dict:
    out = np.empty((ts.size, 6))
    kern.outputs(both, pvec, tab, np.ascontiguousarray(ts), np.ascontiguousarray(ys), out)
    cols = (0, 1, 2, 3, 4) if both else (0, 1, 2)
    return {j: _mm(out[:, j]) for j in cols}


def _rel_change(a: dict, b: dict) -> float:
    """Largest change of an extremum, relative to that quantity's largest magnitude."""
    worst = 0.0
    for k, (lo, hi) in a.items():
        scale = max(abs(lo), abs(hi))
        if scale > 0:
            worst = max(worst, abs(lo - b[k][0]) / scale, abs(hi - b[k][1]) / scale)
    return worst


def _warm_up(kern, both, pvec, tab, y) -> float:
    """Compile (or load from numba's cache) once per process; return the time it took."""
    global _COMPILED
    if _COMPILED:
        return 0.0
    t0 = time.perf_counter()
    yy = y.copy()
    kern.rk4_run(both, pvec, tab, yy, 0.0, 1e-6, 2, 0.0, 1e-6, np.empty((1, y.size)),
                 np.empty(1))
    kern.outputs(both, pvec, tab, np.zeros(1), np.array([y]), np.empty((1, 6)))
    _COMPILED = True
    return time.perf_counter() - t0


def _run_scipy(method, rtol, both, pvec, tab, y0, period, revolutions, npts, params, progress):
    from scipy.integrate import solve_ivp

    kern, _, _ = _kernels_for("rk4-python")
    n = y0.size
    aux = np.empty(6)
    rhs = kern.rhs

    def f(t, y):
        dy = np.empty(n)
        rhs(both, t, y, pvec, tab, dy, aux)
        return dy

    w = params.omega
    scale = np.array([1e-4, w, 1e-2, 0.1 * w]) if not both else \
        np.array([1e-4, w, 1e-4, w, 1e-2, 0.1 * w])
    t_last = (revolutions - 1) * period
    t_eval = t_last + np.arange(npts) * (period / npts)
    t0 = time.perf_counter()
    ys_parts, y = [], y0.copy()
    n_steps = nfev = 0
    for r in range(revolutions):
        last = r == revolutions - 1
        sol = solve_ivp(f, (r * period, (r + 1) * period), y, method=method, rtol=rtol,
                        atol=rtol * scale, dense_output=last)
        if sol.status != 0:
            raise SolverError(f"solve_ivp({method}) failed in revolution {r + 1}: "
                              f"{sol.message}", status=sol.status)
        n_steps += len(sol.t) - 1
        nfev += sol.nfev
        if last:
            ys_parts.append(sol.sol(t_eval).T)
        else:
            y = sol.y[:, -1].copy()
        if progress is not None:
            progress(r + 1, revolutions)
    wall = time.perf_counter() - t0
    return t_eval, np.ascontiguousarray(ys_parts[0]), n_steps, nfev, "scipy", wall


def _assemble(params, kern, both, pvec, tab, ts, ys, theta0, phiP, revolutions, method,
              backend, wall, compile_time, n_steps, nfev, notes) -> SleyResult:
    out = np.empty((ts.size, 6))
    kern.outputs(both, pvec, tab, np.ascontiguousarray(ts), np.ascontiguousarray(ys), out)
    crank = (theta0 + params.omega * ts) % TWO_PI
    # a uniform grid over one revolution: sorting by crank angle is one rotation
    wrap = np.flatnonzero(np.diff(crank) < 0)
    order = np.roll(np.arange(crank.size), -(int(wrap[0]) + 1)) if wrap.size == 1 \
        else np.argsort(crank, kind="stable")
    crank = crank[order]
    out = out[order]
    fb = params.fourbar()
    eps4T = fb.evaluate(crank).nu * params.omega ** 2
    nlo, nhi = _nu_range(params.l2P, params.l3, params.l4, params.d, params.branch)
    lo, hi = nlo * params.omega ** 2, nhi * params.omega ** 2
    extrema = {"eps2P": _mm(out[:, 0]), "eps4P": _mm(out[:, 1]), "eps4T": (lo, hi),
               "M2V": _mm(out[:, 2])}
    eps5P = M5V = None
    if both:
        eps5P, M5V = out[:, 3].copy(), out[:, 4].copy()
        extrema["eps5P"] = _mm(eps5P)
        extrema["M5V"] = _mm(M5V)
    return SleyResult(params=params, crank_angle=crank, eps2P=out[:, 0].copy(),
                      eps4P=out[:, 1].copy(), eps4T=eps4T, M2V=out[:, 2].copy(),
                      M4=-out[:, 5], eps5P=eps5P, M5V=M5V, states=ys[order],
                      extrema=extrema, revolution=revolutions, theta0=theta0, phiP=phiP,
                      method=method, backend=backend, wall_time=wall,
                      compile_time=compile_time, n_steps=n_steps, nfev=nfev,
                      notes=tuple(notes))


@lru_cache(maxsize=64)
def _nu_range(l2P, l3, l4, d, branch):
    from .models import fourbar_of_lengths

    (_, lo), (_, hi) = fourbar_of_lengths(l2P, l3, l4, d, branch).nu_extrema()
    return lo, hi


def _mm(a) -> tuple[float, float]:
    return float(np.min(a)), float(np.max(a))


# -------------------------------------------------------------------- batch
def _batch_worker(job):
    params, revolutions, method, kwargs = job
    return simulate_params(params, revolutions, method, **kwargs)


def simulate_batch(params_list: list[SleyParameters] | None = None, revolutions: int = 5,
                   method: str | None = None, *, processes: int | None = None,
                   **kwargs) -> list[SleyResult]:
    """Simulate many models in parallel (default: the 14 presets of Tables 1 and 2).

    Parameters
    ----------
    params_list : list of SleyParameters, optional
        Default :func:`~mechcirc.sley.presets.all_presets`.
    revolutions, method, **kwargs
        As :func:`simulate_params`.
    processes : int, optional
        Worker processes (default: every core, ``os.cpu_count()``); 1 runs in
        this process.

    Returns
    -------
    list of SleyResult
        In the order of ``params_list``.
    """
    from concurrent.futures import ProcessPoolExecutor

    if params_list is None:
        from .presets import all_presets

        params_list = all_presets()
    jobs = [(p, revolutions, method, kwargs) for p in params_list]
    processes = processes or os.cpu_count() or 1
    if processes == 1 or len(jobs) == 1:
        return [_batch_worker(j) for j in jobs]
    with ProcessPoolExecutor(max_workers=min(processes, len(jobs))) as pool:
        return list(pool.map(_batch_worker, jobs))
