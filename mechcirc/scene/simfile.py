"""The time-domain tables of a scene file: ``[[moments]]``, ``[simulate]`` and ``[shaft]``
(the motor and flywheel of :mod:`mechcirc.scene.shaft`, read here).

``[[moments]]`` -- a moment on a body that depends on the crank angle (the
beat-up moment of Mrázek's sley, eqs. (5)–(7))::

    [[moments]]
    name = "beatup"
    body = "sley"                # a rigid link or a torsion body
    amplitude = -500.0           # M0 [N·m], positive turning the body counter-clockwise
    window_deg = 10.0            # α: the moment acts while the crank is within α around the centre
    sigma_deg = 10.0             # optional, default α: M = M0 sin(π x / σ), x ∈ [0, α)
    centre = "front-dead-centre" # or "back-dead-centre", or a crank rotation from the pose [deg]

x = φ − centre + α/2 (mod 2π), φ the crank link's own rotation from the pose
(in the deformed motion: the crank's part, not the driven shaft).

``[simulate]`` -- defaults of ``mechcirc simulate SCENE.toml`` (all optional)::

    [simulate]
    omega = 100.0                # crank shaft speed [rad/s]; default the crank's omega
    revolutions = 5              # the last one is tabulated
    start_deg = 0.0              # crank rotation from the pose at t = 0 (rigid state)
    steps_per_period = 50        # RK4 steps per period of the fastest linearised mode
    points = 7200                # output points per revolution
    omega_ripple = {amplitude = 0.05, harmonic = 2}   # optional: a crank speed profile
    [simulate.aliases]           # more output names: NAME = "BODY.acceleration", …
    eps2P = "crank.acceleration"

``omega_ripple`` -- the crank does not turn at constant speed but with
ω(t) = Ω (1 + a cos(k Ω t)): ``amplitude`` a in [0, 1) (relative to Ω, so the
crank never stops or turns back), ``harmonic`` k a whole number ≥ 1 (k ripples per
revolution, so the crank still turns once per period 2π/Ω).  The crank angle is
θ = θs + Ω t + (a/k) sin(k Ω t), and every rigid part follows it with
θ̈ = −a k Ω² sin(k Ω t) (``docs/scenes.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cache, cached_property
from typing import Any

from .._memo import Memos
from ..errors import MechcircError
from ..sources import Table, brief, check_keys, checked_number, finite_number, is_name, located
from ..units import in_si

__all__ = ["Moment", "SimulateSettings", "parse_moments", "parse_simulate",
           "Motor", "Shaft", "kloss_motor", "table_motor", "parse_shaft"]

_RIPPLE_FORM = "omega_ripple = {amplitude = 0.05, harmonic = 2}"
#: The keys of ``[[moments]]`` and ``[simulate]`` (see :class:`mechcirc.sources.Table`).
_MOMENTS = Table("moments", {"name": "element name (default M_BODY)",
                             "body": "a rigid link or torsion body", "amplitude": "[N·m]",
                             "window_deg": "[deg], < 360", "sigma_deg": "[deg]",
                             "centre": "a dead centre or a crank rotation [deg]"}, array=True)
_SIMULATE = Table("simulate", {"omega": "[rad/s]", "revolutions": "≥ 1", "start_deg": "[deg]",
                               "steps_per_period": "> 0", "points": "≥ 16",
                               "omega_ripple": _RIPPLE_FORM, "aliases": "[simulate.aliases]"})


@dataclass(frozen=True)
class Moment:
    """A crank-angle-dependent moment on ``body`` (half sine over a window)."""

    name: str
    body: str
    amplitude: float
    window: float             # α [rad]
    sigma: float              # σ [rad]
    centre: str | float       # "front-dead-centre", "back-dead-centre" or a rotation [rad]


@dataclass(frozen=True)
class SimulateSettings:
    """Defaults of the time-domain run (``[simulate]``); None: the built-in default."""

    omega: float | None = None
    revolutions: int | None = None
    start_deg: float = 0.0
    steps_per_period: float | None = None
    points: int | None = None
    aliases: dict = field(default_factory=dict)
    #: (amplitude a, harmonic k): crank speed Ω (1 + a cos(k Ω t)); None: constant.
    omega_ripple: tuple | None = None


def parse_moments(text, source, table, scene) -> tuple:
    """The ``[[moments]]`` entries, checked against the scene's bodies.

    Parameters
    ----------
    text, source : str
        The file's text and name, for errors.
    table : list of dict or None
    scene : Scene

    Returns
    -------
    tuple of Moment
    """
    if table is None:
        return ()
    if not isinstance(table, list) or not all(isinstance(x, dict) for x in table):
        raise located(text, source, "moments must be an array of tables [[moments]]", None,
                   "moments")
    bodies = scene.bodies
    taken = {m.name for m in scene.masses} | {x.name for x in (*scene.elastic, *scene.torsions,
                                                                 *scene.loads)}
    out = []
    for n, m in enumerate(table):
        check_keys(text, source, _MOMENTS, m, n)
        body = m.get("body")
        if not isinstance(body, str) or body not in bodies:
            raise located(text, source, f"[[moments]] #{n + 1}: body {body!r} is not a rigid link "
                       "or torsion body", "moments", "body" if "body" in m else "amplitude",
                       occurrence=n, value=body, choices=bodies)
        name = m.get("name", f"M_{body}")
        if not is_name(name) or name in taken:
            raise located(text, source, f"[[moments]] #{n + 1}: name {name!r} is not a valid "
                       "unused name", "moments", "name" if "name" in m else "body",
                       occurrence=n, expected="an identifier not used by another element")
        taken.add(name)
        amp, alpha, sigma = _moment_numbers(text, source, m, n, name)
        centre = m.get("centre", "front-dead-centre")
        if isinstance(centre, str):
            if centre not in ("front-dead-centre", "back-dead-centre"):
                raise located(text, source, f"centre {centre!r} of {name!r} is unknown", "moments",
                           "centre", occurrence=n, expected='"front-dead-centre", '
                           '"back-dead-centre" or a crank rotation from the pose [deg]')
        else:
            centre = math.radians(checked_number(text, source, centre, f"centre of {name!r} [deg]",
                                                 "moments", "centre", n))
        out.append(Moment(name, body, amp, math.radians(alpha), math.radians(sigma), centre))
    return tuple(out)


def _moment_numbers(text, source, m, n, name) -> tuple[float, float, float]:
    """amplitude [N·m], window_deg and sigma_deg [deg] of [[moments]] entry ``n`` named
    ``name``, checked."""
    amp = checked_number(text, source, m.get("amplitude"), f"amplitude of {name!r} [N·m]",
                         "moments", "amplitude" if "amplitude" in m else "body", n)
    alpha = checked_number(text, source, m.get("window_deg"), f"window_deg of {name!r} [deg]",
                           "moments", "window_deg" if "window_deg" in m else "body", n,
                           positive=True)
    if alpha >= 360:
        raise located(text, source, f"window_deg of {name!r} must be < 360, got {alpha!r}",
                      "moments", "window_deg", occurrence=n, expected="0 < window_deg < 360")
    sigma = checked_number(text, source, m.get("sigma_deg", alpha),
                           f"sigma_deg of {name!r} [deg]", "moments", "sigma_deg", n,
                           positive=True)
    return amp, alpha, sigma


def parse_simulate(text, source, table, scene) -> SimulateSettings:
    """The optional ``[simulate]`` table.

    Parameters
    ----------
    text, source : str
        The file's text and name, for errors.
    table : dict or None
    scene : Scene

    Returns
    -------
    SimulateSettings
    """
    if table is None:
        return SimulateSettings()
    if not isinstance(table, dict):
        raise located(text, source, "simulate must be a table [simulate]", None, "simulate")
    check_keys(text, source, _SIMULATE, table)
    kw: dict[str, Any] = {}
    for k, v in table.items():
        if k == "aliases":
            if not isinstance(v, dict):
                raise located(text, source, "[simulate] aliases must be a table "
                              "[simulate.aliases]", "simulate", "aliases",
                              expected='eps2P = "crank.acceleration"')
            for a, b in v.items():      # located at the first bad alias
                if not (is_name(a) and isinstance(b, str) and "." in b):
                    raise located(text, source, "[simulate.aliases] maps names to "
                                  f"\"THING.quantity\" strings, got {a} = {b!r}",
                                  "simulate.aliases", a,
                                  expected='eps2P = "crank.acceleration"')
            kw["aliases"] = dict(v)
        elif k in ("omega", "steps_per_period", "start_deg"):
            if k == "omega":        # "600 rpm", "10 Hz"
                v = in_si(text, source, v, "omega", "simulate", k)
            kw[k] = checked_number(text, source, v, f"[simulate] {k}", "simulate", k,
                                   positive=k != "start_deg")
        elif k in ("revolutions", "points"):
            if isinstance(v, bool) or not isinstance(v, int) or v < (1 if k == "revolutions"
                                                                      else 16):
                raise located(text, source, f"[simulate] {k} must be an integer ≥ "
                           f"{1 if k == 'revolutions' else 16}, got {v!r}", "simulate", k)
            kw[k] = v
        elif k == "omega_ripple":
            kw[k] = _ripple(text, source, v)
    return SimulateSettings(**kw)


def _ripple(text, source, v):
    """``omega_ripple = {amplitude = a, harmonic = k}`` → (a, k), checked."""
    if not isinstance(v, dict):
        raise located(text, source, f"[simulate] omega_ripple must be an inline table, got "
                   f"{brief(v)}", "simulate", "omega_ripple", expected=_RIPPLE_FORM)
    extra = set(v) - {"amplitude", "harmonic"}
    if extra or "amplitude" not in v:
        what = (f"unknown key {sorted(extra)[0]!r}" if extra else "missing amplitude")
        raise located(text, source, f"[simulate] omega_ripple: {what}", "simulate",
                   "omega_ripple", expected=_RIPPLE_FORM)
    a = v["amplitude"]
    if not (finite_number(a) and 0 <= a < 1):
        raise located(text, source, f"[simulate] omega_ripple amplitude must be a number in "
                   f"[0, 1) (relative to the crank speed), got {brief(a)}", "simulate",
                   "omega_ripple", expected="0 <= amplitude < 1")
    k = v.get("harmonic", 1)
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise located(text, source, f"[simulate] omega_ripple harmonic must be a whole number "
                   f">= 1 (ripples per revolution), got {brief(k)}", "simulate",
                   "omega_ripple", expected="harmonic = 1, 2, 3, ...")
    return float(a), int(k)


def override_run(source: str, sim: SimulateSettings, key: str, value) -> SimulateSettings:
    """``sim`` with ``omega``, ``omega_ripple.amplitude`` or ``.harmonic`` set to ``value``
    (``--set``, named by ``source``), checked by the [simulate] reader's rules."""
    if key == "omega":
        return replace(sim, omega=parse_simulate("", source, {"omega": value}, None).omega)
    a, k = sim.omega_ripple or (0.0, 1)
    whole = isinstance(value, float) and value.is_integer()     # the reader takes harmonic = 3
    ripple = {"amplitude": a, "harmonic": k, key.partition(".")[2]: int(value) if whole else value}
    return replace(sim, omega_ripple=_ripple("", source, ripple))


