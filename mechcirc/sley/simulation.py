"""The sley presets in the time domain: :func:`simulate` and :func:`simulate_batch`.

A preset layer over the scene: the parameters become the scene of
:func:`mechcirc.sley.scenes.sley_scene` (what ``examples/mrazek_*.toml`` hold, with the
variant's values) and :func:`mechcirc.scene.simulate_scene` integrates its Lagrange II
equations, written once for any scene -- eqs. (4) and (9) are not written again here.
This module maps the scene's outputs onto the paper's names (ε2P, ε4P, ε4T, M2V,
ε5P, M5V) and keeps the paper's conventions.

Start (as the paper): at the first crank angle θ0 ∈ [0, 2π) where the rigid
sley acceleration ν(θ0) ω² is zero, no deformation, rigid-body velocities
(ω2P = ω, ω4P = μ(θ0) ω).  The crank shaft turns at constant ω.  R revolutions
are integrated; the last one (crank angles θ0 + 2π(R−1) … θ0 + 2πR) is tabulated
on a uniform grid and reported against the crank angle φ2 mod 2π.

Methods (those of :func:`~mechcirc.scene.simulate_scene`)
----------------------------------------------------------
``"rk4"`` (default)
    Classical RK4 at a fixed step chosen from the linearised model's largest
    eigenvalue |λ|max over the cycle (``steps_per_period`` steps per 2π/|λ|max);
    output points between steps by cubic Hermite interpolation.
    Clearance dead zones and the beat-up window are evaluated inside the
    right-hand side; a step in which a gap's edge is crossed or the window
    opens or closes is cut there, so RK4 keeps its order through the impacts.  Compiled with numba when the ``fast`` extra is
    installed, else the same code runs as pure Python (``result.backend`` and
    ``result.notes`` say which).
``"rk4-python"``
    The same, forced pure Python.
``"rk8"``
    The 8th-order formula of DOP853 at a fixed step (8 steps per period, else 16),
    cut at the same kinks, with quintic Hermite output in the coordinates.
``"DOP853"``, ``"RK45"``, ``"LSODA"``
    ``scipy.integrate.solve_ivp`` on the same right-hand side with ``rtol``
    (default 1e-10, the reference), in the deviations from the rigid motion.

Transfer functions: every rotation is tabulated from the linkage solver at
``table_points`` crank angles and interpolated by quintic Hermite pieces (value,
first and second derivative matched at every node), so μ and ν are the exact
derivatives of the interpolated φ4; :func:`table_error` measures the
interpolation error against the closed form of :class:`~mechcirc.kinematics.FourBar`.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from ..errors import SleyAccuracyWarning
from ..limits import METHODS
from ..sources import data_frame, summary_repr
from .models import ParameterError, SleyParameters, linkage_constants, start_angle
from .presets import all_presets, preset
from .scenes import ALIASES, sley_scene

__all__ = ["SleyResult", "simulate", "simulate_params", "simulate_batch", "METHODS",
           "table_error", "start_angle", "SleyAccuracyWarning"]

TWO_PI = 2.0 * math.pi

#: Default output points per revolution (0.05° in crank angle).
DEFAULT_POINTS = 7200


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
        RK4 methods: the largest change of an extremum of any of the scene's
        outputs (accelerations, rod moments and twists, …) between the run at
        the step (the one returned) and a run at twice the step, relative to
        that quantity's largest magnitude (``docs/sley.md`` compares it with the
        true error); the scipy methods: the same change between the runs at
        rtol and rtol/100 (the one returned); None with ``error_estimate=False``.
    periodicity : float or None
        The same change from the previous revolution, of the run at twice the step
        when there is one (None for R = 1).
    scene_extrema : dict
        The scene's own outputs ``BODY.acceleration``, ``ELEMENT.force``,
        ``ELEMENT.deformation``, ``drive.moment``, ``M4.moment`` -> (min, max) (the
        points' accelerations, which the result does not return, are not computed).
    """

    __repr__ = summary_repr

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
    scene_extrema: dict = field(default_factory=dict)

    @property
    def alpha_deg(self) -> float:
        """Beat-up interval α [deg] used."""
        return math.degrees(self.params.alpha)

    def columns(self) -> dict[str, NDArray[np.float64]]:
        """Output arrays by name, crank angle in degrees first (for CSV)."""
        second = {name: col for name, col in (("eps5P", self.eps5P), ("M5V", self.M5V))
                  if col is not None}       # the second crank's side (variants with one)
        return {"crank_angle_deg": np.degrees(self.crank_angle), "eps2P": self.eps2P,
                "eps4P": self.eps4P, "eps4T": self.eps4T, "M2V": self.M2V, **second,
                "M4": self.M4}

    def to_dataframe(self):
        """:meth:`columns` as a ``pandas.DataFrame``, a row per sample; ``attrs["units"]``
        the unit of each column: deg, rad/s² (``eps*``), N·m (``M*``)."""
        cols = self.columns()
        return data_frame(cols, {c: {"c": "deg", "e": "rad/s²", "M": "N·m"}[c[0]] for c in cols})

    def summary(self) -> dict:
        """Plain-data summary for JSON output."""
        return {"label": self.params.label, "drive": self.params.drive,
                "alpha_deg": self.alpha_deg, "revolution": self.revolution,
                "method": self.method, "backend": self.backend,
                "extrema": {k: list(v) for k, v in
                            {**self.scene_extrema, **self.extrema}.items()},
                "theta0_deg": math.degrees(self.theta0), "phiP_deg": math.degrees(self.phiP),
                "wall_time_s": self.wall_time, "compile_time_s": self.compile_time,
                "n_steps": self.n_steps, "nfev": self.nfev, "notes": list(self.notes),
                "error_estimate": self.error_estimate, "periodicity": self.periodicity,
                "parameters": self.params.as_dict()}


