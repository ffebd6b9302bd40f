"""A dynamic main shaft: a flywheel and a motor characteristic turning a scene's mechanism.

The first crank's rotation θ becomes a state.  With elastic parts (the default when
the scene has any), θ joins the free parts' coordinates of :mod:`.motion` and the
drive's part gets (J_f + m₀) θ̈ + ½ m₀' θ̇² = T_motor(θ̇) + Q₀, m₀ and Q₀ its inertia and
the elastic elements' and moments' generalised force on it from the time domain's
right-hand side (:class:`_ElasticShaft`).  With every elastic element
rigid (``rigid=True``), the mechanism's kinetic energy is ½ J_red(θ) θ̇², J_red = Σ m |∂x/∂θ|²
+ Σ J (∂φ/∂θ)² over the scene's masses and inertias (the rigid-motion tables of
:mod:`.motion`), and Lagrange II gives

    (J_f + J_red(θ)) θ̈ + ½ J_red'(θ) θ̇² = T_motor(θ̇) + Q(θ),   Q = Σ M(θ) ∂φ_body/∂θ,

J_f the flywheel on the main shaft, M the scene's crank-angle moments
(``[[moments]]``, the beat-up), T_motor the motor's torque–speed
characteristic referred to the main shaft: an induction motor by Kloss's
formula T = 2 T_b / (s/s_b + s_b/s), s = (ω_s − ω)/ω_s, or a table.

:func:`simulate_shaft` finds the **steady cycle** (a periodic solution: the
state after one cycle equals the state before it, found by shooting on the cycle
map, integrated in θ by the scene's stepper, RK4 or RK8, or by DOP853) and the
**start-up** from rest
(integrated in time until the speed reaches the steady cycle), and returns a
:class:`ShaftMotion`: the speed over the cycle, δ = (ω_max − ω_min)/ω_mean
(ω_mean the time mean), the motor and load torques, every body's angular
acceleration, the start-up curve and its time.

The scene file's ``[shaft]`` table (:func:`parse_shaft`)::

    [shaft]
    flywheel = 0.5            # J_f [kg·m²] on the main shaft (the first crank's)
    motor = "kloss"           # an induction motor (values referred to the main shaft) ...
    sync_speed = 104.72       #   synchronous speed ω_s [rad/s]
    breakdown_torque = 60.0   #   T_b [N·m]
    breakdown_slip = 0.2      #   s_b; or, instead, the rated point:
    # rated_power = 1500.0    #   [W] and
    # rated_speed = 99.0      #   [rad/s]: T_n = P/ω_n, s_b = s_n (λ + √(λ² − 1)), λ = T_b/T_n
    # motor = "table"         # ... or a table, linear between its points:
    # speeds = [0.0, 100.0]   #   [rad/s], increasing
    # torques = [40.0, 0.0]   #   [N·m]
    start_deg = 0.0           # optional: the crank's rotation from the pose at rest
    max_time = 120.0          # optional: the longest start-up simulated [s]
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import MechcircError, ShaftWarning, SolverError
from ..sources import data_frame, summary_repr
from .files import Scene
from .motion import (Builder, MotionModel, body_tables, function_args, hermite_table,
                     kernel_arrays, moment_centre, motion_model)
from .simfile import Motor, Shaft, kloss_motor, parse_shaft, table_motor  # noqa: F401
from .simulation import check_strokes, kernels_for, max_rate, output_units, refined_extremes

__all__ = ["Motor", "Shaft", "ShaftMotion", "kloss_motor", "table_motor", "parse_shaft",
           "simulate_shaft", "ShaftWarning"]


@dataclass(frozen=True, eq=False)
class ShaftMotion:
    """The main shaft's steady cycle and start-up (plain, picklable data).

    Attributes
    ----------
    name, source : str
        The scene's name and where it came from.
    flywheel : float
        J_f [kg·m²].
    theta : ndarray
        Crank rotation over the steady cycle [rad, from the start angle].
    time : ndarray
        Time of each θ from the cycle's start [s].
    speed, acceleration : ndarray
        θ̇ [rad/s] and θ̈ [rad/s²] over the cycle.
    motor_torque, load_torque : ndarray
        T_motor(θ̇) and −Q, the torque the shaft must give against the moments (rigid) or
        against the moments and elastic elements acting on the drive's part [N·m].
    body_accelerations : dict[str, ndarray]
        Every link's and torsion body's angular acceleration [rad/s²] over the cycle
        (rigid: φ''(θ) θ̇² + φ'(θ) θ̈; elastic: each part's own motion, a block's travel
        ``BLOCK.travel`` in m/s²).
    omega_min, omega_max, omega_mean : float
        Extremes and time mean (cycle / its period) of the speed [rad/s].
    delta : float
        Coefficient of fluctuation (ω_max − ω_min)/ω_mean.
    period : float
        Duration of the steady cycle [s].
    startup_time : float or None
        Time from rest after which the speed stays within 1 % of ω_mean of the
        steady cycle's band [ω_min, ω_max] [s]; None without a start-up run.
    startup_t, startup_speed : ndarray
        The start-up curve (empty without one).
    notes : tuple of str
        How the motion was computed, for the report.
    values : dict[str, ndarray]
        Elastic scenes: ``ELEMENT.force`` [N or N·m], ``ELEMENT.deformation`` [m or rad]
        and ``MOMENT.moment`` [N·m] over the cycle (empty when rigid).
    states : ndarray
        Elastic scenes: the free parts' [q, q̇] at each θ (rows); shape (points, 0) rigid.
    aliases : dict[str, str]
        The scene's ``[simulate.aliases]`` of a body's acceleration: alias → body (an
        elastic scene's not of its ``rigid_acceleration``).
    units : dict[str, str]
        The unit of each of :meth:`curves`.
    """

    __repr__ = summary_repr

    name: str
    source: str
    flywheel: float
    theta: np.ndarray
    time: np.ndarray
    speed: np.ndarray
    acceleration: np.ndarray
    motor_torque: np.ndarray
    load_torque: np.ndarray
    body_accelerations: dict
    omega_min: float
    omega_max: float
    omega_mean: float
    delta: float
    period: float
    startup_time: float | None = None
    startup_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    startup_speed: np.ndarray = field(default_factory=lambda: np.empty(0))
    notes: tuple = ()
    values: dict = field(default_factory=dict)
    states: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    aliases: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)

    def curves(self) -> dict:
        """Every curve over the cycle by name: ``speed`` [rad/s], ``acceleration``
        [rad/s²], ``motor_torque`` and ``load_torque`` [N·m], each body's
        ``BODY.acceleration``, each alias of one, and each of ``values`` (their units
        in :attr:`units`)."""
        bodies = self.body_accelerations
        return {"speed": self.speed, "acceleration": self.acceleration,
                "motor_torque": self.motor_torque, "load_torque": self.load_torque,
                **{f"{b}.acceleration": a for b, a in bodies.items()},
                **{a: bodies[b] for a, b in self.aliases.items()}, **self.values}

    def to_dataframe(self):
        """One row per θ of the steady cycle: ``theta`` [rad], ``time`` [s] and each of
        :meth:`curves`; ``attrs["units"]`` the unit of each column."""
        cols = {"theta": self.theta, "time": self.time, **self.curves()}
        units = {"theta": "rad", "time": "s", **self.units}
        return data_frame(cols, {c: units.get(c, "") for c in cols})

    def summary(self) -> dict:
        """The scalar results and extremes, JSON-ready."""
        return {"flywheel": self.flywheel, "omega_min": self.omega_min,
                "omega_max": self.omega_max, "omega_mean": self.omega_mean,
                "delta": self.delta, "period": self.period, "startup_time": self.startup_time,
                "motor_torque": [float(self.motor_torque.min()), float(self.motor_torque.max()),
                                 float(np.mean(self.motor_torque))],
                "body_accelerations": {b: [float(v.min()), float(v.max())]
                                       for b, v in self.body_accelerations.items()}}


class _Cubic:
    """Cubic Hermite pieces on uniform nodes from values and slopes."""

    def __init__(self, h, f, f1):
        f, f1 = np.asarray(f, float), np.asarray(f1, float)
        d = (f[1:] - f[:-1]) / h
        self.h, self.n = h, f.size - 1
        self.c = np.column_stack([f[:-1], f1[:-1], (3 * d - 2 * f1[:-1] - f1[1:]) / h,
                                  (f1[:-1] + f1[1:] - 2 * d) / (h * h)])

    def __call__(self, u, slope=False):
        u = np.asarray(u, float)
        i = np.minimum((u / self.h).astype(int), self.n - 1)
        s = u - i * self.h
        a0, a1, a2, a3 = self.c[i].T
        return a1 + s * (2.0 * a2 + s * 3.0 * a3) if slope else a0 + s * (a1 + s * (a2 + s * a3))


def rigid_model(scene: Scene, N: int = 1024):
    """The rigid mechanism as the scene kernel's model of one part, the drive's, whose
    coordinate is the shaft's θ: every mass's x(θ), y(θ) and every inertia's rotation φ(θ)
    (a torsion body's: its link's) a quintic Hermite table of the rigid motion with weight m
    or J, so that the kernel's m₀ = J_red(θ) = Σ m |∂x/∂θ|² + Σ J (∂φ/∂θ)² and Q₀ the moments'
    Σ M ∂φ/∂θ: the rigid shaft's equation is the elastic one's with no free parts.

    Parameters
    ----------
    scene : Scene
        The scene to model.
    N : int
        Table nodes per crank revolution.

    Returns
    -------
    MotionModel
    """
    (ang, ang1, ang2, pos, vel, acc), _ = body_tables(scene, N)
    cyc, nodes = scene.cycle, N * scene.cycle_revolutions
    h, B = cyc / nodes, Builder(nodes, cyc)
    B.line(-1, 0.0, 1.0)                        # the drive's part: θ itself

    def table(f, f1, f2, turns=False):
        w = round((f[-1] - f[0]) / (2 * math.pi)) * 2 * math.pi / cyc if turns else 0.0
        q = h * np.arange(f.size)
        B.tabs.append(hermite_table(h, f - w * q, f1 - w, f2))
        return B.add([0, 0, len(B.tabs) - 1], [0.0, 0.0, cyc, 0.0, h, w])
    MI, MW = [], []
    for m in scene.masses:
        if m.kind == "mass":
            MI += [table(pos[m.point][:, k], vel[m.point][:, k], acc[m.point][:, k]) for k in (0, 1)]
        else:
            MI.append(table(ang[m.link], ang1[m.link], ang2[m.link], True))
        MW += [m.value] * (2 if m.kind == "mass" else 1)
    # the window's angle: θ itself
    MOI = [[B.line(0, 0.0, 1.0), table(ang[mo.body], ang1[mo.body], ang2[mo.body], True)]
           for mo in scene.moments]
    MOF = [[mo.amplitude, mo.window, mo.sigma, float(moment_centre(scene, mo))]
           for mo in scene.moments]
    # one part (the drive's), no elastic elements
    arrays = kernel_arrays(B, len(B.FI), dict(MI=MI, MW=MW, EI=[], EF=[], MOI=MOI, MOF=MOF,
                                              PRIG=[0], BI=[]))
    return MotionModel(scene=scene, omega=abs(scene.linkage.cranks[0].omega),
                       parts=((),), coordinate=("",), bodies=(), elements=(),
                       moments=tuple(mo.name for mo in scene.moments), arrays=arrays,
                       body_fn={}, centre={})


class _ElasticShaft:
    """The scene's time-domain model (:mod:`.motion`, its kernel's right-hand side) with the
    drive's part turned by the shaft's θ: the free parts' z = [q, q̇] and

        (J_f + c² m₀(cθ)) θ̈ + ½ c³ m₀'(cθ) θ̇² = T_motor(θ̇) + c Q₀(θ, θ̇, z)

    (q₀ = c θ the drive's coordinate, m₀ its part's inertia, Q₀ the generalised force of the
    elastic elements and moments on it: rows 3–5 of the kernel's work array)."""

    def __init__(self, scene: Scene, Jf: float, motor: Motor, model=None):
        self.model = m = motion_model(scene) if model is None else model
        a = m.arrays
        r = a["PRIG"][0]
        if a["FI"][r, 0] != 2 or a["FF"][r, 0] != 0.0:
            raise MechcircError(f"{scene.source}: the drive's part does not turn in proportion "
                                "to the main shaft; a dynamic shaft cannot drive it")
        self.c, self.n, self.Jf = float(a["FF"][r, 1]), m.n_free, Jf
        self.kern = kernels_for("rk4")[0]
        self.run_kern = _shaft_kernels()
        self.MP, self.steps = motor.params, 0     # steps per cycle of rk_run (0: scipy)
        self.tableau = self.run_kern.tableau("rk4")
        self.args = m.kernel_args(0.0, 1e300)
        self.oargs = m.kernel_args(0.0, 1e300, outputs=True)
        n = self.n
        self.PVt = np.concatenate((self.args[0], [2.0, Jf, self.c, -math.inf], self.MP))
        self.aux, self.dY, self.Y = np.empty(m.naux()), np.empty(2 * n + 2), np.empty(2 * n + 2)
        self.work = np.zeros((9, max(a["FI"].shape[0], a["PRIG"].shape[0])))
        self.zy, self.zd = np.empty(2 * n), np.empty(2 * n)
        self.shift = np.concatenate([m.rigid_state(scene.cycle)[:n] - m.rigid_state(0.0)[:n],
                                     np.zeros(n)])

    def deriv(self, theta, w, z, dz=None):
        """θ̈ at θ, θ̇ = w and the free parts' state z (the kernel's ``shaft_rhs`` in time);
        ż into ``dz`` when given."""
        n, Y, dY = self.n, self.Y, self.dY
        Y[0], Y[1:1 + n], Y[1 + n], Y[2 + n:] = theta, z[:n], w, z[n:]
        acc = self.run_kern.shaft_rhs(0.0, Y, self.PVt, *self.args[1:], dY, self.aux,
                                      self.work, self.zy, self.zd)
        if dz is not None:
            dz[:n], dz[n:] = dY[1:1 + n], dY[2 + n:]
        return acc

    def run(self, Y, in_theta, s0, h, nsteps, floor, record=True, every=1):
        """``nsteps`` steps of h of the shaft and free parts from s0 (Y = [θ̇, t, z] in θ, or
        [θ, θ̇, z] in time) by the scene's stepper (``rk_run`` of :mod:`._motion_kernels` with
        ``self.tableau``), stopping where the speed falls below ``floor`` → :class:`_Run`
        (the states at every ``every``-th step's start when ``record``, else the last only)."""
        Yk = _to_kernel(np.array(Y, float), in_theta, self.n)
        PV = np.concatenate((self.args[0], [1.0 if in_theta else 2.0, self.Jf, self.c, floor],
                             self.MP))
        rec_y = np.empty((nsteps // every + 1 if record else 0, Yk.size))
        rec_t = np.empty(rec_y.shape[0])
        t_end, j, ok, _, _ = self.run_kern.rk_run(Yk, float(s0), float(h), int(nsteps),
                                                  float(s0), float(h * every), rec_y, rec_t, PV,
                                                  *self.args[1:], self.model.naux(),
                                                  *self.tableau)
        ts, ys = rec_t[:j], rec_y[:j]
        if not ok or not j:
            ts, ys = np.append(ts, t_end), np.vstack((ys, Yk))
        return _Run(self, in_theta, ts, ys, int(not ok), floor)

    def evaluate(self, th, w, z):
        """The equations at crank rotations ``th``, speeds ``w`` and free parts' states ``z``
        (rows), in one kernel call (``shaft_eval``): rows [aux, θ̈, T_motor, m₀, m₀', Q₀]."""
        th = np.asarray(th, float)
        Y = _to_kernel(np.column_stack((th, np.broadcast_to(w, th.shape),
                                        np.reshape(z, (th.size, 2 * self.n)))), False, self.n)
        PV = np.concatenate((self.oargs[0], [2.0, self.Jf, self.c, -math.inf], self.MP))
        out = np.empty((th.size, self.model.naux() + 5))
        self.run_kern.shaft_eval(np.ascontiguousarray(Y), out, PV, *self.oargs[1:],
                                 self.model.naux())
        return out

    def rest(self, theta, w=0.0):
        """z of the rigid motion at θ turning at w (at rest: w = 0)."""
        return self.model.rigid_state(theta, w)

    def check_strokes(self, th, z):
        """Every slider with a ``stroke`` checked at every sample of the cycle (crank rotations
        ``th``, free parts' states ``z``) by the linkage's ``check_stroke``, as the
        constant-speed simulation does: its located error where a point is past its stroke."""
        m, coord = self.model, {0: self.c * th, **{i + 1: z[:, i] for i in range(self.n)}}
        stroked = [sl for sl in m.scene.linkage.sliders if sl.stroke]
        positions = {p: [self._function(f, coord[i])[:, 0] for f in (fx, fy)]
                     for p, (fx, fy, i) in m.point_fn.items()
                     if any(p in (sl.point, *sl.line) for sl in stroked)}
        check_strokes(m.scene, th, positions, "sample of the shaft's steady cycle")

    def _function(self, f, qs):
        """Function ``f`` of the model and its two derivatives at the coordinates ``qs``,
        shape (len(qs), 3): the kernels' ``eval_many``, one call for all samples."""
        out = np.empty((len(qs), 3))
        self.kern.eval_many(*function_args(self.model.arrays, f),
                            np.ascontiguousarray(qs, dtype=float), out)
        return out

    def samples(self, th, w, z, acc, out):
        """(body accelerations, element values) over the cycle's samples (``out``: their
        :meth:`evaluate`)."""
        m, a, c = self.model, self.model.arrays, self.c
        self.check_strokes(th, z)
        nb, ne = len(m.bodies), len(m.elements)
        bodies = {}
        for k, b in enumerate(m.bodies):
            f = m.body_fn[b]
            v = out[:, k].copy()
            if a["FI"][f, 1] == 0:          # on the drive's part: the kernel took θ̈ = 0
                v += self._function(f, c * th)[:, 1] * c * acc
            bodies[b] = v
        values = {f"{e}.{kind}": out[:, nb + j + off].copy() for j, e in enumerate(m.elements)
                  for kind, off in (("force", 0), ("deformation", ne))}
        values.update({f"{mo}.moment": out[:, nb + 2 * ne + 1 + j].copy()
                       for j, mo in enumerate(m.moments)})
        return bodies, values


class _RigidShaft(_ElasticShaft):
    """The shaft's equation on the rigid mechanism: the kernel's on :func:`rigid_model` (no
    state beyond θ, θ̇: z is empty)."""

    def __init__(self, scene: Scene, Jf: float, motor: Motor, N: int = 1024):
        (_, ang1, ang2, _, vel, _), _ = body_tables(scene, N)
        nodes = N * scene.cycle_revolutions
        J = np.zeros(nodes + 1)                 # J_red(θ) of the rigid mechanism
        for m in scene.masses:
            if m.kind == "mass":
                J += m.value * np.sum(vel[m.point] ** 2, axis=1)
            else:
                J += m.value * ang1[m.link] ** 2
        if float(J.min()) + Jf <= 0:
            raise MechcircError(f"{scene.source}: the shaft has no inertia (flywheel 0 and no "
                                "mass of the mechanism moves with the crank)")
        super().__init__(scene, Jf, motor, rigid_model(scene))
        self.cycle = scene.cycle
        #: Each body's φ'(θ) (its slope φ''(θ)) of the rigid mechanism.
        self.rate = {b: _Cubic(self.cycle / nodes, ang1[b], ang2[b]) for b in scene.bodies}

    def load(self, th):
        """The load torque −Q(θ) [N·m] of the moments at crank rotations ``th`` (array)."""
        th = np.asarray(th, float)
        return -self.evaluate(th, 0.0, np.empty((th.size, 0)))[:, -1]

    def samples(self, th, w, z, acc, out):
        """(body accelerations, element values) over the cycle's samples."""
        u = th - self.cycle * np.floor(th / self.cycle)
        bodies = {b: r(u, slope=True) * w * w + r(u) * acc for b, r in self.rate.items()}
        return bodies, {}


_WARM_STATEMENT = ("import mechcirc._jit as j; j.COMPILED = True; "
                   "from mechcirc.scene.shaft import warm_up; warm_up()")


def _shaft_kernels():
    """The kernel module whose ``rk_run``, ``shaft_eval`` (the kernel ``output_pass``) and
    ``shaft_rhs`` the shaft calls: compiled when numba's disk cache holds it (or
    :data:`mechcirc._jit.COMPILED` is True), else the Python copy while a detached process
    compiles it (the no-wait rule of :mod:`mechcirc._jit`)."""
    from .. import _jit

    from . import _motion_kernels as k

    return k if k.HAVE_NUMBA and _jit.use(_WARM_STATEMENT, k.rk_run, k.output_pass,
                                          k.shaft_rhs) else k.load_python()


def warm_up() -> None:
    """Compile the shaft's kernels (the scene's ``rk_run``, ``shaft_eval`` and ``shaft_rhs``)
    into numba's disk cache on a two-step run of a shaft with nothing on it (the arguments'
    types are those of every scene and method).

    Returns
    -------
    None
    """
    from . import _motion_kernels as k

    i8 = np.int64
    PV = np.concatenate((np.zeros(8), [1.0, 1.0, 1.0, 0.0, 0.0, 10.0, 1.0, 0.2]))
    arrays = (np.array([[2, -1, 0]], i8), np.array([[0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]]),
              np.zeros((1, 2, 6)), np.zeros(0, i8), np.zeros(0), np.zeros((0, 8), i8),
              np.zeros((0, 10)), np.zeros((0, 2), i8), np.zeros((0, 4)), np.array([0], i8),
              np.zeros(0, i8))
    k.rk_run(np.array([0.0, 1.0]), 0.0, 0.1, 2, 0.0, 0.1, np.empty((3, 2)), np.empty(3), PV,
             *arrays, 4, *k.tableau("rk4"))
    PV[8] = 2.0
    k.shaft_eval(np.array([[0.0, 1.0]]), np.empty((1, 9)), PV, *arrays, 4)
    k.shaft_rhs(0.0, np.array([0.0, 1.0]), PV, *arrays, np.empty(2), np.empty(4),
                np.zeros((9, 1)), np.empty(0), np.empty(0))


def _prepare(scene: Scene, shaft, flywheel, points, rigid):
    """Checks of the options → (shaft, the rigid shaft's equations, the equations (each with
    its J_f), peak load, mean load, notes)."""
    shaft = shaft or scene.shaft
    if shaft is None:
        raise MechcircError(f"{scene.source}: no [shaft] table: give the flywheel and motor "
                            "(docs/scenes.md, \"A dynamic main shaft\")")
    Jf = shaft.flywheel if flywheel is None else float(flywheel)
    if not (math.isfinite(Jf) and Jf >= 0):
        raise MechcircError(f"flywheel must be a number ≥ 0 kg·m², got {flywheel!r}")
    if isinstance(points, bool) or not isinstance(points, int) or points < 16:
        raise MechcircError(f"points must be an integer ≥ 16, got {points!r}")
    motor = shaft.motor
    req = _RigidShaft(scene, Jf, motor)         # (refuses a shaft with no inertia)
    eq: _ElasticShaft = req
    if not rigid and scene.parts and len(scene.parts) > 1:
        eq, th = _ElasticShaft(scene, Jf, motor), np.array([0.0, 1.0, 2.0])
        with np.errstate(divide="ignore", invalid="ignore"):     # θ̈ of no inertia: unused
            m0 = eq.evaluate(th, 0.0, [eq.rest(t) for t in th])[:, -3]
        if eq.Jf + eq.c ** 2 * float(m0.min()) <= 0:
            raise MechcircError(f"{scene.source}: the shaft has no inertia of its own (flywheel "
                                "0 and no mass on the drive's part): give [shaft] flywheel > 0")
    grid = np.linspace(0.0, req.cycle, 4 * points, endpoint=False)
    load = req.load(grid)
    peak = float(load.max())
    if motor.peak_torque < peak:
        text = (f"the motor's largest torque {motor.peak_torque:.6g} N·m (breakdown) is below "
                f"the peak load torque {peak:.6g} N·m at θ = "
                f"{math.degrees(grid[int(load.argmax())]):.4g}°: only the flywheel and the "
                "mechanism's inertia carry the shaft through it")
        warnings.warn(f"{scene.source}: {text}", ShaftWarning, stacklevel=3)
        return shaft, req, eq, peak, float(np.mean(load)), ["warning: " + text]
    return shaft, req, eq, peak, float(np.mean(load)), []


#: Steps per period of the fastest linearised mode of the elastic shaft, by method.
STEPS_PER_PERIOD = {"rk4": 100, "rk8": 16}

#: :func:`simulate_shaft`'s method when none is given (bench_shaft.py, measured in
#: docs/performance.md): rigid, rk8 reaches RK4's error at 100 steps per period for less CPU;
#: elastic, rk8 at 16 steps per period is 1.3-1.6x cheaper than RK4 at 100 and 40-120x
#: more accurate on the benchmark's three elastic cases (clearance gaps included).
DEFAULT_METHOD = "rk8"

#: Steps per cycle of the rigid shaft for each step per period (it has no elastic mode).
RIGID_STEPS = 16

#: Fixed steps a cycle at most; beyond, DOP853 (adaptive) integrates the cycle.
MAX_STEPS = 2 ** 16

#: Right-hand side evaluations one cycle of the shaft may take.
MAX_CALLS = 200_000


def _to_kernel(Y, in_theta, n):
    """A shaft state as :func:`._motion_kernels.shaft_rhs` takes it, from [θ̇, t, q, q̇] (in θ)
    or [θ, θ̇, q, q̇] (in time); rows for a 2-d ``Y``."""
    Y = np.asarray(Y, float)
    if not in_theta:
        return np.concatenate((Y[..., :1], Y[..., 2:2 + n], Y[..., 1:2], Y[..., 2 + n:]), -1)
    u = 1.0 / Y[..., :1]
    return np.concatenate((Y[..., 1:2], Y[..., 2:2 + n], u, Y[..., 2 + n:] * u), -1)


def _from_kernel(Y, in_theta, n):
    """The inverse of :func:`_to_kernel`."""
    if not in_theta:
        return np.concatenate((Y[..., :1], Y[..., 1 + n:2 + n], Y[..., 1:1 + n],
                               Y[..., 2 + n:]), -1)
    w = 1.0 / Y[..., 1 + n:2 + n]
    return np.concatenate((w, Y[..., :1], Y[..., 1:1 + n], Y[..., 2 + n:] * w), -1)


class _Run:
    """A fixed-step run of the shaft as solve_ivp's result: ``status`` (1: stalled), ``t``,
    ``y`` (columns [θ̇, t, z] in θ, [θ, θ̇, z] in time) at the steps' starts, and ``sol(x)``:
    one step of the same method from the last step's start before x (the run's own accuracy
    at any x, kinks located in it)."""

    def __init__(self, eq, in_theta, ts, yk, status, floor):
        self.eq, self.in_theta, self.floor, self.status = eq, in_theta, floor, status
        self.t, self.y = ts, _from_kernel(yk, in_theta, eq.n).T

    def sol(self, x):
        x = np.asarray(x, float)
        out = np.empty((self.y.shape[0], x.size))
        idx = np.clip(np.searchsorted(self.t, x.ravel(), "right") - 1, 0, self.t.size - 1)
        for c, (xi, i) in enumerate(zip(x.ravel(), idx)):
            h = xi - self.t[i]
            out[:, c] = self.y[:, i] if h == 0.0 else self.eq.run(
                self.y[:, i], self.in_theta, self.t[i], h, 1, -math.inf, record=False).y[:, -1]
        return out.reshape((-1,) + x.shape)

    def grid(self, cycle, points):
        """The states at ``points`` + 1 uniform steps over the cycle from the run's start (in
        θ), each the end of a step of the method: the cycle rerun at the smallest multiple
        of ``points`` steps not below the run's."""
        k = max(-(-self.eq.steps // points), 1)
        return self.eq.run(self.y[:, 0], self.in_theta, self.t[0], cycle / (points * k),
                           points * k, -math.inf, every=k).y


def _over_cycle(eq, th0, cycle, x0, rtol, scale, dense=False, floor=1e-6):
    """One cycle in θ from θ0 of Y = [θ̇, t, z] (dY/dθ = Ẏ/θ̇), x0 = [θ̇, z] at θ0; stops
    where θ̇ falls to ``floor`` × the motor's speed scale (a stall)."""
    from scipy.integrate import solve_ivp

    Y0 = np.concatenate(([x0[0], 0.0], x0[1:]))       # [θ̇, t, z]
    if eq.steps:
        return eq.run(Y0, True, th0, cycle / eq.steps, eq.steps, floor * scale, record=dense)
    calls = [0]

    def f(th, Y):
        calls[0] += 1
        if calls[0] > MAX_CALLS or not math.isfinite(Y[0]):
            raise SolverError(f"a cycle of the shaft needed more than {MAX_CALLS} evaluations "
                              f"(at θ = {math.degrees(th):.6g}°, speed {Y[0]:.6g} rad/s)",
                              status="too-many-steps")
        out = np.empty(Y.size)
        out[0], out[1] = eq.deriv(th, Y[0], Y[2:], out[2:]), 1.0
        out /= Y[0]
        return out

    def stall(th, Y):
        return Y[0] - floor * scale
    stall.terminal = True
    return solve_ivp(f, (th0, th0 + cycle), Y0, method="DOP853", rtol=rtol,
                     atol=_atol(rtol, scale, eq.n), events=stall, dense_output=dense)


def _atol(rtol, scale, n):
    """DOP853's absolute tolerances of the shaft's state with n free coordinates: speed and
    time (or angle) on the motor's speed ``scale``, then the coordinates and their rates."""
    return rtol * 1e-3 * np.concatenate(([scale, scale], np.full(n, 1e-2),
                                         np.full(n, 1e-2 * scale)))


def _steady_speed(eq, th0, cycle, rtol, scale, guess, fail, xtol=1e-13):
    """The rigid steady cycle's speed at θ0: the zero of (speed after a cycle − before) by
    Brent's method, bracketed outward from ``guess``; ``fail()`` raises when none is found."""
    from scipy.optimize import brentq

    def gap(w0):
        sol = _over_cycle(eq, th0, cycle, [w0], rtol, scale)
        return -w0 if sol.status == 1 else sol.y[0, -1] - w0

    lo, hi = 0.5 * guess, guess * 1.02 + 1e-9 * scale
    glo, ghi = gap(lo), gap(hi)
    for _ in range(40):
        if glo > 0 and ghi < 0:
            break
        if glo <= 0:
            lo *= 0.5
            glo = gap(lo)
        if ghi >= 0:
            hi = hi * 1.1 + 1e-3 * scale
            ghi = gap(hi)
    else:
        fail()
    return brentq(gap, lo, hi, xtol=xtol * scale, rtol=4 * np.finfo(float).eps)


def _steady_state(eq, th0, cycle, w0, rtol, scale):
    """The elastic steady cycle's [θ̇, z] at θ0: the fixed point of the cycle map (after one
    cycle θ̇ and z as before, positions shifted by their windings) by scipy's hybrid Powell
    method from the rigid cycle's speed and rigid state; (x, largest residual)."""
    from scipy.optimize import root

    def G(x):         # below 1 % of the rigid cycle's speed the shaft counts as stalled
        try:
            sol = _over_cycle(eq, th0, cycle, x, rtol, scale, floor=0.01 * w0 / scale)
        except SolverError:
            sol = None
        if sol is None or sol.status == 1:
            return np.concatenate(([-x[0]], np.zeros(2 * eq.n)))
        Y = sol.y[:, -1]
        return np.concatenate(([Y[0] - x[0]], Y[2:] - x[1:] - eq.shift))

    x = np.concatenate(([w0], eq.rest(th0, w0)))
    x = x + G(x)                        # a cycle settles the fast elastic transient
    res = root(G, x, method="hybr", options={"xtol": 1e-13, "maxfev": 12 * (x.size + 1)})
    resid = float(np.max(np.abs(res.fun) / np.concatenate((
        [scale], np.full(eq.n, 1.0), np.full(eq.n, scale)))))
    # hybr may stop short of xtol where the map's rounding (~rtol) is all that is left
    if not res.success and not resid <= 100 * rtol:
        raise SolverError(f"no steady cycle of the elastic mechanism on the shaft: {res.message} "
                          f"(speed {x[0]:.6g} rad/s at the last cycle's start, residual "
                          f"{resid:.2g})", status="no-steady-cycle")
    return res.x, resid


def simulate_shaft(scene: Scene, shaft: Shaft | None = None, *, flywheel: float | None = None,
                   points: int = 720, startup: bool = True, rtol: float = 1e-10,
                   rigid: bool = False, method: str | None = None,
                   steps_per_period: float | None = None) -> ShaftMotion:
    """The main shaft turned by the motor through the flywheel: steady cycle and start-up.

    Parameters
    ----------
    scene : Scene
        The scene whose main shaft turns.
    shaft : Shaft, optional
        Default the scene's ``[shaft]`` table.
    flywheel : float, optional
        J_f [kg·m²], replacing the shaft's.
    points : int
        Samples over the steady cycle (≥ 16).
    startup : bool
        Also integrate the start-up from rest (in time, until the steady cycle).
    rtol : float
        Relative tolerance of the DOP853 integrations.
    rigid : bool
        Treat every elastic element as rigid (θ the only degree of freedom); by default
        the elastic parts are simulated, coupled to θ (the free parts of :mod:`.motion`).
    method : {"rk4", "rk8", "DOP853"}, optional
        ``"rk4"``/``"rk8"``: the scene's compiled stepper at fixed steps (classical RK4 or
        DOP853's 8th-order formula; in θ over the cycle, in time for the start-up; kinks of
        clearance gaps and moment windows located inside the steps); ``"DOP853"``: scipy's
        solve_ivp at ``rtol``.  The rigid shaft takes the same paths (:func:`rigid_model`).
        Default (None): :data:`DEFAULT_METHOD`, ``"rk8"`` (16 steps per period with elastic
        parts, 16 × 16 steps a cycle for the rigid shaft).
    steps_per_period : float, optional
        ``"rk4"``/``"rk8"``: steps per period of the fastest linearised mode at the steady
        speed (default :data:`STEPS_PER_PERIOD` of the method).

    Returns
    -------
    ShaftMotion

    Raises
    ------
    MechcircError
        No ``[shaft]``; the motor cannot start the mechanism from rest at the start angle,
        or stalls during the start-up or the steady cycle (the message gives the torques);
        the start-up did not reach the steady cycle within ``max_time``.
    """
    shaft, req, eq, peak, mean_load, notes = _prepare(scene, shaft, flywheel, points, rigid)
    method = method or DEFAULT_METHOD
    spp = _checked_method(method, steps_per_period)       # None for DOP853
    motor = shaft.motor
    th0, cyc = math.radians(shaft.start_deg), req.cycle
    scale = max(abs(motor.sync_speed) if motor.kind == "kloss" else max(motor.speeds), 1e-300)
    if startup:
        _require_start(scene, shaft, req, th0)
    if method != "DOP853":
        eq.tableau = eq.run_kern.tableau(method)
    x0, sol = _steady_cycle(scene, eq, req, motor, th0, rtol, scale, mean_load, peak, notes, spp)
    motion = _tabulate(scene, eq, sol, th0, cyc, points)
    if not startup:
        return ShaftMotion(**motion, notes=tuple(notes))
    up = (_startup_steps if eq.steps else _startup)(scene, eq, shaft, th0, cyc, x0[0], motion,
                                                    rtol, scale, peak)
    notes.append(_how(method, eq.steps, rtol, up.pop("cycles")))
    return ShaftMotion(**motion, **up, notes=tuple(notes))


def _how(method: str, steps: int, rtol: float, cycles: int) -> str:
    """The note of how :func:`simulate_shaft` integrated the steady cycle and start-up."""
    how = f"{method.upper()} in θ, {steps} steps a cycle" if steps else \
        f"DOP853 in θ, rtol {rtol:g}"
    return (f"steady cycle by shooting ({how}); start-up from rest over {cycles} "
            f"cycle{'s' * (cycles != 1)}")


def _checked_method(method, steps_per_period) -> float | None:
    """``steps_per_period`` of :func:`simulate_shaft` (its method's default when None; None
    for DOP853), with the method checked."""
    if method not in ("rk4", "rk8", "DOP853"):
        raise MechcircError(f"method must be 'rk4', 'rk8' or 'DOP853', got {method!r}")
    if steps_per_period is None:
        steps_per_period = STEPS_PER_PERIOD.get(method, 4)
    if isinstance(steps_per_period, bool) or not (
            isinstance(steps_per_period, (int, float)) and steps_per_period >= 4):
        raise MechcircError(f"steps_per_period must be a number ≥ 4, got {steps_per_period!r}")
    return None if method == "DOP853" else steps_per_period


def _require_start(scene, shaft, req, th0) -> None:
    """Refuse a motor whose starting torque does not exceed the load at the start angle.

    At rest the elastic elements carry the loads statically: the rigid
    mechanism's torque is the load.
    """
    T0, L0 = shaft.motor.scalar_torque(0.0), float(req.load([th0])[0])
    if T0 - L0 <= 0:
        raise MechcircError(
            f"{scene.source}: the motor cannot start the mechanism: its starting torque "
            f"T(0) = {T0:.6g} N·m does not exceed the load torque "
            f"{L0:.6g} N·m at the start angle {shaft.start_deg:g}°")


def _steady_cycle(scene, eq, req, motor, th0, rtol, scale, mean_load, peak, notes, spp):
    """The steady cycle from θ0: ([θ̇, z] at θ0, its dense solution over the cycle); elastic
    with ``spp`` given: by the compiled stepper (``eq.tableau``) at ``spp`` steps per period
    of the fastest mode.  ``req``: the rigid shaft's equations (the elastic's first guess)."""
    cyc = req.cycle

    def fail():
        raise MechcircError(
            f"{scene.source}: no steady cycle: the motor (largest torque "
            f"{motor.peak_torque:.6g} N·m) cannot keep the mechanism turning against the mean "
            f"load torque {mean_load + 0.0:.6g} N·m, peak {peak + 0.0:.6g} N·m, with flywheel "
            f"{eq.Jf:g} kg·m²")
    guess, th = _balance(motor, mean_load, scale), th0 + np.linspace(0.0, cyc, 2048, False)
    if spp is not None:
        req.tableau = eq.tableau
        req.steps = _stable(req, cyc, th, 0.5 * guess, RIGID_STEPS * spp)
    w0 = _steady_speed(req, th0, cyc,
                       max(rtol, 1e-5) if eq.n else rtol, scale,     # elastic: a first guess
                       guess, fail, 1e-5 if eq.n else 1e-13)
    x0 = np.array([w0])
    if eq.n and spp is not None:
        eq.steps = _stable(eq, cyc, th, w0, cyc * max_rate(eq.model) * spp / (2 * math.pi * w0))
    if spp is not None and not eq.steps:
        notes.append(f"DOP853 in θ: fixed steps would need over {MAX_STEPS} a cycle (small flywheel)")
    if eq.n and eq.steps:
        backend = "compiled" if getattr(eq.run_kern, "HAVE_NUMBA", False) else "Python copy"
        name = "RK8" if eq.tableau[3] else "RK4"
        notes.append(f"{name} in θ with the elastic parts, {eq.steps} steps a cycle (at "
                     f"least {spp:g} per period of the fastest mode), {backend}")
    if eq.n:
        x0, resid = _steady_state(eq, th0, cyc, w0, rtol, scale)
        notes.append(f"elastic steady cycle: {2 * eq.n} elastic states beside θ̇, cycle map "
                     f"residual {resid:.2g} (relative)")
    sol = _over_cycle(eq, th0, cyc, x0, rtol, scale, dense=True)
    if sol.status != 0:
        raise SolverError(f"{scene.source}: the steady cycle stalls at θ = "
                          f"{math.degrees(sol.t[-1]):.6g}°", status="stalled")
    return x0, sol


def _stable(eq, cyc, th, w, steps):
    """``steps`` a cycle of the fixed-step method (at least 64), or more, so that each
    step's h·λ stays within half its real-axis stability limit (RK4 2.785, RK8 6.39):
    λ = |∂(θ̈/θ̇)/∂θ̇|, the relaxation of the shaft's speed in θ, at crank rotations ``th``
    and speed ``w`` (fast where a small flywheel leaves little inertia against the motor's
    slope); 0 (DOP853, adaptive) beyond :data:`MAX_STEPS`."""
    z = np.array([eq.rest(t, w) for t in th]) if eq.n else np.empty((th.size, 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = [eq.evaluate(th, v, z)[:, -5] / v for v in (w, w * (1 + 1e-6))]
        n = cyc * float(np.max(np.abs(a[1] - a[0]))) / (1e-6 * w * (3.2 if eq.tableau[3] else 1.39))
    return max(64, math.ceil(steps), math.ceil(n)) if n <= MAX_STEPS else 0


def _tabulate(scene, eq, sol, th0, cyc, points):
    """The steady cycle on ``points`` uniform θ samples → ShaftMotion's fields."""
    th = th0 + np.linspace(0.0, cyc, points + 1)
    Y = sol.grid(cyc, points) if isinstance(sol, _Run) else sol.sol(th)
    period = float(Y[1, -1])
    th, Y = th[:-1], Y[:, :-1]
    w, tt, z = Y[0], Y[1], Y[2:].T
    out = eq.evaluate(th, w, z)
    acc = out[:, -5]
    bodies, values = eq.samples(th, w, z, acc, out)
    wmin, wmax = refined_extremes(lambda x: sol.sol(x)[0], th, w)
    mean = cyc / period
    aliases = {a: t.rsplit(".", 1)[0] for a, t in (scene.simulate.aliases.items()
               if scene.simulate is not None else ())
               if t.endswith("acceleration") and t.rsplit(".", 1)[0] in bodies
               and (not values or not t.endswith(".rigid_acceleration"))}   # elastic: not rigid
    return dict(name=scene.name, source=scene.source, flywheel=eq.Jf, theta=th - th0, time=tt,
                speed=w, acceleration=acc, motor_torque=out[:, -4].copy(),
                load_torque=-eq.c * out[:, -1], body_accelerations=bodies, omega_min=wmin, omega_max=wmax,
                omega_mean=mean, delta=(wmax - wmin) / mean, period=period, values=values,
                states=np.ascontiguousarray(z), aliases=aliases,
                units={"speed": "rad/s", "acceleration": "rad/s²", "motor_torque": "N·m",
                       "load_torque": "N·m", **output_units(
                           scene, [f"{b}.acceleration" for b in bodies] + [*aliases, *values])})


def _startup(scene, eq, shaft, th0, cyc, w0, motion, rtol, scale, peak):
    """The start-up from rest, in time, cycle by cycle until the speed at a cycle's start is
    within 1e-5 ω_mean of the steady cycle's → startup_time, startup_t, startup_speed."""
    from scipy.integrate import solve_ivp

    mean = motion["omega_mean"]
    ts, ws, segments = [0.0], [0.0], []
    t, y, k = 0.0, np.concatenate(([th0, 0.0], eq.rest(th0))), 0
    atol = _atol(rtol, scale, eq.n)

    def f(_, y):
        out = np.empty(y.size)
        out[0], out[1] = y[1], eq.deriv(y[0], y[1], y[2:], out[2:])
        return out

    def stopped(_, y):
        return y[1] + 1e-9 * scale
    stopped.terminal = True
    while True:
        k += 1

        def reached(_, y, target=th0 + k * cyc):
            return y[0] - target
        reached.terminal = True
        s = solve_ivp(f, (t, shaft.max_time), y, method="DOP853", rtol=rtol, atol=atol,
                      events=(reached, stopped), dense_output=True)
        tk = np.linspace(t, s.t[-1], 65)[1:]
        ts.extend(tk)
        ws.extend(s.sol(tk)[1])
        segments.append((t, s.sol))
        t, y = float(s.t[-1]), s.y[:, -1]
        if s.status == 1 and s.t_events[1].size:
            raise _stalled(scene, shaft, t, y[0], peak, motion)
        if s.status != 1:
            raise _too_slow(scene, shaft, y[1], w0)
        if abs(y[1] - w0) <= 1e-3 * 0.01 * mean:     # settled well inside the band
            break
    return _startup_result(ts, ws, segments, motion, k)


def _startup_steps(scene, eq, shaft, th0, cyc, w0, motion, rtol, scale, peak):
    """:func:`_startup` by the scene's stepper in time, at the time step of the steady cycle's
    θ step, one cycle's steps at a time; the cycle's starts and the band's last crossing
    located by Brent's method on the run's :meth:`_Run.sol`."""
    from scipy.optimize import brentq

    mean, h = motion["omega_mean"], cyc / eq.steps / w0
    ts, ws, runs = [0.0], [0.0], []
    t, Y, k = 0.0, np.concatenate(([th0, 0.0], eq.rest(th0))), 0
    every = max(eq.steps // 64, 1)
    while True:
        run = eq.run(Y, False, t, h, eq.steps, -1e-9 * scale)
        rec = run.y.T
        runs.append(run)
        if run.status:
            raise _stalled(scene, shaft, run.t[-1], rec[-1, 0], peak, motion)
        done = None
        while th0 + (k + 1) * cyc <= rec[-1, 0]:
            k += 1
            i = int(np.searchsorted(rec[:, 0], th0 + k * cyc))
            tk = brentq(lambda x, k=k, run=run: run.sol(x)[0] - th0 - k * cyc, run.t[i - 1], run.t[i],
                        xtol=1e-14)
            if abs(run.sol(tk)[1] - w0) <= 1e-3 * 0.01 * mean:     # settled well inside
                done = tk
                break
        keep = run.t[1:] if done is None else np.append(run.t[1:][run.t[1:] < done], done)
        keep = keep[::-1][::every][::-1]
        ts.extend(keep)
        ws.extend(run.sol(keep)[1])
        if done is not None:
            break
        t, Y = float(run.t[-1]), rec[-1]
        if t >= shaft.max_time:
            raise _too_slow(scene, shaft, Y[1], w0)
    return _startup_result(ts, ws, [(r.t[0], r.sol) for r in runs], motion, k)


def _stalled(scene, shaft, t: float, theta: float, peak: float, motion) -> MechcircError:
    return MechcircError(
        f"{scene.source}: the start-up stalls at t = {t:.4g} s, θ = "
        f"{math.degrees(theta):.5g}°: the motor's largest torque "
        f"{shaft.motor.peak_torque:.6g} N·m is below the peak load torque {peak:.6g} "
        f"N·m and the flywheel ({motion['flywheel']:g} kg·m²) does not carry it through")


def _too_slow(scene, shaft, speed: float, w0: float) -> MechcircError:
    return MechcircError(
        f"{scene.source}: the start-up did not reach the steady cycle within max_time "
        f"= {shaft.max_time:g} s (speed {speed:.6g} rad/s against the steady "
        f"{w0:.6g} rad/s at the cycle's start): raise [shaft] max_time")


def _startup_result(ts, ws, segments, motion, k: int) -> dict:
    """The start-up's record from its samples (``ts``, ``ws``) and ``segments`` (start time,
    dense solution ``sol(t) -> (θ, ω, ...)``): the time of the last crossing into the band
    of the steady cycle's speed ±1 % of its mean, located by Brent's method on the solution."""
    from scipy.optimize import brentq

    ts, ws, mean = np.array(ts), np.array(ws), motion["omega_mean"]
    band = (motion["omega_min"] - 0.01 * mean, motion["omega_max"] + 0.01 * mean)
    out = np.flatnonzero((ws < band[0]) | (ws > band[1]))
    t_up = 0.0
    if out.size:
        i = int(out[-1])
        fi = next(sol for t0, sol in reversed(segments) if t0 <= ts[i])
        bound = band[0] if ws[i] < band[0] else band[1]
        t_up = float(brentq(lambda x: fi(x)[1] - bound, ts[i], ts[i + 1], xtol=1e-14))
    return dict(startup_time=t_up, startup_t=ts, startup_speed=ws, cycles=k)


def _balance(motor: Motor, torque: float, scale: float) -> float:
    """The speed where the motor gives ``torque`` on its falling branch (a first guess)."""
    from scipy.optimize import brentq

    top = motor.sync_speed if motor.kind == "kloss" else motor.speeds[-1]
    ws = np.linspace(0.0, top, 401)
    tq = motor.torque(ws) - torque
    i = int(np.argmax(tq))
    for j in range(i, 400):
        if tq[j] > 0 >= tq[j + 1]:
            return float(brentq(lambda w: float(motor.torque(w)) - torque, ws[j], ws[j + 1]))
    return 0.5 * scale