def override_moment(source: str, old: Moment, fld: str, value) -> Moment:
    """The moment ``old`` with ``amplitude``, ``window_deg`` or ``sigma_deg`` set to ``value``
    (``--set``, named by ``source``), checked by the [[moments]] reader's rules (a window
    that was its own sigma keeps sigma equal to it)."""
    tied = old.sigma == old.window
    entry = {"amplitude": old.amplitude, "window_deg": math.degrees(old.window), fld: value}
    if not tied:
        entry.setdefault("sigma_deg", math.degrees(old.sigma))
    amp, alpha, sigma = _moment_numbers("", source, entry, 0, old.name)
    if fld == "amplitude":
        return replace(old, amplitude=amp)
    if fld == "window_deg":
        return replace(old, window=math.radians(alpha), sigma=math.radians(alpha) if tied
                       else old.sigma)
    return replace(old, sigma=math.radians(sigma))


# ------------------------------------------------------------------ [shaft]
@dataclass(frozen=True)
class Motor(Memos):
    """A motor's torque–speed characteristic T(ω) [N·m], referred to the main shaft.

    ``kind`` is ``"kloss"`` (``sync_speed`` ω_s [rad/s], ``breakdown_torque`` T_b
    [N·m], ``breakdown_slip`` s_b) or ``"table"`` (``speeds`` [rad/s] increasing,
    ``torques`` [N·m]; linear between points and beyond the ends along the end
    segments).
    """

    kind: str
    sync_speed: float = math.nan
    breakdown_torque: float = math.nan
    breakdown_slip: float = math.nan
    speeds: tuple = ()
    torques: tuple = ()

    @cached_property
    def params(self):
        """The characteristic as the shaft kernel's array (``motor_torque`` in
        :mod:`._motion_kernels`, where the law is written)."""
        import numpy as np

        if self.kind == "kloss":
            return np.array([0.0, self.sync_speed, self.breakdown_torque, self.breakdown_slip])
        return np.array([1.0, 0.0, 0.0, 0.0, len(self.speeds), *self.speeds, *self.torques])

    def torque(self, omega):
        """T(ω) [N·m] at shaft speed(s) ``omega`` [rad/s]."""
        import numpy as np

        w = np.asarray(omega, float)
        P, law = self.params, _motor_law()
        return np.array([law(P, x) for x in w.ravel()]).reshape(w.shape)

    def scalar_torque(self, w: float) -> float:
        """T(ω) at one speed (the integrators' fast path)."""
        return _motor_law()(self.params, w)

    @property
    def peak_torque(self) -> float:
        """The largest torque on 0 ≤ ω ≤ (ω_s or the table's last speed) [N·m]."""
        if self.kind == "kloss":
            return self.breakdown_torque if self.breakdown_slip <= 1 else float(self.torque(0.0))
        return float(max(self.torques))


