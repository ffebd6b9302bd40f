"""Simulate a scene over whole revolutions: :func:`simulate_scene` → :class:`SceneMotion`.

The drive's part turns with the rigid motion at crank speed Ω from crank
rotation ``start_deg`` (t = 0: every part in its rigid position with its rigid
velocity, nothing deformed); R revolutions are integrated and the last one is
tabulated on a uniform grid against the crank angle.  The step rule is the
sley's (``docs/sley.md``): classical RK4 with ``steps_per_period`` steps per
period 2π/|λ|max of the fastest mode of the linearised model over the cycle,
a step cut where a force law changes piece (a clearance gap's edge, a moment's
window; :func:`mechcirc.scene._motion_kernels.rk_run`).

Every result carries two checks:

* ``error_estimate`` — the largest change of any tabulated extremum between the
  run at the step (the one returned) and a run at twice the step (half the
  ``steps_per_period``), relative to that quantity's largest magnitude, compared
  on every k-th output point (:data:`CHECK_POINTS_PER_PERIOD`); the run at twice
  the step covers every revolution and the run at the step the last
  :data:`ESTIMATE_REVOLUTIONS`, from the other's state at their start (for RK4
  the change is about 15× the returned run's error; measured 3.6–16×,
  ``docs/sley.md``); for the scipy methods, its change from the run at rtol of
  the run at rtol/100, which is the one returned;
* ``periodicity`` — the same change from the previous revolution (needs R ≥ 2),
  of the run at twice the step when there is one.

A :class:`~mechcirc.errors.MechcircWarning` is issued (and a note kept) when
either exceeds 1e-3, when fewer steps per period than the default are asked
for, and when a part leaves the range its kinematics are tabulated over.
"""

from __future__ import annotations

import math
import time
import warnings
import weakref
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import _jit
from ..errors import FollowerFlightWarning, MechcircError, SceneAccuracyWarning, SolverError
from ..errors import warn as issue
from ..limits import METHODS, SCIPY_METHODS
from ..sources import brief, data_frame, did_you_mean, real_number, summary_repr
from .files import Scene
from .motion import MotionModel, function_args, motion_model

__all__ = ["SceneMotion", "simulate_scene", "flight", "linear_matrices", "max_rate",
           "ACCURACY_GOAL"]

TWO_PI = 2.0 * math.pi
#: RK4 steps per period of the fastest mode without an error estimate (and the second try
#: of the default with one).
DEFAULT_STEPS_PER_PERIOD = 50
#: The default's first try with the error estimate on (kept if its estimate is within the
#: accuracy goal, else the run at twice as many steps is returned).
AUTO_STEPS_PER_PERIOD = 25
#: The same two for ``method="rk8"`` (the 8th-order steps are three times as long).
RK8_STEPS_PER_PERIOD = (8, 16)
DEFAULT_POINTS = 7200
DEFAULT_REVOLUTIONS = 5
MAX_STEPS_PER_REV = 20_000_000
#: Relative error estimate / periodicity above which a result is flagged.
ACCURACY_GOAL = 1e-3


@dataclass(frozen=True)
class SceneMotion:
    """One tabulated revolution of a scene's motion (plain data).

    Attributes
    ----------
    name, source : str
    omega : float
        Crank shaft speed Ω [rad/s].
    crank_angle : ndarray
        Crank rotation from the pose, mod 2π [rad], ascending.
    values : dict[str, ndarray]
        ``BODY.acceleration`` [rad/s²], ``ELEMENT.force`` [N or N·m] and
        ``ELEMENT.deformation`` [m or rad], ``drive.moment`` (the generalised
        force the drive supplies), ``MOMENT.moment`` [N·m], and the aliases.
    extrema : dict[str, (float, float)]
    revolution : int
    error_estimate, periodicity : float or None
        Relative (see the module docstring); None when not computed.
    n_steps, nfev : int
        Steps and right-hand-side evaluations of every run of the call (the error
        estimate's included).
    wall_time : float
        Wall time of the integration [s], every run of the call.
    method, backend : str
    notes : tuple of str
    """

    __repr__ = summary_repr

    name: str
    source: str
    omega: float
    crank_angle: np.ndarray
    values: dict
    extrema: dict
    revolution: int
    error_estimate: float | None
    periodicity: float | None
    n_steps: int
    nfev: int
    wall_time: float
    method: str
    backend: str
    steps_per_revolution: int
    notes: tuple = field(default=())
    #: Time [s] of each tabulated point (the crank-angle order) and the state there,
    #: ``[q_1..q_n, q̇_1..q̇_n]`` (each free part's coordinate, :attr:`MotionModel.coordinate`).
    time: np.ndarray | None = None
    states: np.ndarray | None = None
    #: numba compilation or cache load of the first call in a process [s], else 0.
    compile_time: float = 0.0
    #: The unit of each output of ``values`` (:func:`output_units`); a required keyword.
    units: dict = field(kw_only=True)

    def summary(self) -> dict:
        """Plain-data summary for JSON."""
        return {"scene": self.name, "source": self.source, "omega": self.omega,
                "revolution": self.revolution, "method": self.method, "backend": self.backend,
                "steps_per_revolution": self.steps_per_revolution,
                "extrema": {k: list(v) for k, v in self.extrema.items()},
                "error_estimate": self.error_estimate, "periodicity": self.periodicity,
                "n_steps": self.n_steps, "nfev": self.nfev, "wall_time_s": self.wall_time,
                "compile_time_s": self.compile_time, "notes": list(self.notes)}

    def columns(self) -> dict:
        """Output arrays by name, crank angle in degrees first (for CSV)."""
        return {"crank_angle_deg": np.degrees(self.crank_angle), **self.values}

    def to_dataframe(self):
        """One row per tabulated point, the columns of :meth:`columns` (``crank_angle_deg``
        [deg], then every output); ``attrs["units"]`` the unit of each column
        (:func:`output_units`)."""
        return data_frame(self.columns(), {"crank_angle_deg": "deg",
                                           **{k: self.units.get(k, "") for k in self.values}})


def output_units(scene: Scene, names) -> dict[str, str]:
    """The unit of each output name of a scene's motion, an alias as its target's.

    ``BODY.acceleration`` rad/s² (a block's ``BODY.travel.acceleration`` and a point's
    ``P.acceleration``, ``_x``, ``_y`` m/s²); ``ELEMENT.force`` N (N·m for a torsion rod)
    and ``ELEMENT.deformation`` m (rad); ``MOMENT.moment`` N·m; ``drive.moment`` N·m on a
    link, N at a point.

    Parameters
    ----------
    scene : Scene
    names : iterable of str

    Returns
    -------
    dict of str to str
    """
    aliases = dict(getattr(scene.simulate, "aliases", None) or {})
    torsions, out = {t.name for t in scene.torsions}, {}
    for name in names:
        owner, _, what = aliases.get(name, name).rpartition(".")
        if what == "moment":
            out[name] = "N" if owner == "drive" and scene.drive.link is None else "N·m"
        elif what in ("force", "deformation"):
            out[name] = {"force": "N", "deformation": "m"}[what] if owner not in torsions \
                else {"force": "N·m", "deformation": "rad"}[what]
        else:               # an acceleration: of a point or a block's travel, or a body's turn
            linear = owner in scene.linkage.pose or owner.endswith(".travel")
            out[name] = "m/s²" if linear else "rad/s²"
    return out


