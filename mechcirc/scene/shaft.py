"""A dynamic main shaft: a flywheel and a motor characteristic turning a scene's rigid mechanism.

The first crank's rotation θ becomes a state.  With every elastic element
rigid, the mechanism's kinetic energy is ½ J_red(θ) θ̇², J_red = Σ m |∂x/∂θ|²
+ Σ J (∂φ/∂θ)² over the scene's masses and inertias (the rigid-motion tables of
:mod:`.motion`), and Lagrange II gives

    (J_f + J_red(θ)) θ̈ + ½ J_red'(θ) θ̇² = T_motor(θ̇) + Q(θ),   Q = Σ M(θ) ∂φ_body/∂θ,

J_f the flywheel on the main shaft, M the scene's crank-angle moments
(``[[moments]]``, the beat-up), T_motor the motor's torque–speed
characteristic referred to the main shaft: an induction motor by Kloss's
formula T = 2 T_b / (s/s_b + s_b/s), s = (ω_s − ω)/ω_s, or a table.

:func:`simulate_shaft` finds the **steady cycle** (a periodic solution: the
speed after one cycle equals the speed before it, found by Brent's method on
the cycle map, integrated in θ by DOP853) and the **start-up** from rest
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
from .files import Scene
from .simfile import Motor, Shaft, kloss_motor, parse_shaft, table_motor  # noqa: F401

__all__ = ["Motor", "Shaft", "ShaftMotion", "kloss_motor", "table_motor", "parse_shaft",
           "reduced_inertia", "simulate_shaft", "ShaftWarning"]


@dataclass(frozen=True, eq=False)
class ShaftMotion:
    """The main shaft's steady cycle and start-up (plain, picklable data).

    Attributes
    ----------
    name, source : str
    flywheel : float
        J_f [kg·m²].
    theta : ndarray
        Crank rotation over the steady cycle [rad, from the start angle].
    time : ndarray
        Time of each θ from the cycle's start [s].
    speed, acceleration : ndarray
        θ̇ [rad/s] and θ̈ [rad/s²] over the cycle.
    motor_torque, load_torque : ndarray
        T_motor(θ̇) and −Q(θ), the moments' torque the shaft must give [N·m].
    body_accelerations : dict[str, ndarray]
        Every link's and torsion body's angular acceleration [rad/s²] in the rigid
        motion over the cycle: φ''(θ) θ̇² + φ'(θ) θ̈.
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
    """

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

    def summary(self) -> dict:
        """The scalar results and extremes, JSON-ready."""
        out = {"flywheel": self.flywheel, "omega_min": self.omega_min,
               "omega_max": self.omega_max, "omega_mean": self.omega_mean,
               "delta": self.delta, "period": self.period, "startup_time": self.startup_time,
               "motor_torque": [float(self.motor_torque.min()), float(self.motor_torque.max()),
                                float(np.mean(self.motor_torque))],
               "body_accelerations": {b: [float(v.min()), float(v.max())]
                                      for b, v in self.body_accelerations.items()}}
        return out


class _Cubic:
    """Cubic Hermite pieces on uniform nodes from values and slopes, with a fast scalar path."""

    def __init__(self, h, f, f1):
        f, f1 = np.asarray(f, float), np.asarray(f1, float)
        d = (f[1:] - f[:-1]) / h
        self.h, self.n = h, f.size - 1
        self.c = np.column_stack([f[:-1], f1[:-1], (3 * d - 2 * f1[:-1] - f1[1:]) / h,
                                  (f1[:-1] + f1[1:] - 2 * d) / (h * h)])
        self.rows = self.c.tolist()

    def at(self, u):
        """(value, slope) at one u in [0, n h]."""
        i = min(int(u / self.h), self.n - 1)
        s = u - i * self.h
        a0, a1, a2, a3 = self.rows[i]
        return a0 + s * (a1 + s * (a2 + s * a3)), a1 + s * (2.0 * a2 + s * 3.0 * a3)

    def __call__(self, u, slope=False):
        u = np.asarray(u, float)
        i = np.minimum((u / self.h).astype(int), self.n - 1)
        s = u - i * self.h
        a0, a1, a2, a3 = self.c[i].T
        if slope:
            return a1 + s * (2.0 * a2 + s * 3.0 * a3)
        return a0 + s * (a1 + s * (a2 + s * a3))


class _Rigid:
    """J_red(θ), J_red'(θ), Q(θ) and each body's φ'(θ), φ''(θ) of the rigid mechanism."""

    def __init__(self, scene: Scene, N: int = 1024):
        from .motion import rigid_tables, dead_centre
        from .simulation import kernels_for

        ang, ang1, ang2, pos, vel, acc = (dict(x) for x in rigid_tables(scene, N))
        tlink = {}
        for t in scene.torsions:
            tlink.setdefault(t.body, t.link)
        for b, l in tlink.items():
            ang1[b], ang2[b] = ang1[l], ang2[l]
        self.cycle = scene.cycle
        nodes = N * scene.cycle_revolutions
        h = self.cycle / nodes
        J = np.zeros(nodes + 1)
        dJ = np.zeros(nodes + 1)
        for m in scene.masses:
            if m.kind == "mass":
                v, a = vel[m.point], acc[m.point]
                J += m.value * np.sum(v * v, axis=1)
                dJ += 2.0 * m.value * np.sum(v * a, axis=1)
            else:
                J += m.value * ang1[m.link] ** 2
                dJ += 2.0 * m.value * ang1[m.link] * ang2[m.link]
        self.J = _Cubic(h, J, dJ)
        self.bodies = tuple(scene.bodies)
        self.rate = {b: _Cubic(h, ang1[b], ang2[b]) for b in self.bodies}
        self.J_range = (float(J.min()), float(J.max()))
        self.moments = []
        for mo in scene.moments:
            c = mo.centre
            if isinstance(c, str):
                c = dead_centre(scene, "front" if c.startswith("front") else "back")
            self.moments.append((mo.amplitude, mo.window, mo.sigma, float(c),
                                 self.rate[mo.body]))
        self._wm = kernels_for("rk4-python")[0].window_moment

    def wrap(self, theta):
        return theta - self.cycle * math.floor(theta / self.cycle)

    def Q(self, theta: float) -> float:
        """Generalised force of the moments on θ [N·m]."""
        u = self.wrap(theta)
        return sum(self._wm(a, al, sg, c, theta) * rate.at(u)[0]
                   for a, al, sg, c, rate in self.moments)