@cache
def _motor_law():
    """The motor law of the shaft kernel, as plain Python (a scalar call without numba's
    dispatch; the kernels' one Python copy, :func:`._motion_kernels.load_python`)."""
    from ._motion_kernels import load_python

    return load_python().motor_torque


def kloss_motor(*, sync_speed: float, breakdown_torque: float,
                breakdown_slip: float | None = None, rated_power: float | None = None,
                rated_speed: float | None = None) -> Motor:
    """An induction motor by Kloss's formula T = 2 T_b / (s/s_b + s_b/s), s = (ω_s − ω)/ω_s.

    Give ``breakdown_slip`` s_b, or the rated point (``rated_power`` P_n [W],
    ``rated_speed`` ω_n [rad/s]): then T_n = P_n/ω_n, s_n = (ω_s − ω_n)/ω_s, and
    Kloss's formula through the rated point gives s_b = s_n (λ + √(λ² − 1)),
    λ = T_b/T_n (the stable branch: s_n < s_b).

    Parameters
    ----------
    sync_speed : float
        ω_s [rad/s].
    breakdown_torque : float
        T_b [N·m].
    breakdown_slip : float, optional
    rated_power, rated_speed : float, optional
        [W], [rad/s].

    Returns
    -------
    Motor
        A ``"kloss"`` motor, with s_b (given or from the rated point).

    Raises
    ------
    MechcircError
        A non-positive value, both or neither of s_b and the rated point,
        ω_n ≥ ω_s, or T_b ≤ T_n (names the values).
    """
    for what, v in (("sync_speed", sync_speed), ("breakdown_torque", breakdown_torque)):
        if not (finite_number(v) and v > 0):
            raise MechcircError(f"motor {what} must be a number > 0, got {v!r}")
    if (breakdown_slip is None) == (rated_power is None or rated_speed is None):
        raise MechcircError("a Kloss motor needs breakdown_slip, or rated_power and "
                            "rated_speed (not both)")
    if breakdown_slip is None:
        if not (finite_number(rated_power) and rated_power > 0 and finite_number(rated_speed)
                and 0 < rated_speed < sync_speed):
            raise MechcircError(f"the rated point needs rated_power > 0 and 0 < rated_speed < "
                                f"sync_speed = {sync_speed:g} rad/s, got rated_power = "
                                f"{rated_power!r} W, rated_speed = {rated_speed!r} rad/s")
        tn = rated_power / rated_speed
        sn = (sync_speed - rated_speed) / sync_speed
        lam = breakdown_torque / tn
        if lam <= 1:
            raise MechcircError(f"the breakdown torque T_b = {breakdown_torque:g} N·m must "
                                f"exceed the rated torque T_n = P/ω_n = {tn:.6g} N·m")
        breakdown_slip = sn * (lam + math.sqrt(lam * lam - 1.0))
    if not (finite_number(breakdown_slip) and breakdown_slip > 0):
        raise MechcircError(f"motor breakdown_slip must be a number > 0, got {breakdown_slip!r}")
    return Motor("kloss", float(sync_speed), float(breakdown_torque), float(breakdown_slip))