NO_NUMBA_NOTE = ("numba is not importable (install the 'fast' extra: pip install "
                 "'mechcirc[fast]'); ran the same RK4 as pure Python, about 100x slower")
COLD_NOTE = ("numba's cache does not hold the compiled kernels yet: ran the same RK4 as "
             "Python while a background process compiles them for the next run")
_WARM = False
# Compiles the kernels a default run and a scipy method take into numba's disk cache
# (a short, coarse run of each: the compiled code does not depend on the step).
_WARM_STATEMENT = ("import mechcirc._jit as j; j.COMPILED = True; "
                   "from mechcirc.sley.simulation import simulate; "
                   "simulate(revolutions=1, error_estimate=False, steps_per_period=5); "
                   "simulate(revolutions=1, method='DOP853', error_estimate=False, rtol=1e-3)")


def kernels_for(method, *, long=False):
    """(kernel module, backend name): compiled for ``"rk4"`` (and the scipy methods' right-hand
    side) when numba is importable, else the pure-Python copy.

    With :data:`mechcirc._jit.COMPILED` None (default) the compiled kernels are taken only
    once numba's disk cache holds them; until then the Python copy runs and a detached
    process compiles them (:func:`mechcirc._jit.warm_in_background`).  True compiles them
    here if need be; False always gives the Python copy.  ``long``: a run far longer as
    Python than compiling (a crosscheck's records, 650,000 steps for the heald scene: 268 s
    of CPU as Python, 18 s with the compile here first), given the compiled kernels unless
    ``COMPILED`` is False.
    """
    from . import _motion_kernels as k

    kernels = (k.rk_run, k.output_pass, k.eval_many, k.point_samples,
               *((k.rhs,) if method in SCIPY_METHODS else ()))
    if method != "rk4-python" and k.HAVE_NUMBA:
        if long and _jit.COMPILED is not False:
            _jit.in_cache(*kernels)         # those cached loaded with their callees first
            return k, "numba"
        if _jit.use(_WARM_STATEMENT, *kernels):
            return k, "numba"
    return k.load_python(), "python"


def _warm_up(model, kern) -> float:
    """Compile (or load from numba's cache) the kernels once per process; the time it took."""
    global _WARM
    if _WARM:
        return 0.0
    t0 = time.perf_counter()
    y = model.rigid_state(0.0)
    args = model.kernel_args(0.0, 1e300)
    for method in ("rk4", "rk8"):           # (one compiled signature for both)
        kern.rk_run(y, 0.0, 1e-9, 2, 0.0, 1e-9, np.empty((1, y.size)), np.empty(1), *args,
                    model.naux(), *kern.tableau(method))
    _outputs(model, kern, 0.0, (0.0, 0.0), np.zeros(1), np.array([y]))
    _output_extrema(model, kern, 0.0, (0.0, 0.0), np.zeros(1), np.array([y]))
    one = np.zeros(1)
    kern.point_samples(*function_args(model.arrays, model.arrays["PRIG"][0]), one, one, one,
                       np.empty(1), np.empty(1))
    _WARM = True
    return time.perf_counter() - t0


def linear_matrices(model: MotionModel, theta: float):
    """(M, D, K) of the free coordinates linearised about the rigid motion at θ [rad].

    M is the diagonal of the kinetic energy; K and D are Σ k ∇δ ∇δᵀ, Σ d ∇δ ∇δᵀ
    over the elastic elements with ∇δ by central differences of the kernel's
    deformations (pre-load and velocity-squared terms excluded, as in the circuit).

    Parameters
    ----------
    model : MotionModel
    theta : float

    Returns
    -------
    tuple of 3 ndarray
    """
    from . import _motion_kernels

    kern = kernels_for("rk4")[0]           # compiled when numba is importable
    n = model.n_free
    y0 = model.rigid_state(theta)
    args = model.kernel_args(0.0, 1e300, outputs=True)
    args[0][1] = theta
    nb, ne = len(model.bodies), len(model.elements)

    def deformations(y):
        aux = np.empty(model.naux())
        kern.rhs(0.0, y, *args, np.empty(2 * n), aux,
                 np.zeros((9, max(args[1].shape[0], args[10].shape[0]))))
        return aux[nb + ne:nb + 2 * ne].copy()

    step = 1e-6
    G = np.zeros((ne, n))
    for i, dy in enumerate(step * np.eye(n, y0.size)):     # each coordinate moved by ±step
        G[:, i] = (deformations(y0 + dy) - deformations(y0 - dy)) / (2 * step)
    # Σ k ∇δ ∇δᵀ and Σ d ∇δ ∇δᵀ (columns 0, 1 of EF); element gradients w.r.t. the
    # prescribed part do not enter; loads are linear anyway
    K, D = (G.T @ (args[7][:, j, None] * G) for j in (0, 1))
    a = model.arrays
    # the Python copy's feval, as MotionModel.rigid_state: the compiled one, called from
    # Python, would be compiled apart for these few values (0.24 s of a cold start)
    value = _motion_kernels.load_python().feval
    m = np.zeros(n + 1)
    for f, w in zip(a["MI"], a["MW"]):
        p = a["FI"][f, 1]
        q = y0[p - 1] if p > 0 else value(*function_args(a, a["PRIG"][0]), theta)[0]
        m[p] += w * value(*function_args(a, f), q)[1] ** 2
    return np.diag(m[1:]), D, K


def _last_of(model, name, key, make):
    """``make()``, kept for ``model`` (immutable) under ``name`` while ``key`` stays that of
    the call that made it (only the last: the memory stays bounded): a repeated call (a
    preset's, a study's at the same step) asks again for the step rate, the crank-angle
    order of the same times and the rigid accelerations at the same crank angles."""
    kept = _LAST.setdefault(model, {})
    last = kept.get(name)
    if last is None or last[0] != key:     # (the value returned is this call's own, even
        last = kept[name] = (key, make())  # when another thread keeps another meanwhile)
    return last[1]


#: :func:`_last_of`'s values by model, then by name: (key, value).
_LAST: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def max_rate(model: MotionModel, samples: int = 72) -> float:
    """Largest |λ| of the linearised model over a revolution [1/s] (sets the RK4 step);
    memoised per model (a model is immutable).

    Parameters
    ----------
    model : MotionModel
    samples : int
        Crank angles over the revolution.

    Returns
    -------
    float
    """
    # the fastest mode's |λ| of the linearised motion at each θ
    return _last_of(model, "max_rate", samples, lambda: float(max(
        np.max(np.abs(np.linalg.eigvals(state_matrix(*linear_matrices(model, th)))))
        for th in np.linspace(0.0, model.scene.cycle, samples, endpoint=False))))


def state_matrix(M, D, K):
    """A of ż = A z, z = (x, ẋ), for M ẍ + D ẋ + K x = 0 with M diagonal:
    [[0, I], [−M⁻¹K, −M⁻¹D]] (the sley's :meth:`~mechcirc.sley.linear.LinearModel.state_matrix`
    too)."""
    n = M.shape[0]
    inv, A = 1.0 / np.diag(M)[:, None], np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -inv * K
    A[n:, n:] = -inv * D
    return A