# --------------------------------------------------------------------- set-up
@lru_cache(maxsize=16)
def _model(params: SleyParameters, table_points: int):
    """The scene of ``params`` and its motion model (memoised: the tables are the cost)."""
    from ..scene.motion import motion_model

    scene = sley_scene(params)
    return scene, motion_model(scene, table_points=int(table_points))


def table_error(params: SleyParameters | None = None, n: int = 1024,
                samples: int = 100_003) -> dict:
    """Largest error of the tabulated φ4, μ, ν against the closed form of ``FourBar``.

    The table is the scene model's rotation of the rocker against the crank's.

    Parameters
    ----------
    params : SleyParameters, optional
        Default: Table 1 variant 3.
    n : int
        Table intervals.
    samples : int

    Returns
    -------
    dict
        ``phi4`` [rad], ``mu`` [1], ``nu`` [1/rad] absolute maxima over
        ``samples`` crank angles (interval midpoints and odd points included), and
        ``nu_rel`` = max |Δν| / max |ν|.
    """
    from ..scene.motion import function_args
    from ..scene.simulation import kernels_for

    params = params or SleyParameters()
    _, model = _model(params, n)
    a = model.arrays
    f = model.body_fn["rocker"]
    th = np.linspace(0.0, TWO_PI, samples, endpoint=False) + 0.37 * TWO_PI / samples
    got = np.empty((th.size, 3))
    kernels_for("rk4")[0].eval_many(*function_args(a, f), th, got)
    fb = params.fourbar()
    st = fb.evaluate(th)
    phi0 = fb.transfer(0.0)[0]
    err = {"phi4": float(np.max(np.abs(got[:, 0] + phi0 - st.phi4))),
           "mu": float(np.max(np.abs(got[:, 1] - st.mu))),
           "nu": float(np.max(np.abs(got[:, 2] - st.nu)))}
    err["nu_rel"] = err["nu"] / float(np.max(np.abs(st.nu)))
    return err