def table_motor(speeds, torques) -> Motor:
    """A motor given as a table of torque [N·m] against speed [rad/s] (linear between points).

    Parameters
    ----------
    speeds, torques : sequence of float

    Returns
    -------
    Motor
        A ``"table"`` motor, linear between the points.

    Raises
    ------
    MechcircError
        Fewer than two points, unequal lengths, speeds not increasing, a value
        not finite.
    """
    sp, tq = list(speeds), list(torques)
    if len(sp) < 2 or len(sp) != len(tq) or not all(map(finite_number, sp + tq)):
        raise MechcircError(f"a motor table needs two or more finite (speed, torque) pairs of "
                            f"equal length, got {len(sp)} speeds and {len(tq)} torques")
    if any(b <= a for a, b in zip(sp, sp[1:])):
        raise MechcircError(f"the motor table's speeds must increase, got {sp}")
    return Motor("table", speeds=tuple(map(float, sp)), torques=tuple(map(float, tq)))


@dataclass(frozen=True)
class Shaft:
    """The ``[shaft]`` table: flywheel J_f [kg·m²], motor, start angle [deg], max_time [s]."""

    flywheel: float
    motor: Motor
    start_deg: float = 0.0
    max_time: float = 120.0


_KEYS = {"flywheel": "J_f [kg·m²] on the main shaft, ≥ 0", "motor": '"kloss" or "table"',
         "sync_speed": "ω_s [rad/s]", "breakdown_torque": "T_b [N·m]",
         "breakdown_slip": "s_b", "rated_power": "[W]", "rated_speed": "[rad/s]",
         "speeds": "[rad/s], increasing", "torques": "[N·m]",
         "start_deg": "crank rotation at rest [deg]", "max_time": "[s], > 0"}