def simulate_scene(scene: Scene, *, omega: float | None = None, revolutions: int | None = None,
                   start_deg: float | None = None, steps_per_period: float | None = None,
                   points: int | None = None, method: str = "rk4", error_estimate: bool = True,
                   model: MotionModel | None = None, rtol: float | None = None,
                   revolution: int | None = None, omega_ripple: tuple | None = None,
                   progress: Callable[[int, int], None] | None = None,
                   exact_rigid: bool = True, point_accelerations: bool = True) -> SceneMotion:
    """Simulate ``scene`` over ``revolutions`` turns of the crank and tabulate the last.

    Parameters default to the scene's ``[simulate]`` table, then Ω from its crank, 5
    revolutions, start 0°, 7200 points, RK4 steps per period of the fastest mode: 25 if
    the estimate (run at 12.5) is within :data:`ACCURACY_GOAL`, else 50; 50 without it.
    ``omega_ripple`` = (a, k) (default the file's ``omega_ripple = {amplitude = a,
    harmonic = k}``, else none): the crank speed Ω (1 + a cos(k Ω t)) (:func:`crank_angle`).

    Parameters
    ----------
    scene : Scene
    omega, revolutions, start_deg, steps_per_period, points : optional
        Crank speed [rad/s], revolutions, start angle [deg], RK4 steps per period of
        the fastest mode, output points per revolution (defaults above).
    method, rtol : optional
        ``"rk4"`` (numba when importable), ``"rk4-python"``, ``"rk8"`` (DOP853's 8th-order
        formula at a fixed step: 8, else 16 steps per period), or scipy's ``"DOP853"``,
        ``"RK45"``, ``"LSODA"`` at ``rtol`` (default 1e-10; in the deviations from the
        rigid motion, so that the tolerance applies to the deformations).
    error_estimate : bool
        Also a run at twice the step, and the change of the extrema (module docstring).
    model : MotionModel, optional
        A :func:`~mechcirc.scene.motion.motion_model` of ``scene`` made before (reused).
    revolution, omega_ripple : optional
        The revolution tabulated (1 … R: the integration stops there); the ripple (above).
    progress : callable, optional
        ``progress(done, total)`` as the integration advances.
    exact_rigid, point_accelerations : bool
        Refine the extrema of the ``BODY.rigid_acceleration`` aliases to the exact extreme
        (Brent on the tables), and tabulate every moving ``POINT.acceleration`` (``_x``,
        ``_y``); False: the samples' extrema, and no points (the sley's choice for both).

    Returns
    -------
    SceneMotion
        The tabulated revolution: crank angle, named outputs, their extrema.

    Raises
    ------
    MechcircError, GeometryError, SolverError
        A bad option (named, :func:`check_run`: e.g. a ``steps_per_period`` given with a
        scipy method, or a count that is not an integer); a mechanism that cannot turn a
        revolution; a run that diverged or needs too many steps.

    Warns
    -----
    SceneAccuracyWarning, FollowerFlightWarning
        An estimate or periodicity above :data:`ACCURACY_GOAL` (also in the notes); a cam
        follower that flew across the whole gap of its contact (:func:`flight`).
    """
    o = _options(scene, omega, revolutions, start_deg, steps_per_period, points, method,
                 rtol, revolution, omega_ripple, exact_rigid, point_accelerations)
    model, ripple = _model_at(scene, o, model)
    kern, backend, notes, compile_time = _ready_kernels(method, model)
    ctx = (scene, o, model, kern, math.radians(o.start_deg), ripple, progress)
    if method in SCIPY_METHODS:
        return _simulate_scipy(ctx, error_estimate, notes, compile_time)
    return _simulate_rk4(ctx, backend, error_estimate, notes, compile_time)


def flight(scene, sm, warn: bool = False) -> str:
    """Did the follower fly across the whole gap the model gives it?

    The contact's law has its far flank 2 × (stroke + preload/spring) from the cam
    (:func:`~mechcirc.scene.cam.open_contact_rows`); a follower that gets there hits
    it, and the motion past that is not a free flight.

    Parameters
    ----------
    scene : Scene
        A scene whose ``[cam]`` has a contact that can open.
    sm : SceneMotion
        Its :func:`~mechcirc.scene.simulate_scene` result.
    warn : bool
        Also issue the message as a :class:`~mechcirc.errors.FollowerFlightWarning`, at the
        caller's line (:func:`simulate_scene` does).

    Returns
    -------
    str
        The message (the largest departure from the cam, the gap, the cam angle), or
        "" when the follower stayed within the gap.
    """
    from .cam import contact_geometry

    el, _, _, _, half = contact_geometry(scene)
    e = sm.values[f"{el.name}.deformation"]
    k = int(np.argmax(e))
    if not e[k] > half:
        return ""
    unit, L = scene.units or "m", scene.length_scale
    msg = (f"{scene.source}: the follower left the cam by {(e[k] + half) / L:.6g} {unit} at "
           f"cam angle {math.degrees(sm.crank_angle[k]):.2f}°, more than the model's gap "
           f"{2 * half / L:.6g} {unit} (2 × (stroke + preload/spring)): it hit the contact's "
           "far flank, so the motion from there on is not the follower's free flight; lower "
           "the speed or raise the spring or its preload")
    if warn:
        issue(msg, FollowerFlightWarning)
    return msg


def _model_at(scene, o, model):
    """The motion model at the run's Ω (``model`` when it is one) and the crank-speed
    ripple (A, ν) [rad/s] of the options ``o``."""
    if model is None or (o.omega is not None and model.omega != float(o.omega)):
        model = motion_model(scene, o.omega)
    ripple = (0.0, 0.0) if o.ripple is None or o.ripple[0] == 0.0 else \
        (float(o.ripple[0]) * model.omega, float(o.ripple[1]) * model.omega)
    return model, ripple


def _ready_kernels(method, model):
    """The kernels of ``method``, their backend, the notes on it (numba missing, or not
    compiled yet) and the time spent compiling them for ``model`` [s]."""
    from . import _motion_kernels as k

    kern, backend = kernels_for(method)
    notes = [] if backend == "numba" or method == "rk4-python" or _jit.COMPILED is False else \
        [COLD_NOTE if k.HAVE_NUMBA else NO_NUMBA_NOTE]
    return kern, backend, notes, (_warm_up(model, kern) if backend == "numba" else 0.0)


@dataclass(frozen=True)
class _Options:
    """The checked options of one :func:`simulate_scene` call (file defaults applied)."""

    omega: float | None
    revolutions: int
    start_deg: float
    spp: float | None
    npts: int
    ripple: tuple | None
    method: str
    rtol: float | None
    exact_rigid: bool = True
    point_accelerations: bool = True


def _options(scene, omega, revolutions, start_deg, spp, npts, method, rtol, revolution,
             ripple, exact_rigid=True, point_accelerations=True) -> _Options:
    """Options from the call, else the scene's ``[simulate]`` table, else the defaults;
    each checked (a :class:`MechcircError` names the bad one)."""
    cfg = scene.simulate

    def pick(v, k, d):          # the call's value, else the file's, else the default
        v = getattr(cfg, k, None) if v is None else v
        return d if v is None else v

    omega = pick(omega, "omega", None)
    revolutions = pick(revolutions, "revolutions", DEFAULT_REVOLUTIONS)
    start_deg = float(pick(start_deg, "start_deg", 0.0))
    # the file's steps_per_period is a default of the fixed-step methods, not the scipy ones'
    spp = spp if method in SCIPY_METHODS else pick(spp, "steps_per_period", None)
    npts = pick(npts, "points", DEFAULT_POINTS)
    ripple = pick(ripple, "omega_ripple", None)
    if ripple is not None:
        amp_rel, harmonic = ripple
        if not (math.isfinite(amp_rel) and 0.0 <= amp_rel < 1.0):
            raise MechcircError(f"omega_ripple amplitude must be in [0, 1) (relative to Ω), "
                                f"got {amp_rel!r}")
        if isinstance(harmonic, bool) or int(harmonic) != harmonic or not harmonic >= 1:
            raise MechcircError(f"omega_ripple harmonic must be a whole number >= 1, got "
                                f"{harmonic!r}")
    check_run(method, revolutions, revolution, npts, spp, rtol)
    if method in SCIPY_METHODS:
        rtol = 1e-10 if rtol is None else float(rtol)
    # the run stops at the tabulated revolution: later ones cannot change it
    return _Options(omega, int(revolution or revolutions), start_deg,
                    None if spp is None else float(spp), int(npts), ripple, method, rtol,
                    bool(exact_rigid), bool(point_accelerations))