# ----------------------------------------------------------------- simulate
def simulate(drive: str = "one-side", variant: int = 3, revolutions: int = 5,
             method: str | None = None, *, params: SleyParameters | None = None,
             points_per_revolution: int = DEFAULT_POINTS, steps_per_period: float | None = None,
             rtol: float | None = None, table_points: int = 1024, revolution: int | None = None,
             progress: Callable[[int, int], None] | None = None,
             error_estimate: bool = True, **overrides) -> SleyResult:
    """Simulate a preset variant (Table 1 or 2) or given parameters over R revolutions.

    Parameters
    ----------
    drive, variant : {"one-side", "both-sides"}, int
        Table 1 (eq. 4) or Table 2 (eq. 9), and its preset 1 … 7; ignored when ``params`` is given.
    revolutions : int
        R ≥ 1 revolutions from the start; the last one is tabulated.
    method : str, optional
        One of :data:`METHODS`; default ``"rk4"``.
    params : SleyParameters, optional
        Explicit parameters instead of a preset.
    points_per_revolution : int
        Uniform output grid in crank angle (default 7200, i.e. 0.05°).
    steps_per_period : float, optional
        RK4 steps per period 2π/|λ|max of the fastest linearised mode (default: 25 when
        the estimate is then ≤ the scenes' ``ACCURACY_GOAL``, 1e-3, else 50; 50 without it).
    rtol : float, optional
        Relative tolerance of the scipy methods (default 1e-10).
    table_points : int
        Intervals of the φ4/μ/ν table (default 1024).
    revolution : int, optional
        Tabulate this revolution (1 … R) instead of the last; the integration stops after it.
    progress : callable, optional
        ``progress(done, total)`` after each revolution.
    error_estimate : bool
        Also run at twice the step (scipy methods: rtol/100) for ``SleyResult.error_estimate``.
    **overrides
        :class:`SleyParameters` fields, e.g. ``alpha=math.radians(30)``, ``clearance=0.01``.

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
        The integration failed or would need too many steps (the message says how).

    Examples
    --------
    >>> r = simulate("one-side", 1, revolutions=1, points_per_revolution=720)
    >>> [round(x) for x in r.extrema["eps4T"]]
    [-2319, 2915]
    """
    return simulate_params(_parameters(drive, variant, params, overrides), revolutions,
                           method, points_per_revolution=points_per_revolution,
                           steps_per_period=steps_per_period, rtol=rtol,
                           table_points=table_points, revolution=revolution,
                           progress=progress, error_estimate=error_estimate)


def _parameters(drive: str, variant: int, params: SleyParameters | None,
                overrides: dict) -> SleyParameters:
    """``params`` or else the preset ``drive``/``variant``, with the ``overrides``."""
    if params is None:
        return preset(drive, variant, **overrides)
    return params.replace(**overrides) if overrides else params


def simulate_params(params: SleyParameters, revolutions: int = 5, method: str | None = None,
                    *, points_per_revolution: int = DEFAULT_POINTS,
                    steps_per_period: float | None = None, rtol: float | None = None,
                    table_points: int = 1024, revolution: int | None = None,
                    progress: Callable[[int, int], None] | None = None,
                    error_estimate: bool = True) -> SleyResult:
    """:func:`simulate` for explicit :class:`SleyParameters` (same options).

    ``error_estimate`` (rk4 methods): a run at twice the step (half the steps per
    period) beside the returned one, and the relative change of the extrema as
    ``result.error_estimate`` (:func:`mechcirc.scene.simulate_scene`).  A
    :class:`SleyAccuracyWarning` is issued when it or
    the periodicity exceeds 1e-3, or fewer steps per period than the default
    are used.  The run is the scene's (:func:`mechcirc.scene.simulate_scene`).

    Parameters
    ----------
    params : SleyParameters
    revolutions, method, points_per_revolution, steps_per_period, rtol, table_points, revolution, progress
        As :func:`simulate`.
    error_estimate : bool
        Repeat the run at twice the step (above).

    Returns
    -------
    SleyResult
        The last (or the chosen) revolution, tabulated.
    """
    from ..scene.simulation import SceneAccuracyWarning, check_run, simulate_scene

    method = "rk4" if method is None else method
    check_run(method, revolutions, revolution, points_per_revolution, steps_per_period, rtol,
              ParameterError, "points_per_revolution")     # before the model is built
    params.fourbar()                            # GeometryError: not a crank-rocker
    theta0, *linkage = linkage_constants(params.l2P, params.l3, params.l4, params.d,
                                         params.branch)
    scene, model = _model(params, table_points)
    notes = [f"alpha = {math.degrees(params.alpha):g} deg (beat-up interval; sigma = alpha)"]
    if params.M0 > 0:
        notes.append("beat-up moment enters the sley equation as " +
                     ("-M4 (eq. 4 as printed)" if params.beat_sign < 0 else
                      "+M4 (beat_sign=+1: along the rigid acceleration at beat-up)"))
    with warnings.catch_warnings(record=True, action="always",
                                 category=SceneAccuracyWarning) as caught:
        m = simulate_scene(scene, model=model, revolutions=revolutions, revolution=revolution,
                           start_deg=math.degrees(theta0), steps_per_period=steps_per_period,
                           points=points_per_revolution, method=method, rtol=rtol,
                           progress=progress, error_estimate=error_estimate, exact_rigid=False,
                           point_accelerations=False)
    for w in caught:
        if issubclass(w.category, SceneAccuracyWarning):
            text = str(w.message).split(": ", 1)[-1]
            warnings.warn(f"{params.label or params.drive}: {text}", SleyAccuracyWarning,
                          stacklevel=3)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return _result(params, model, m, theta0, linkage, notes)