def parse_shaft(text: str, source: str, table, scene) -> Shaft:
    """The scene file's ``[shaft]`` table (see the module docstring); errors at file:line:col.

    Parameters
    ----------
    text, source : str
        The file's text and name, for errors.
    table : dict
    scene : Scene

    Returns
    -------
    Shaft

    Raises
    ------
    NetlistError
        An unknown key, a missing or bad value, an inconsistent motor.
    """
    if not isinstance(table, dict):
        raise located(text, source, "shaft must be a table [shaft]", None, "shaft")
    check_keys(text, source, Table("shaft", _KEYS), table)

    def num(key, default=None, positive=True, zero=False):
        return checked_number(text, source, table.get(key, default), f"[shaft] {key}", "shaft",
                              key if key in table else next(iter(table), key),
                              positive=positive, allow_zero=zero,
                              expected=f"{key} = … ({_KEYS[key]})")

    # checked in this order: the flywheel, the motor, the start angle, max_time
    return Shaft(num("flywheel", 0.0, zero=True), _shaft_motor(text, source, table, num),
                 num("start_deg", 0.0, positive=False), num("max_time", 120.0))


def _shaft_motor(text: str, source: str, table: dict, num):
    """The ``[shaft]`` motor: its kind checked against the keys given, then built (``num``
    reads a checked number)."""
    kind = table.get("motor")
    if kind not in ("kloss", "table"):
        raise located(text, source, f"[shaft] motor must be \"kloss\" or \"table\", got "
                      f"{brief(kind)}", "shaft", "motor" if "motor" in table else
                      next(iter(table), "motor"), expected='motor = "kloss" or "table"')
    other = ("speeds", "torques") if kind == "kloss" else (
        "sync_speed", "breakdown_torque", "breakdown_slip", "rated_power", "rated_speed")
    for k in other:
        if k in table:
            raise located(text, source, f"[shaft] {k} does not apply to motor = {kind!r}",
                          "shaft", k)
    try:
        if kind == "kloss":
            opt = {k: num(k) for k in ("breakdown_slip", "rated_power", "rated_speed")
                   if k in table}
            return kloss_motor(sync_speed=num("sync_speed"),
                               breakdown_torque=num("breakdown_torque"), **opt)
        for k in ("speeds", "torques"):
            if not isinstance(table.get(k), list):
                raise located(text, source, f"[shaft] a motor table needs {k} = [...]", "shaft",
                              k if k in table else "motor", expected=f"{k} = [{_KEYS[k]}]")
        return table_motor(table["speeds"], table["torques"])
    except MechcircError as exc:
        if hasattr(exc, "line"):
            raise
        raise located(text, source, f"[shaft] {exc}", "shaft", "motor") from None