def check_run(method, revolutions, revolution, points, spp, rtol, error=MechcircError,
              points_name="points") -> None:
    """The run options of :func:`simulate_scene` checked, and those of the sley's
    :func:`~mechcirc.sley.simulate_params` (its ``error`` class, its ``points_name``):
    one set of rules, the bad option named as its caller's user wrote it."""
    if method not in METHODS:
        raise error(f"unknown method {method!r}; choose one of {', '.join(METHODS)}"
                    f"{did_you_mean(str(method), METHODS)}")
    if not _whole(revolutions, 1):
        raise error(f"revolutions must be an integer ≥ 1, got {revolutions!r}")
    if revolution is not None and not (_whole(revolution, 1) and revolution <= revolutions):
        raise error(f"revolution must be an integer in 1..{revolutions}, got {revolution!r}")
    if not _whole(points, 16):
        raise error(f"{points_name} must be an integer ≥ 16, got {points!r}")
    if method in SCIPY_METHODS:
        if spp is not None:
            raise error(f"steps_per_period applies to rk4 and rk8, not {method}; use rtol")
        if rtol is not None and not (real_number(rtol) and 1e-14 <= rtol < 1):
            raise error(f"rtol must be in [1e-14, 1), got {brief(rtol)}")
    elif rtol is not None:
        raise error(f"rtol applies to the scipy methods, not {method}; use steps_per_period")
    elif spp is not None and not (real_number(spp) and spp >= 1):
        raise error(f"steps_per_period must be ≥ 1, got {brief(spp)}")