def _result(params: SleyParameters, model, m, theta0: float, linkage: list,
            notes: list) -> SleyResult:
    """The scene's motion under the paper's names and state convention (``linkage``:
    :func:`~mechcirc.sley.models.linkage_constants` but θ0)."""
    v = m.values
    both = params.drive == "both-sides"
    w = params.omega
    # the rigid rocker's ν ω² from the scene's tables (within 1.1e-10 of the closed form's ν,
    # table_error()); its extrema below from the closed form (the scene is asked not to
    # refine its own: exact_rigid=False)
    phiP, sley_off, nlo, nhi = linkage
    extrema = {"eps2P": m.extrema["eps2P"], "eps4P": m.extrema["eps4P"],
               "eps4T": (nlo * w ** 2, nhi * w ** 2), "M2V": m.extrema["M2V"],
               **{k: m.extrema[k] for k in ("eps5P", "M5V") if both}}
    # states in the paper's convention: [δ2, ω2P, (δ5, ω5P,) φ4P − φ̄4, ω4P]
    coord = list(model.coordinate[1:])
    n = len(coord)
    phi2 = theta0 + w * m.time
    cols = []
    for name in (("crank", "crank5") if both else ("crank",)) + ("sley",):
        i = coord.index(name)
        offset = sley_off if name == "sley" else -phi2
        cols += [m.states[:, i] + offset, m.states[:, n + i]]
    scene_extrema = {k: x for k, x in m.extrema.items()
                     if k not in ALIASES["both-sides"] and not k.endswith(".rigid_acceleration")}
    return SleyResult(params=params, crank_angle=m.crank_angle, eps2P=v["eps2P"],
                      eps4P=v["eps4P"], eps4T=v["eps4T"], M2V=v["M2V"], M4=v["M4.moment"],
                      eps5P=v["eps5P"] if both else None, M5V=v["M5V"] if both else None,
                      states=np.column_stack(cols), extrema=extrema,
                      revolution=m.revolution, theta0=theta0, phiP=phiP, method=m.method,
                      backend=m.backend, wall_time=m.wall_time, compile_time=m.compile_time,
                      n_steps=m.n_steps, nfev=m.nfev, notes=tuple(notes + list(m.notes)),
                      error_estimate=m.error_estimate, periodicity=m.periodicity,
                      scene_extrema=scene_extrema)


# -------------------------------------------------------------------- batch
def _batch_worker(job):
    """One model of :func:`simulate_batch` → (result, its warnings' messages and classes),
    the warnings brought back from a worker process (they were lost there)."""
    params, revolutions, method, kwargs = job
    with warnings.catch_warnings(record=True, action="always") as caught:
        result = simulate_params(params, revolutions, method, **kwargs)
    return result, [(w.message, w.category) for w in caught]


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
        params_list = all_presets()
    jobs = [(p, revolutions, method, kwargs) for p in params_list]
    processes = processes or os.cpu_count() or 1
    if processes == 1 or len(jobs) == 1:
        done = [_batch_worker(j) for j in jobs]
    else:
        with ProcessPoolExecutor(max_workers=min(processes, len(jobs))) as pool:
            done = list(pool.map(_batch_worker, jobs))
    for message, category in (w for _, caught in done for w in caught):
        warnings.warn(message, category, stacklevel=2)
    return [result for result, _ in done]
