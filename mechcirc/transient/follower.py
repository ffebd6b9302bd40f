"""A cam follower held on its cam by a preloaded spring: its motion, contact force and jump.

The follower (mass m, spring k with preload F₀ at the bottom of the lift,
damper c to the frame) rides on the cam through a contact of stiffness k_c
that can open: the clearance law of :mod:`._kernels` (``spring ... backlash=``)
with one flank in use and the other out of reach.  Coordinates: y the
follower's rise from its rest on the base circle, s(θ) the cam's lift
(:class:`~mechcirc.motion_laws.Motion`), θ = Ωt.  In contact

    m ÿ + c ẏ + k y + F₀ = N,      N = k_c (s − y) (+ its damping),

and the contact opens where N would become negative.

**Jump speed** (closed form, rigid follower, y = s): the contact force the
cam must give is N(θ) = F₀ + k s + cΩ s' + mΩ² s'' (s' = ds/dθ); it first
reaches zero at the shaft speed Ω* where min_θ N = 0.  Without damping
Ω*² = min over s'' < 0 of (F₀ + k s)/(−m s'') — the largest deceleration of
the follower against what its spring can give there (Norton, *Design of
Machinery*, ch. 8.9 *follower jump*).  :func:`jump_speed` finds the minimum
over θ by a fine grid refined with bounded Brent, and Ω* (damped) by
``brentq``.

**The circuit.**  In the netlist the preload is carried by the start: the
spring k to the frame is at 0 where it is free, so the follower starts at
z₀ = F₀/k; the contact, a clearance of total gap G between the cam node and
the follower, pushes when x_cam − x_f > G/2, so the cam node starts at
X₀ = z₀ + G/2 + F₀/k_c (``.ic`` lines).  Then the start is the static
equilibrium with both forces F₀, and the other flank of the gap
(x_f − x_cam > G/2) is G away: :func:`follower` takes G/2 = max s + z₀ and
refuses a run that reaches it; G/2 = max s + z₀ keeps the coordinates
small, so the contact's deflection F₀/k_c is not lost to their rounding.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import MechcircError
from ..units import convert_frequency

__all__ = ["FollowerResult", "follower", "follower_circuit", "jump_speed", "separation_speed",
           "least_sample"]

#: Grid of the minimum over the cam angle (refined by Brent between its points).
GRID = 4096


def _min_over_angle(f):
    """(min f(θ), θ) over one turn: a grid of GRID points, then bounded Brent around the best."""
    from scipy.optimize import minimize_scalar

    grid = np.linspace(0.0, 2 * math.pi, GRID, endpoint=False)
    values = f(grid)
    i = int(np.argmin(values))
    step = 2 * math.pi / GRID
    res = minimize_scalar(lambda t: float(f(np.array([t]))[0]),
                          bounds=(grid[i] - step, grid[i] + step), method="bounded",
                          options={"xatol": 1e-13})
    return (float(res.fun), float(res.x) % (2 * math.pi)) if res.fun <= values[i] else \
        (float(values[i]), float(grid[i]))


def _check(**values):
    """Each value a finite number, > 0 (mass, preload, contact) or >= 0 (the others)."""
    for name, v in values.items():
        positive = name in ("mass", "preload", "contact")
        if not (isinstance(v, (int, float)) and math.isfinite(v)
                and (v > 0 if positive else v >= 0)):
            raise MechcircError(f"the follower's {name} must be a finite number "
                                f"{'> 0' if positive else '>= 0'}, got {v!r}")


def jump_speed(motion, mass: float, spring: float, preload: float,
               damping: float = 0.0) -> tuple[float, float]:
    """The shaft speed at which a rigid follower's contact force first reaches zero.

    Parameters
    ----------
    motion : Motion
        The cam's lift s(θ) over one turn [m].
    mass, spring, preload, damping : float
        m [kg], k [N/m], F₀ [N] (the spring's force at s = 0) and c [N·s/m].

    Returns
    -------
    rpm, angle_deg : float
        The jump speed [rev/min] and the cam angle [deg] where N first reaches 0.

    Examples
    --------
    >>> from mechcirc.motion_laws import cam_cycle
    >>> m = cam_cycle("cycloidal", 100, 80, 80, 0.02)
    >>> rpm, angle = jump_speed(m, 0.5, 5e3, 50.0)      # early in the return
    >>> round(rpm, 3), round(angle, 3)
    (629.138, 201.639)
    """
    from scipy.optimize import brentq

    _check(mass=mass, spring=spring, preload=preload, damping=damping)

    def need(theta, omega):     # N(θ; Ω) = F₀ + k s + cΩ s' + mΩ² s''
        s, ds, dds = motion.evaluate(theta)
        return preload + spring * s + damping * omega * ds + mass * omega ** 2 * dds

    low, _ = _min_over_angle(lambda t: need(t, 0.0))
    if low <= 0:
        raise MechcircError(f"the contact force is {low:g} N at rest: the preload does not "
                            "hold the follower on the cam even at zero speed")
    if damping == 0.0:
        # Ω² = min (F₀ + k s)/(−m s'') over s'' < 0: N(θ; Ω) ∝ that ratio − Ω² there.
        def ratio(t):
            s, _, dds = motion.evaluate(t)
            with np.errstate(divide="ignore", invalid="ignore"):
                r = (preload + spring * s) / (-mass * dds)
            return np.where(dds < 0, r, np.inf)
        w2, theta = _min_over_angle(ratio)
        omega = math.sqrt(w2)
    else:
        def lowest(omega):
            return _min_over_angle(lambda t: need(t, omega))[0]
        hi = 1.0
        while lowest(hi) > 0:
            hi *= 2
            if hi > 1e12:
                raise MechcircError("the contact force stays positive at every speed "
                                    "below 1e12 rad/s")
        omega = brentq(lowest, hi / 2 if hi > 1 else 0.0, hi, xtol=1e-14, rtol=1e-15)
        theta = _min_over_angle(lambda t: need(t, omega))[1]
    return convert_frequency(omega, "rad/s", "rpm"), math.degrees(theta)


def follower_circuit(motion, mass, spring, preload, damping=0.0, *, contact,
                     contact_damping=0.0):
    """The follower as a :class:`~mechcirc.circuit.Circuit` (nodes ``cam`` and ``f``).

    Elements ``kc`` (the contact: a clearance), ``m``, ``k``, ``c`` (when
    damping > 0); the ``.ic`` start is the static equilibrium with both the
    spring and the contact carrying the preload (module text).

    Parameters
    ----------
    motion : Motion
        The lift s(θ) [m].
    mass, spring, preload, damping : float
        As :func:`jump_speed`.
    contact, contact_damping : float
        Contact stiffness [N/m] and damping [N·s/m].

    Returns
    -------
    Circuit
    """
    from ..netlist import parse

    _check(mass=mass, spring=spring, preload=preload, damping=damping, contact=contact,
           contact_damping=contact_damping)
    s = motion.evaluate(np.linspace(0, 2 * math.pi, GRID, endpoint=False))[0]
    z0 = preload / spring
    half = float(np.abs(s).max()) + z0
    x0 = z0 + half + preload / contact
    text = (f"drive cam cam 0 velocity=1\n"
            f"spring kc cam f {contact!r} backlash={2 * half!r} damping={contact_damping!r}\n"
            f"mass m f 0 {mass!r}\nspring k f 0 {spring!r}\n"
            + (f"damper c f 0 {damping!r}\n" if damping > 0 else "")
            + f".ic cam x={x0!r}\n.ic f x={z0!r}\n")
    c = parse(text)
    return dataclasses.replace(c, name="follower",
                               drive=dataclasses.replace(c.drive, motion=motion))


@dataclass
class FollowerResult:
    """A cam follower's run (plain data).

    Attributes
    ----------
    rpm, omega_shaft : float
        Shaft speed [rev/min], Ω [rad/s].
    angle_deg : ndarray
        Shaft angle Ωt [deg] of each sample (growing past 360 after one turn).
    lift, rise : ndarray
        The cam's lift s(θ) and the follower's rise y from its rest [m].
    contact_force : ndarray
        The contact force N [N] (0 while open).
    min_contact, min_contact_angle_deg : float
        The smallest contact force the contact spring would carry, k_c(x_cam −
        x_f − G/2), over the run (negative once the follower has left the cam),
        refined between samples by a parabola, and where [deg].
    separations : list of Separation
        Each opening: cam angle, duration, impact velocity.
    transient : TransientResult
        The whole run.
    """

    rpm: float
    omega_shaft: float
    angle_deg: np.ndarray
    lift: np.ndarray
    rise: np.ndarray
    contact_force: np.ndarray
    min_contact: float
    min_contact_angle_deg: float
    separations: list = field(default_factory=list)
    transient: object = None


def follower(motion, rpm: float, mass: float, spring: float, preload: float,
             damping: float = 0.0, *, contact: float, contact_damping: float = 0.0,
             revolutions: float = 1.0, dt: float | None = None,
             rtol: float = 1e-10) -> FollowerResult:
    """Simulate the follower on its cam from rest on the base circle at θ = 0.

    Parameters
    ----------
    motion : Motion
        The lift s(θ) [m].
    rpm : float
        Shaft speed [rev/min].
    mass, spring, preload, damping : float
        As :func:`jump_speed`.
    contact, contact_damping : float
        Contact stiffness k_c [N/m] and damping [N·s/m] (the clearance law's).
    revolutions : float
        How many turns to run.
    dt : float, optional
        Output step [s] (default 1/7200 of a turn).
    rtol : float
        Tolerance of the clearance integrator (:func:`~mechcirc.transient.transient`).

    Returns
    -------
    FollowerResult
    """
    from .simulate import transient

    circuit = follower_circuit(motion, mass, spring, preload, damping, contact=contact,
                               contact_damping=contact_damping)
    if not (isinstance(revolutions, (int, float)) and 0 < revolutions <= 1e4):
        raise MechcircError(f"revolutions must be > 0 and at most 1e4, got {revolutions!r}")
    period = 60 / rpm if isinstance(rpm, (int, float)) and rpm > 0 else math.nan
    r = transient(circuit, revolutions * period, dt if dt is not None else period / 7200,
                  rpm=rpm, rtol=rtol)
    omega = convert_frequency(rpm, "rpm", "rad/s")
    lo, ang = _least_contact(r, circuit.elements[0], omega)
    theta, z0 = omega * r.time, preload / spring
    return FollowerResult(rpm=float(rpm), omega_shaft=omega, angle_deg=np.degrees(theta),
                          lift=motion.evaluate(theta)[0], rise=r.x[:, r.nodes.index("f")] - z0,
                          contact_force=r.element_force("kc"), min_contact=lo,
                          min_contact_angle_deg=math.degrees(ang) % 360.0,
                          separations=list(r.separations), transient=r)


def _least_contact(r, kc, omega) -> tuple:
    """(least contact force [N], its shaft angle [rad]) of the run ``r``: the least sample,
    refined by the parabola through it and its neighbours; the far flank refused."""
    i_cam, i_f = r.nodes.index("cam"), r.nodes.index("f")
    half, e = kc.backlash / 2, r.x[:, i_cam] - r.x[:, i_f]
    if np.any(e < -half):
        raise MechcircError("the follower left the cam by more than the model's reach "
                            f"({2 * half:g} m): the far flank of the contact was hit")
    lo, at = least_sample(kc.value * (e - half))
    return lo, omega * (r.time[0] + at * (r.time[1] - r.time[0]))


def least_sample(values, periodic: bool = False) -> tuple:
    """The least sample refined by the parabola through it and its neighbours.

    Parameters
    ----------
    values : array_like
        Samples, equally spaced.
    periodic : bool
        The last sample's neighbour is the first.

    Returns
    -------
    tuple of float
        (least value, where, in samples).
    """
    v = np.asarray(values, dtype=float)
    i = int(np.argmin(v))
    lo, at = float(v[i]), float(i)
    if periodic or 0 < i < v.size - 1:
        a, b, c = v[i - 1], v[i], v[(i + 1) % v.size]
        den = a - 2 * b + c
        if den > 0:
            off = 0.5 * (a - c) / den
            lo, at = float(b - 0.25 * (a - c) * off), i + off
    return lo, at

def separation_speed(motion, mass, spring, preload, damping=0.0, *, contact,
                     contact_damping=0.0, bracket, rtol=1e-10, dt=None,
                     xtol=1e-8) -> float:
    """The shaft speed [rev/min] at which the simulated follower first leaves the cam.

    The root in ``bracket`` = (rpm_lo, rpm_hi) of the least contact force over
    the first turn (:attr:`FollowerResult.min_contact`), by ``brentq`` to the
    relative tolerance ``xtol``: the simulated counterpart of :func:`jump_speed`.
    The least force has a kink at the root (beyond it the follower flies), so
    brentq proceeds about as bisection does (some 20 runs).  Its resolution is
    the rounding of the contact's deflection: k_c × ~1e-16 m of position
    (1e-5 N at k_c = 1e11 N/m, about 1e-7 of the speed in the example).

    Parameters
    ----------
    motion, mass, spring, preload, damping, contact, contact_damping
        As :func:`follower`, which this runs.
    bracket : tuple of (float, float)
        [rev/min].
    rtol : float
        Of the integration.
    dt : float, optional
        Output step [s].
    xtol : float
        Of the root.

    Returns
    -------
    float
    """
    from scipy.optimize import brentq

    def least(rpm):
        return follower(motion, rpm, mass, spring, preload, damping, contact=contact,
                        contact_damping=contact_damping, rtol=rtol, dt=dt).min_contact / preload

    lo, hi = bracket
    if not least(lo) > 0 > least(hi):
        raise MechcircError(f"the follower does not leave the cam between {lo:g} and {hi:g} "
                            "rpm only (give a bracket with contact at the low end and "
                            "separation at the high end)")
    return brentq(least, lo, hi, rtol=xtol, xtol=1e-300)