def _whole(value, least) -> bool:
    """``value`` is an integer (a numpy one too, not a bool) ≥ ``least``."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool) \
        and value >= least


def _simulate_scipy(ctx, error_estimate, notes, compile_time):
    """:func:`simulate_scene` with a scipy method: the run at rtol/100 returned, its change
    from the run at rtol the error estimate (about the error of the run at rtol, ~100×
    the returned one's, so it bounds it); about 2.5× the cost of one run."""
    scene, o, model, kern, theta_s, ripple, progress = ctx
    rtol, method = o.rtol, o.method
    ref_tol = max(rtol / 100, SCIPY_RTOL_FLOOR)
    if not error_estimate or ref_tol > rtol / 10:
        ref_tol = rtol
    ts, ys, prev, wall, bad, n_steps, nfev = _run_scipy(model, kern, theta_s, o.revolutions,
                                                       o.npts, method, ref_tol, progress, ripple)
    coarse, text = None, f"{method}, rtol {rtol:g}"
    if ref_tol < rtol:
        coarse = _run_scipy(model, kern, theta_s, o.revolutions, o.npts, method, rtol, None,
                            ripple)
        n_steps, nfev = n_steps + coarse[5], nfev + coarse[6]
        text = (f"{method}, rtol {ref_tol:g} (error estimate: its change from the run at "
                f"rtol {rtol:g})")
    elif error_estimate:
        notes.append(f"no error estimate: rtol {rtol:g} leaves no tighter reference "
                     f"(solve_ivp's floor is {SCIPY_RTOL_FLOOR:g})")
    return _finish(ctx, (ts, ys, prev, wall, bad), None if coarse is None else coarse[:5],
                   (n_steps, nfev, "scipy", 0, compile_time), notes + [text], [])


def _simulate_rk4(ctx, backend, error_estimate, notes, compile_time):
    """:func:`simulate_scene` with RK4 (or RK8): the run at ``steps_per_period`` is returned;
    the error estimate is its change from a run at half as many steps (twice the step).

    For RK4 in its asymptotic regime that change is ~15× the returned run's error, so it
    bounds it with margin (the steps are cut at the force laws' kinks, so the order holds
    through impacts; measured: ``benchmarks/calib_sley_estimate.py``, ``docs/sley.md``);
    it costs half a run more.  With no ``steps_per_period`` (estimate on) the step is
    chosen for the accuracy goal: the run at :data:`AUTO_STEPS_PER_PERIOD` is returned
    when its estimate is at most :data:`ACCURACY_GOAL`, else the run at twice as many
    steps, with its change from the first as the estimate.
    """
    scene, o, model, kern, theta_s, ripple, progress = ctx
    rule = _step_rule(scene, o, model, error_estimate)
    tableau = kern.tableau(o.method)

    def run(per_rev, prog=None, last=1, start=None):
        return _run(model, kern, theta_s, ripple, per_rev, o.revolutions, o.npts, prog,
                    tableau, (last, rule.stride), start)

    spp, main, other = _first_runs(run, rule, progress, notes, error_estimate)
    start = other[7] if isinstance(other, tuple) else None
    first = start[0] if start else 0
    n_steps, nfev, wall = main[6] * (o.revolutions - first), main[5], 0.0
    if isinstance(other, tuple):
        n_steps, nfev, wall = n_steps + other[6] * o.revolutions, nfev + other[5], other[3]
    crank, order, sub = _crank_order(scene, model, theta_s, ripple, main[0], rule.stride)
    main = _in_order(main, order)       # once: the outputs and the result take this order
    out, other_ext, periodicity = _estimate_run_extrema(model, kern, theta_s, ripple, main,
                                                        other)
    check = _extrema(out, sub)          # the checks' samples of this run, as _finish's
    if rule.auto and spp == rule.spp:
        est = None if other_ext is None else _rel_change(check, other_ext)
        if (est is None or est > ACCURACY_GOAL) and \
                rule.period * rule.rate * 2 * spp / TWO_PI <= MAX_STEPS_PER_REV:
            # not good enough: twice as many steps (beyond the limit: keep it, warned), from
            # the same state as the run at spp
            notes.append(_rerun_note(spp, est))
            other, other_ext = main, check
            wall += main[3]
            spp, out, check = 2 * spp, None, None
            main = _in_order(run(_steps_per_cycle(rule, spp), start=start), order)
            n_steps, nfev = n_steps + main[6] * (o.revolutions - first), nfev + main[5]
    if other == "diverged":
        rule.warn.append(f"the error estimate's run at {spp / 2:g} steps per period diverged: "
                         "no estimate; raise steps_per_period")
    notes.append(_step_note(rule.period, main[6], spp, rule.rate, error_estimate, o.method))
    main = (*main[:3], wall + main[3], *main[4:])
    return _finish(ctx, main, other, (n_steps, nfev, backend, main[6], compile_time), notes,
                   rule.warn, out=out, other_extrema=other_ext, tab=(crank, None, sub),
                   periodicity=periodicity, check=check)


@dataclass
class _StepRule:
    """The fixed-step rule of one RK run (:func:`_step_rule`)."""

    period: float           # one revolution, or the cycle of geared cranks [s]
    rate: float             # |λ|max [1/s]
    spp: float              # steps per period of the fastest mode of the first run
    auto: bool              # the step chosen for the accuracy goal (first try, then twice)
    stride: int             # the checks compare the extrema on every stride-th output point
    warn: list


#: The error estimate's run at twice the step covers the last this many revolutions, from
#: the returned run's state at their start: the error a run commits before them has been
#: damped by the time the tabulated revolution is reached (a motion that keeps it is not
#: periodic, and the periodicity check says so).
ESTIMATE_REVOLUTIONS = 2
#: The error estimate and the periodicity compare the extrema of two runs on the same
#: output points, at least this many per period of the fastest mode (every k-th point of
#: a finer grid: both runs sampled alike, so the change measured is the runs' change).
CHECK_POINTS_PER_PERIOD = 40


def _step_rule(scene, o, model, error_estimate) -> _StepRule:
    """The step rule of :func:`_simulate_rk4` for the options ``o``; too few steps per period
    asked for is a warning (in the rule's ``warn``)."""
    period = scene.cycle / model.omega
    rate = max_rate(model)
    auto = o.spp is None and error_estimate
    first, second = RK8_STEPS_PER_PERIOD if o.method == "rk8" else \
        (AUTO_STEPS_PER_PERIOD, DEFAULT_STEPS_PER_PERIOD)
    spp = o.spp if o.spp is not None else (first if auto else second)
    warn = []
    if o.spp is not None and spp < first:
        warn.append(f"{spp:g} steps per period of the fastest mode, fewer than the "
                    f"{first} the default starts from: expect a larger error")
    per_fast = o.npts * TWO_PI / (rate * period) if rate > 0 else o.npts
    stride = max(1, int(per_fast // CHECK_POINTS_PER_PERIOD))
    return _StepRule(period, rate, spp, auto, stride, warn)


def _first_runs(run, rule, progress, notes, error_estimate):
    """(steps per period, the run returned, the estimate's run): with the estimate, the run
    at half the steps over every revolution (the estimate's run), then the run at the
    step over the last :data:`ESTIMATE_REVOLUTIONS` from the first's state at their start;
    without it, the one run (the estimate's run None).  In the automatic rule a run that
    diverges is repeated at twice as many steps (noted)."""
    for spp in (rule.spp, 2 * rule.spp):
        try:
            return (spp, *_paired_runs(run, _steps_per_cycle(rule, spp), progress, rule.stride,
                                       error_estimate))
        except SolverError:
            if not rule.auto or spp != rule.spp:
                raise
            notes.append(f"the run at {spp:g} steps per period diverged: run at {2 * spp:g}")


def _paired_runs(run, per_rev, progress, stride, error_estimate):
    """(run at ``per_rev`` steps per revolution, the estimate's run at half as many, or
    ``"diverged"``, or None without the estimate) (:func:`_first_runs`).

    The revolutions before the last :data:`ESTIMATE_REVOLUTIONS` only bring the motion
    to its periodic state: the error committed there is damped by the time the tabulated
    revolution is reached (a motion that keeps it is not periodic, which the periodicity
    check reports), so they are integrated once, at the estimate's step."""
    if not error_estimate:
        return run(per_rev, progress), None
    try:
        coarse = run(per_rev // 2, progress, last=stride)
    except SolverError:
        return run(per_rev, progress), "diverged"
    return run(per_rev, start=coarse[7]), coarse


def _in_order(run, order):
    """:func:`_run`'s tuple with its tabulated times and states put in the crank-angle
    ``order`` (:func:`_crank_order`; ``np.take``, several times faster here than
    indexing with the array)."""
    return (np.take(run[0], order), np.take(run[1], order, axis=0), *run[2:])


def _estimate_run_extrema(model, kern, theta_s, ripple, main, other):
    """The outputs of the run ``main`` (its samples in crank-angle order,
    :func:`_in_order`), the extrema of the estimate's run ``other`` on its last
    revolution and its periodicity (the change of its extrema from its previous
    revolution; None with fewer than two), both on the points it was recorded at (None,
    None when it diverged or was not run)."""
    out = _outputs(model, kern, theta_s, ripple, main[0], main[1])
    if not isinstance(other, tuple):
        return out, None, None
    last = _output_extrema(model, kern, theta_s, ripple, *other[:2])
    periodicity = None if other[2] is None else \
        _rel_change(last, _output_extrema(model, kern, theta_s, ripple, *other[2]))
    return out, last, periodicity


def _rerun_note(spp, est):
    """The note that the run at ``spp`` missed the accuracy goal (estimate ``est``)."""
    return (f"the run at {spp:g} steps per period had an error estimate of "
            + ("none (its run at twice the step diverged)" if est is None else f"{est:.2g}")
            + f" > {ACCURACY_GOAL:g}: run again at {2 * spp:g}")


def _step_note(period, per_rev, spp, rate, error_estimate, method="rk4"):
    """The note stating the RK4 (or RK8) step of the returned run."""
    return (f"{'RK8' if method == 'rk8' else 'RK4'} step {period / per_rev:.4g} s ({per_rev} steps per revolution, "
            f"{spp:g} per period of the fastest mode |λ| = {rate:.5g} 1/s)"
            + (" (error estimate: its change from the run at twice the step)"
               if error_estimate else ""))


def _steps_per_cycle(rule, spp):
    """RK4 steps per cycle at ``spp`` steps per period of the fastest mode (``rule``'s
    period and rate; even, so that the estimate's run has half as many; at least 16);
    refused above the limit."""
    need = rule.period * rule.rate * spp / TWO_PI
    if need > MAX_STEPS_PER_REV:
        raise SolverError(f"the stiffest linearised mode (|λ| = {rule.rate:.4g} 1/s) needs "
                          f"{need:.3g} RK4 steps per revolution at steps_per_period={spp:g}, "
                          f"more than the limit {MAX_STEPS_PER_REV:.0e}: lower the stiffest "
                          "rigidity (stiffness), raise the inertias, or use method='LSODA'",
                          status="too-stiff")
    return max(2 * int(math.ceil(need / 2)), 16)


def _extrema(out: dict, sub=None) -> dict:
    """(min, max) of each output, or of its samples at the positions ``sub`` (the outputs
    stacked, so that one reduction of each kind serves them all)."""
    if not out:
        return {}
    rows = out.rows if isinstance(out, _Rows) and len(out) == len(out.rows) else \
        np.stack(list(out.values()))
    if sub is not None:
        rows = np.take(rows, sub, axis=1)
    lo, hi = rows.min(axis=1).tolist(), rows.max(axis=1).tolist()
    return {k: (a, b) for k, a, b in zip(out, lo, hi)}


def _finish(ctx, main, other, counts, notes, warn, out=None, other_extrema=None, tab=None,
            periodicity=None, check=None):
    """Outputs, extrema, the checks and the warnings of one run → :class:`SceneMotion`.

    ``ctx`` is the call's (scene, options, model, kernels, start angle, ripple, progress),
    ``main`` the run (:func:`_run`'s tuple), ``other`` the estimate's (or None, or
    ``"diverged"``), ``counts`` = (steps, evaluations, backend, steps per revolution,
    compile time); ``out``, ``other_extrema``: this run's outputs
    (in the order of ``tab``) and the other run's extrema when already evaluated,
    ``periodicity`` when measured on the estimate's run (else from ``main``'s previous
    revolution); ``tab`` (:func:`_crank_order`; its order None when ``main`` is in it
    already, :func:`_in_order`): the checks compare the extrema on the
    points the other runs were recorded at (``check``: ``out``'s extrema there, when
    already taken)."""
    scene, o, model, kern, theta_s, ripple, _ = ctx
    ts, ys, prev, wall, bad = main[:5]
    n_steps, nfev, backend, per_rev, compile_time = counts
    crank, order, sub = tab or _crank_order(scene, model, theta_s, ripple, ts)
    if order is not None:                       # None: ``main`` is in that order already
        ts, ys = np.take(ts, order), np.take(ys, order, axis=0)
    out = _outputs(model, kern, theta_s, ripple, ts, ys) if out is None else out
    extrema = _extrema(out)
    if check is None:
        check = extrema if sub is None else _extrema(out, sub)
    est = None
    if periodicity is None and prev is not None:
        periodicity = _rel_change(check, _output_extrema(model, kern, theta_s, ripple, *prev))
    if other is not None and not isinstance(other, str):     # "diverged": no estimate
        if other_extrema is None:
            other_extrema = _output_extrema(model, kern, theta_s, ripple, other[0], other[1])
        est = _rel_change(check, other_extrema)
        bad = bad or other[4]
    values = dict(out)
    _add_points_and_aliases(scene, model, theta_s, ripple, crank, ts, ys, values, extrema,
                            (o.exact_rigid, o.point_accelerations))
    warn = warn + _check_warnings(bad, est, periodicity)
    for w in warn:
        warnings.warn(f"{scene.source}: {w}", SceneAccuracyWarning, stacklevel=3)
    result = SceneMotion(scene.name, scene.source, model.omega, crank, values, extrema,
                         o.revolutions, est, periodicity, n_steps, nfev, wall, o.method, backend,
                         per_rev, tuple(notes + [f"warning: {w}" for w in warn]), ts, ys,
                         compile_time, units=output_units(scene, values))
    if getattr(scene.linkage, "contact", ""):          # a cam follower that can jump
        flight(scene, result, warn=True)               # (at the caller's line)
    return result


def _crank_order(scene, model, theta_s, ripple, ts, stride=1):
    """(ascending crank angle mod the cycle, the order of the samples at times ``ts`` that
    gives it, and the positions in that order of every ``stride``-th sample in time, or
    None for every sample); kept for the same times (``%`` on them is most of its cost)."""
    crank, order, sub = _last_of(
        model, "crank_order", (scene.cycle, theta_s, ripple, stride, ts.tobytes()),
        lambda: _new_crank_order(scene.cycle, model.omega, theta_s, ripple, ts, stride))
    return crank.copy(), order, sub     # (the result's array: the kept one stays as it is)


def _new_crank_order(cycle, omega, theta_s, ripple, ts, stride):
    """:func:`_crank_order`, computed."""
    crank = crank_angle(omega, theta_s, ripple, ts)[0] % cycle
    n = crank.size
    wrap = np.flatnonzero(crank[1:] < crank[:-1])
    if wrap.size != 1:
        order = np.argsort(crank, kind="stable")
        return crank[order], order, (np.flatnonzero(order % stride == 0) if stride > 1
                                     else None)
    k = int(wrap[0]) + 1                # one wrap: the order is a rotation by k
    order = np.concatenate((np.arange(k, n), np.arange(k)))
    # the positions of the samples k + p (p < n − k) and p − (n − k) that are multiples
    sub = None if stride == 1 else np.concatenate((
        np.arange(-(-k // stride) * stride, n, stride) - k, np.arange(0, k, stride) + (n - k)))
    return np.concatenate((crank[k:], crank[:k])), order, sub


def _add_points_and_aliases(scene, model, theta_s, ripple, crank, ts, ys, values, extrema,
                            what=(True, True)):
    """The points' accelerations (unless ``what[1]`` is False and no slider has a stroke to
    check) and the ``[simulate.aliases]`` added to ``values`` and ``extrema`` (in place;
    rigid accelerations' extrema refined when ``what[0]``); every slider's stroke checked
    on the samples."""
    exact_rigid, point_acc = what
    if point_acc or any(s.stroke for s in scene.linkage.sliders):
        positions: dict = {}
        for k, v in _point_accelerations(model, theta_s, ripple, ts, ys, values,
                                         positions).items():
            if point_acc:
                values[k] = v
                extrema[k] = (float(v.min()), float(v.max()))
        check_strokes(scene, crank, positions)
    for alias, target in dict(getattr(scene.simulate, "aliases", None) or {}).items():
        if target.endswith(".rigid_acceleration"):
            body = target.rsplit(".", 1)[0]
            values[alias], extrema[alias] = _rigid_acceleration(model, body, crank,
                                                                ripple, ts, exact_rigid)
        elif target in values:
            values[alias], extrema[alias] = values[target], extrema[target]
        else:
            raise MechcircError(f"{scene.source}: alias {alias!r} names {target!r}, which is "
                                f"not an output{did_you_mean(target, values)} (outputs: "
                                f"{', '.join(values)})")


def _check_warnings(bad, est, periodicity) -> list:
    """The accuracy warnings of a run: a part out of its tables' range, an error estimate or
    a periodicity above :data:`ACCURACY_GOAL`."""
    warn = []
    if bad:
        warn.append("a part left the range its kinematics are tabulated over (the values "
                    "there are extrapolated)")
    if est is not None and est > ACCURACY_GOAL:
        warn.append(f"error estimate {est:.2g} (change of the extrema at twice the step) > "
                    f"{ACCURACY_GOAL:g}: raise steps_per_period")
    if periodicity is not None and periodicity > ACCURACY_GOAL:
        warn.append(f"not yet periodic: the extrema changed by {periodicity:.2g} (relative) "
                    f"from the previous revolution > {ACCURACY_GOAL:g}: raise revolutions")
    return warn


#: Smallest rtol solve_ivp honours (100 × machine epsilon).
SCIPY_RTOL_FLOOR = 100 * float(np.finfo(float).eps)


def _run_scipy(model, kern, theta_s, revolutions, npts, method, rtol, progress, ripple):
    """R revolutions by ``solve_ivp`` on the kernel's right-hand side; same outputs as
    :func:`_run` plus (steps, evaluations).

    A part whose rigid motion is a line in θ (a crank: q = θ) is integrated in its
    deviation from it (its twist), so that the tolerance bounds the twist and not the
    growing crank angle; the others in their own (bounded) coordinates.  Only the
    lines are subtracted: a tabulated rigid motion is C² only at its nodes, which
    would make the deviation equation rough for an adaptive step.
    """
    from scipy.integrate import solve_ivp

    n = model.n_free
    omega = model.omega
    f, rigid, lines, bad = _deviation_rhs(model, kern, theta_s, ripple)
    y0 = model.rigid_state(theta_s, omega + ripple[0])
    qs = np.full(n, 1e-2)                       # a bounded rotation (a rocker, the sley)
    qs[[i for i, _, _ in lines]] = 1e-4         # a twist
    scale = np.concatenate([qs, 0.1 * np.maximum(np.abs(y0[n:]), omega)])
    period = model.scene.cycle / omega
    e = y0 - rigid(0.0)[0]
    n_steps = nfev = 0
    out, prev = None, None
    t0 = time.perf_counter()
    for r in range(revolutions):
        keep = r >= revolutions - 2
        sol = solve_ivp(f, (r * period, (r + 1) * period), e, method=method, rtol=rtol,
                        atol=rtol * scale, dense_output=keep)
        if sol.status != 0:
            raise SolverError(f"solve_ivp({method}) failed in revolution {r + 1}: "
                              f"{sol.message}", status=sol.status)
        n_steps += len(sol.t) - 1
        nfev += sol.nfev
        if keep:
            ts = (r * period) + np.arange(npts) * (period / npts)
            ys = sol.sol(ts).T + rigid(ts)[0]
            prev, out = out, (ts, np.ascontiguousarray(ys))     # the last two revolutions
        e = sol.y[:, -1].copy()
        if progress is not None:
            progress(r + 1, revolutions)
    return out[0], out[1], prev, time.perf_counter() - t0, bad[0] > 0, n_steps, nfev


def _deviation_rhs(model, kern, theta_s, ripple):
    """(f, rigid, lines, bad) for :func:`_run_scipy`: f(t, e) the derivative of the deviation
    e = y − rigid(t)[0] from the subtracted motion (the lines of the parts whose rigid motion
    is one: q = c0 + c1 θ), ``lines`` those parts, ``bad[0]`` the out-of-range flag seen."""
    n = model.n_free
    a = model.arrays
    omega = model.omega
    args = model.kernel_args(theta_s, 1e300, ripple=ripple)
    aux = np.empty(model.naux())
    work = np.zeros((9, max(a["FI"].shape[0], a["PRIG"].shape[0])))
    rhs = kern.rhs
    lines = [(i, float(a["FF"][r, 0]), float(a["FF"][r, 1]))
             for i, r in enumerate(a["PRIG"][1:]) if a["FI"][r, 0] == 2]
    bad = [0.0]

    def rigid(t):
        """The subtracted motion (lines only) at t, a row at each of an array of times,
        and its derivative (the same at every t)."""
        th = theta_s + omega * t
        y, yd = np.zeros(getattr(t, "shape", ()) + (2 * n,)), np.zeros(2 * n)
        for i, c0, c1 in lines:
            y[..., i], y[..., n + i] = c0 + c1 * th, c1 * omega
            yd[i] = c1 * omega
        return y, yd

    def f(t, e):
        yr, ydr = rigid(t)
        dy = np.empty(2 * n)
        rhs(t, e + yr, *args, dy, aux, work)
        bad[0] = max(bad[0], aux[-1])
        return dy - ydr

    return f, rigid, lines, bad


def _run(model, kern, theta_s, ripple, per_rev, revolutions, npts, progress, tableau=None,
         strides=(1, 1), start=None):
    """R revolutions of RK4 (or the explicit ``tableau``, :func:`~mechcirc.scene._motion_kernels.tableau`) at ``per_rev``
    steps each: (times and states tabulated on the last revolution, the previous one's
    (times, states) or None (None from ``start``: the estimate's run measures the
    periodicity), wall time, out-of-range seen, right-hand-side evaluations,
    ``per_rev``, (r, state) at the start of revolution r = max(R − :data:`ESTIMATE_REVOLUTIONS`,
    0)).  The last revolution is tabulated on every ``strides[0]``-th of the ``npts`` output
    points, the previous one on every ``strides[1]``-th.  ``start`` = (r, state): begin at
    the start of revolution r (0-based) in that state instead of the rigid start."""
    y = model.rigid_state(theta_s, model.omega + ripple[0])
    limit = 1e3 * model.omega * max(1.0, float(np.max(np.abs(y[model.n_free:]))) / model.omega)
    args = model.kernel_args(theta_s, limit, ripple=ripple)
    period = model.scene.cycle / model.omega
    h = period / per_rev
    (n_last, dt_last), (n_prev, dt_prev) = ((-(-npts // k), period / npts * k) for k in strides)
    rec = np.empty((n_last, y.size)), np.empty(n_last)
    # a run from ``start`` (the estimate's state) takes its periodicity from the estimate's run
    prev = (np.empty(n_prev), np.empty((n_prev, y.size))) \
        if revolutions >= 2 and start is None else None
    dummy = np.empty((0, y.size)), np.empty(0)
    bad, nfev = False, 0
    first, keep = 0, max(revolutions - ESTIMATE_REVOLUTIONS, 0)
    if start is not None:
        first, y = start[0], start[1].copy()
    kept = (keep, y.copy())
    t0 = time.perf_counter()
    for r in range(first, revolutions):
        if r == keep:
            kept = (keep, y.copy())
        dt = dt_last
        if r == revolutions - 1:
            ry, rt = rec
        elif r == revolutions - 2 and prev is not None:
            (rt, ry), dt = prev, dt_prev
        else:
            ry, rt = dummy
        t_end, rows, ok, flag, used = kern.rk_run(y, r * period, h, per_rev, r * period,
                                                  dt, ry, rt, *args, model.naux(),
                                                  *(tableau or kern.tableau("rk4")))
        bad, nfev = bad or flag > 0, nfev + used
        if not ok:
            raise SolverError(f"RK4 diverged at t = {t_end:.6g} s (revolution {r + 1}) with "
                              f"step {h:.3g} s: raise steps_per_period", status="diverged")
        if progress is not None:
            progress(r + 1, revolutions)
    return rec[1], rec[0], prev, time.perf_counter() - t0, bad, nfev, per_rev, kept


def _point_accelerations(model, theta_s, ripple, ts, ys, values, positions=None):
    """``POINT.acceleration`` (magnitude) and ``POINT.acceleration_x``/``_y`` [m/s²] of every
    point on a moving part: a = f''(q) q̇² + f'(q) q̈ for its tabulated position f of its
    part's coordinate q (q̈: the acceleration of the part's coordinate body); each point's
    positions f(q) (n, 2) [m] go into ``positions`` when given."""
    if not model.point_fn:
        return {}
    kern = kernels_for("rk4")[0]
    a = model.arrays
    th, w, dw = crank_angle(model.omega, theta_s, ripple, ts)
    coord: dict = {}
    for i in {i for _, _, i in model.point_fn.values()}:     # (q, q̇) of each part, contiguous
        if i == 0:
            q0 = np.empty((ts.size, 3))
            kern.eval_many(*function_args(a, a["PRIG"][0]), np.ascontiguousarray(th), q0)
            coord[0] = (q0[:, 0].copy(), q0[:, 1] * w)
        else:
            coord[i] = (np.ascontiguousarray(ys[:, i - 1]),
                        np.ascontiguousarray(ys[:, model.n_free + i - 1]))
    out = {}
    for p, (fx, fy, i) in model.point_fn.items():
        q, qd = coord[i]
        # the drive part's coordinate is the crank angle θ (θ̈ from the ripple), not the
        # crank body's rotation, which a cam makes swing
        qdd = np.ascontiguousarray(dw if i == 0 else
                                   values[f"{model.coordinate[i]}.acceleration"])
        comp = []
        for f in (fx, fy):
            pos, acc = np.empty(ts.size), np.empty(ts.size)
            kern.point_samples(*function_args(a, f), q, qd, qdd, pos, acc)
            comp.append(acc)
            if positions is not None:
                positions.setdefault(p, []).append(pos)
        out.update({f"{p}.acceleration": np.hypot(comp[0], comp[1]),
                    f"{p}.acceleration_x": comp[0], f"{p}.acceleration_y": comp[1]})
    return out


def check_strokes(scene, crank, positions: dict,
                   what: str = "output sample of the simulation") -> None:
    """Every slider with a ``stroke`` checked at every output sample of the simulated
    (elastic) motion: the located error of the linkage's stroke check at the first
    crank angle where its point is past it (ground points stay at the pose)."""
    from ..kinematics.linkage_solver import check_stroke

    lk, L = scene.linkage, scene.length_scale
    for s in lk.sliders:
        if s.stroke:
            P, G1, G2 = (np.column_stack(positions[p]) / L if p in positions else
                         np.broadcast_to(np.asarray(lk.pose[p], float), (crank.size, 2))
                         for p in (s.point, *s.line))
            check_stroke(lk, s, crank, P, G1, G2, what)


def crank_angle(omega, theta_s, ripple, t):
    """(θ, θ̇, θ̈) of the crank at times ``t``: θ = θs + Ω t + (A/ν) sin(ν t), the speed
    Ω + A cos(ν t) (``ripple`` = (A, ν); A = 0: constant speed).

    ``simulate_scene``'s ``omega_ripple`` = (a, k) is A = a Ω, ν = k Ω with 0 ≤ a < 1 and
    k a whole number ≥ 1, so the crank still turns once per period 2π/Ω and the rigid
    parts follow it with θ̈ = −a k Ω² sin(k Ω t).

    Parameters
    ----------
    omega, theta_s : float
        Mean crank speed Ω [rad/s] and the start angle θs [rad].
    ripple : tuple of 2 float
        (A, ν) [rad/s]; A = 0: none.
    t : array_like
        Times [s].

    Returns
    -------
    tuple of 3 ndarray
    """
    t = np.asarray(t, float)
    amp, nu = ripple
    if amp == 0.0:
        return theta_s + omega * t, np.full_like(t, omega), np.zeros_like(t)
    return (theta_s + omega * t + amp / nu * np.sin(nu * t), omega + amp * np.cos(nu * t),
            -amp * nu * np.sin(nu * t))


def _outputs(model, kern, theta_s, ripple, ts, ys):
    args = model.kernel_args(theta_s, 1e300, outputs=True, ripple=ripple)
    cols = np.empty((model.naux(), ts.size))        # each output a contiguous row
    kern.outputs(np.ascontiguousarray(ts), np.ascontiguousarray(ys), cols, *args)
    names = _aux_names(model)
    rows = _Rows(zip(names, cols))
    rows.rows = cols[:len(names)]
    return rows


class _Rows(dict):
    """Outputs by name, the j-th row j of the 2-D array ``rows`` (:func:`_outputs`), so that
    :func:`_extrema` takes them all in one reduction of each kind."""

    rows: np.ndarray


def _output_extrema(model, kern, theta_s, ripple, ts, ys):
    """``_extrema(_outputs(...))`` of a run, evaluated in the kernel without the tables."""
    args = model.kernel_args(theta_s, 1e300, outputs=True, ripple=ripple)
    ext = np.empty((2, model.naux()))
    kern.output_extrema(np.ascontiguousarray(ts), np.ascontiguousarray(ys), ext, *args)
    return {name: (float(ext[0, j]), float(ext[1, j]))
            for j, name in enumerate(_aux_names(model))}


def _aux_names(model):
    """The names of the kernel's output columns, in order (the last, the out-of-range
    flag, has none)."""
    return ([f"{b}.acceleration" for b in model.bodies]
            + [f"{e}.force" for e in model.elements]
            + [f"{e}.deformation" for e in model.elements] + ["drive.moment"]
            + [f"{m}.moment" for m in model.moments])


def _rel_change(a: dict, b: dict) -> float:
    """Largest change of an extremum between two runs, relative to the largest magnitude of
    that quantity; quantities below 1e-6 of the largest of their kind (acceleration, force,
    …) are rounding noise (a translating body's rotation) and are skipped."""
    kind_scale: dict[str, float] = {}
    for k, (lo, hi) in a.items():
        kind = k.rsplit(".", 1)[-1]
        kind_scale[kind] = max(kind_scale.get(kind, 0.0), abs(lo), abs(hi))
    worst = 0.0
    for k, (lo, hi) in a.items():
        scale = max(abs(lo), abs(hi))
        if scale == 0 or scale < 1e-6 * kind_scale[k.rsplit(".", 1)[-1]]:
            continue
        lo2, hi2 = b[k]
        worst = max(worst, abs(lo - lo2) / scale, abs(hi - hi2) / scale)
    return worst


def _rigid_acceleration(model, body, crank, ripple=(0.0, 0.0), ts=None, refine=True):
    """Angular acceleration of ``body`` in the rigid motion at the crank angles, and its
    exact extrema (grid, then Brent-refined on the tables; without ``refine``, the grid's)."""
    kern = kernels_for("rk4-python")[0]
    a = model.arrays
    if body not in model.body_fn:
        raise MechcircError(f"no body {body!r} (bodies: {', '.join(model.bodies)})")
    g = model.body_fn[body]
    r = a["PRIG"][a["FI"][g, 1]]
    w2 = model.omega ** 2

    def acc(th):
        q, q1, q2, _ = kern.feval(*function_args(a, r), th)
        _, g1, g2, _ = kern.feval(*function_args(a, g), q)
        return (g2 * q1 * q1 + g1 * q2) * w2

    def samples():
        """The acceleration at the samples (at a constant speed, of their crank angles alone)."""
        fast = kernels_for("rk4")[0]
        qv, gv = np.empty((crank.size, 3)), np.empty((crank.size, 3))
        fast.eval_many(*function_args(a, r), np.ascontiguousarray(crank), qv)
        fast.eval_many(*function_args(a, g), np.ascontiguousarray(qv[:, 0]), gv)
        if ripple[0] == 0.0:
            return (gv[:, 2] * qv[:, 1] ** 2 + gv[:, 1] * qv[:, 2]) * w2
        # a varying crank speed: (g'' q'² + g' q'') θ̇² + g' q' θ̈ at the samples' times;
        # its extrema are those of the samples (the output grid sets their accuracy)
        _, w, dw = crank_angle(model.omega, 0.0, ripple, ts)
        return (gv[:, 2] * qv[:, 1] ** 2 + gv[:, 1] * qv[:, 2]) * w ** 2 + gv[:, 1] * qv[:, 1] * dw

    vals = samples() if ripple[0] != 0.0 else \
        _last_of(model, f"samples {body}", crank.tobytes(), samples).copy()
    if ripple[0] != 0.0 or not refine:
        return vals, (float(vals.min()), float(vals.max()))
    # a function of the model and the bracket alone: the same crank-angle grid of the
    # same model (a repeated or a preset's call) refines once
    return vals, refined_extremes(acc, crank, vals, lambda sgn, lo, hi, search: _last_of(
        model, f"refined {body} {sgn}", (float(lo), float(hi)), search))


def refined_extremes(f, x, values, keep=None) -> tuple[float, float]:
    """(min, max) of ``f`` from its ``values`` at the ascending ``x``: each extreme sample
    refined by a bounded search between its neighbours (``keep(sign, lo, hi, search)``,
    if given, returns ``search()`` or a kept result of it)."""
    from scipy.optimize import minimize_scalar

    ext = []
    for sgn, i in ((1.0, int(np.argmin(values))), (-1.0, int(np.argmax(values)))):
        lo, hi = x[max(i - 1, 0)], x[min(i + 1, x.size - 1)]

        def search(sgn=sgn, lo=lo, hi=hi):
            return minimize_scalar(lambda t: sgn * float(f(t)), bounds=(lo, hi),
                                   method="bounded", options={"xatol": 1e-12}).fun
        ext.append(sgn * min(search() if keep is None else keep(sgn, lo, hi, search),
                             sgn * values[i]))
    return float(ext[0]), float(ext[1])