def reduced_inertia(scene: Scene, theta) -> np.ndarray:
    """J_red(θ) [kg·m²] of the scene's rigid mechanism at first-crank rotations ``theta``."""
    r = _Rigid(scene)
    th = np.asarray(theta, float)
    return r.J(th - r.cycle * np.floor(th / r.cycle))


def simulate_shaft(scene: Scene, shaft: Shaft | None = None, *, flywheel: float | None = None,
                   points: int = 720, startup: bool = True, rtol: float = 1e-10) -> ShaftMotion:
    """The main shaft turned by the motor through the flywheel: steady cycle and start-up.

    Parameters
    ----------
    scene : Scene
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

    Returns
    -------
    ShaftMotion

    Raises
    ------
    MechcircError
        No ``[shaft]``; the motor cannot start the mechanism from rest at the
        start angle, or stalls during the start-up or the steady cycle (the
        message gives the torques); the start-up did not reach the steady
        cycle within ``max_time``.
    """
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    shaft = shaft or scene.shaft
    if shaft is None:
        raise MechcircError(f"{scene.source}: no [shaft] table: give the flywheel and motor "
                            "(docs/scenes.md, \"A dynamic main shaft\")")
    Jf = shaft.flywheel if flywheel is None else float(flywheel)
    if not (math.isfinite(Jf) and Jf >= 0):
        raise MechcircError(f"flywheel must be a number ≥ 0 kg·m², got {flywheel!r}")
    if isinstance(points, bool) or not isinstance(points, int) or points < 16:
        raise MechcircError(f"points must be an integer ≥ 16, got {points!r}")
    rig = _Rigid(scene)
    motor = shaft.motor
    T = motor.torque
    th0 = math.radians(shaft.start_deg)
    cyc = rig.cycle
    notes = []
    if rig.J_range[0] + Jf <= 0:
        raise MechcircError(f"{scene.source}: the shaft has no inertia (flywheel 0 and no mass "
                            "of the mechanism moves with the crank)")
    grid = np.linspace(0.0, cyc, 4 * points, endpoint=False)
    load = np.array([-rig.Q(t) for t in grid])
    peak = float(load.max())
    if motor.peak_torque < peak:
        text = (f"the motor's largest torque {motor.peak_torque:.6g} N·m (breakdown) is below "
                f"the peak load torque {peak:.6g} N·m at θ = "
                f"{math.degrees(grid[int(load.argmax())]):.4g}°: only the flywheel and the "
                "mechanism's inertia carry the shaft through it")
        notes.append("warning: " + text)
        warnings.warn(f"{scene.source}: {text}", ShaftWarning, stacklevel=2)

    tq = motor.scalar_torque

    def accel(theta, w):
        J, dJ = rig.J.at(rig.wrap(theta))
        return (tq(w) + rig.Q(theta) - 0.5 * dJ * w * w) / (Jf + J)

    if startup and tq(0.0) + rig.Q(th0) <= 0:
        raise MechcircError(
            f"{scene.source}: the motor cannot start the mechanism: its starting torque "
            f"T(0) = {tq(0.0):.6g} N·m does not exceed the load torque "
            f"{-rig.Q(th0):.6g} N·m at the start angle {shaft.start_deg:g}°")
    # ---- the steady cycle: speed after one cycle = speed before (in θ: dω/dθ = θ̈/ω)
    scale = max(abs(motor.sync_speed) if motor.kind == "kloss" else max(motor.speeds), 1e-300)

    def stall(th, y):
        return y[0] - 1e-6 * scale
    stall.terminal = True

    def over_cycle(w0, dense=False):
        sol = solve_ivp(lambda th, y: [accel(th, y[0]) / y[0], 1.0 / y[0]], (th0, th0 + cyc),
                        [w0, 0.0], method="DOP853", rtol=rtol, atol=rtol * 1e-3 * scale,
                        events=stall, dense_output=dense)
        return sol

    def gap(w0):
        sol = over_cycle(w0)
        if sol.status == 1:             # stalled within the cycle
            return -w0
        return sol.y[0, -1] - w0

    wmean = _balance(motor, float(np.mean(load)), scale)
    lo, hi = 0.5 * wmean, wmean * 1.02 + 1e-9 * scale
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
        raise MechcircError(
            f"{scene.source}: no steady cycle: the motor (largest torque "
            f"{motor.peak_torque:.6g} N·m) cannot keep the mechanism turning against the mean "
            f"load torque {float(np.mean(load)):.6g} N·m, peak {peak:.6g} N·m, with "
            f"flywheel {Jf:g} kg·m²")
    w0 = brentq(gap, lo, hi, xtol=1e-13 * scale, rtol=4 * np.finfo(float).eps)
    sol = over_cycle(w0, dense=True)
    if sol.status != 0:
        raise SolverError(f"{scene.source}: the steady cycle stalls at θ = "
                          f"{math.degrees(sol.t[-1]):.6g}°", status="stalled")
    th = th0 + np.linspace(0.0, cyc, points + 1)
    w, tt = sol.sol(th)
    period = float(tt[-1])
    th, w, tt = th[:-1], w[:-1], tt[:-1]
    acc = np.array([accel(a, b) for a, b in zip(th, w)])
    u = np.array([rig.wrap(a) for a in th])
    bodies = {b: rig.rate[b](u, slope=True) * w * w + rig.rate[b](u) * acc
              for b in rig.bodies}
    # the extremes of the speed: on the samples, refined on the dense output
    wmin, wmax = _extremes(lambda x: sol.sol(x)[0], th, w)
    mean = cyc / period
    motion = dict(name=scene.name, source=scene.source, flywheel=Jf, theta=th - th0, time=tt,
                  speed=w, acceleration=acc, motor_torque=np.asarray(T(w), float),
                  load_torque=np.array([-rig.Q(a) for a in th]), body_accelerations=bodies,
                  omega_min=wmin, omega_max=wmax, omega_mean=mean,
                  delta=(wmax - wmin) / mean, period=period)
    if not startup:
        return ShaftMotion(**motion, notes=tuple(notes))
    # ---- the start-up from rest, in time
    band = (wmin - 0.01 * mean, wmax + 0.01 * mean)
    ts, ws = [0.0], [0.0]
    t, y = 0.0, np.array([th0, 0.0])
    k = 0
    segments = []
    while True:
        k += 1
        target = th0 + k * cyc

        def reached(_, y, target=target):
            return y[0] - target
        reached.terminal = True

        def stopped(_, y):
            return y[1] + 1e-9 * scale
        stopped.terminal = True
        span = shaft.max_time - t
        s = solve_ivp(lambda _, y: [y[1], accel(y[0], y[1])], (t, t + span), y,
                      method="DOP853", rtol=rtol, atol=rtol * 1e-3 * scale,
                      events=(reached, stopped), dense_output=True)
        tk = np.linspace(t, s.t[-1], 65)[1:]
        ts.extend(tk)
        ws.extend(s.sol(tk)[1])
        segments.append((t, s.sol))
        t, y = float(s.t[-1]), s.y[:, -1]
        if s.status == 1 and s.t_events[1].size:
            raise MechcircError(
                f"{scene.source}: the start-up stalls at t = {t:.4g} s, θ = "
                f"{math.degrees(y[0]):.5g}°: the motor's largest torque "
                f"{motor.peak_torque:.6g} N·m is below the peak load torque {peak:.6g} N·m "
                f"and the flywheel ({Jf:g} kg·m²) does not carry it through")
        if s.status != 1:
            raise MechcircError(
                f"{scene.source}: the start-up did not reach the steady cycle within max_time "
                f"= {shaft.max_time:g} s (speed {y[1]:.6g} rad/s against the steady "
                f"{w0:.6g} rad/s at the cycle's start): raise [shaft] max_time")
        if abs(y[1] - w0) <= 1e-3 * 0.01 * mean:     # settled well inside the band
            break
    ts, ws = np.array(ts), np.array(ws)
    out = np.flatnonzero((ws < band[0]) | (ws > band[1]))
    t_up = 0.0
    if out.size:                  # the last crossing into the band, on the dense output
        i = int(out[-1])
        f = next(sol for t0, sol in reversed(segments) if t0 <= ts[i])
        bound = band[0] if ws[i] < band[0] else band[1]
        t_up = float(brentq(lambda x: f(x)[1] - bound, ts[i], ts[i + 1], xtol=1e-14))
    notes.append(f"steady cycle by shooting (DOP853 in θ, rtol {rtol:g}); start-up from rest "
                 f"over {k} cycles")
    return ShaftMotion(**motion, startup_time=t_up, startup_t=ts, startup_speed=ws,
                       notes=tuple(notes))


def _balance(motor: Motor, torque: float, scale: float) -> float:
    """The speed where the motor gives ``torque`` on its falling branch (a first guess)."""
    from scipy.optimize import brentq

    top = motor.sync_speed if motor.kind == "kloss" else motor.speeds[-1]
    ws = np.linspace(0.0, top, 401)
    tq = motor.torque(ws) - torque
    i = int(np.argmax(motor.torque(ws)))
    for j in range(i, 400):
        if tq[j] > 0 >= tq[j + 1]:
            return float(brentq(lambda w: float(motor.torque(w)) - torque, ws[j], ws[j + 1]))
    return 0.5 * scale


def _extremes(f, th, w):
    """(min, max) of f on the samples, refined by a bounded search between neighbours."""
    from scipy.optimize import minimize_scalar

    out = []
    for sgn, i in ((1.0, int(np.argmin(w))), (-1.0, int(np.argmax(w)))):
        a, b = th[max(i - 1, 0)], th[min(i + 1, th.size - 1)]
        r = minimize_scalar(lambda x, sgn=sgn: sgn * float(f(x)), bounds=(a, b), method="bounded",
                            options={"xatol": 1e-12})
        out.append(sgn * min(r.fun, sgn * w[i]))
    return float(out[0]), float(out[1])
