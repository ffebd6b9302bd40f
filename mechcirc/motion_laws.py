"""Motions over one revolution of the main shaft: the standard cam laws and tables.

A :class:`Motion` is a displacement x(θ) [m or rad] over one turn of the main
shaft, θ ∈ [0, 2π) [rad], written piecewise in closed form: on piece i,
with τ = θ − θᵢ,

    x(τ) = Σₘ aₘ τᵐ (m ≤ 5) + B sin(w τ + φ).

Every standard cam law is of this form, and so is a periodic cubic spline
through a table, so one representation gives x, dx/dθ and d²x/dθ² exactly and
the Fourier coefficients of dx/dθ exactly (:meth:`Motion.fourier`).

The laws (normalised rise s(u) from 0 to 1 for u ∈ [0, 1]; a rise of stroke h
over the cam angle β is x = h·s(θ/β), so dx/dθ = h·s'/β and d²x/dθ² = h·s''/β²):

=====================  ======================================  =========  =========
law                    acceleration s''(u)                      max s'     max |s''|
=====================  ======================================  =========  =========
``harmonic``           (π²/2) cos πu                            π/2        π²/2
``cycloidal``          2π sin 2πu                               2          2π
``modified_sine``      C sin 4πu, C cos(4π/3 (u−1/8)),          1.760      5.528
                       −C cos 4π(u−7/8) at u = 1/8, 7/8
``modified_trapezoid`` C sin 4πu, C, C cos 4π(u−3/8), −C,       2.000      4.888
                       −C cos 4π(u−7/8) at u = 1/8, 3/8, 5/8,
                       7/8
``polynomial_345``     60u − 180u² + 120u³ (s = 10u³−15u⁴+6u⁵)  15/8       10/√3
=====================  ======================================  =========  =========

C is fixed by s(1) = 1 (the pieces are integrated in closed form, the
constants carried from piece to piece).  Mechanism design texts (Norton,
*Design of Machinery*, ch. 8; Rothbart, *Cam Design Handbook*) tabulate the
same laws and coefficients.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError, NetlistError
from .sources import brief, csv_rows, did_you_mean, read_source, real_number, summary_repr

__all__ = [
    "LAWS",
    "MAX_LIFT",
    "PERIODIC_TOLERANCE",
    "Motion",
    "cam_cycle",
    "law",
    "motion_table",
    "read_motion_table",
]

#: Names of the standard laws.
LAWS = ("harmonic", "cycloidal", "modified_sine", "modified_trapezoid", "polynomial_345")

#: A table's two ends must meet within this fraction of its displacement range
#: (or 1e-12 m when the table does not move at all).
PERIODIC_TOLERANCE = 1e-6

#: The largest |stroke| of a law and |displacement| of a table [m or rad].  The
#: drive's velocity, force and Fourier sums multiply it by powers of the shaft
#: speed and the harmonic number: 1e308 overflows float64 in them, 1e100 leaves
#: 200 decades for those factors.
MAX_LIFT = 1e100

_TAU = 2 * math.pi
_DEG = 6  # polynomial coefficients per piece: τ⁰ … τ⁵
_FOURIER_BLOCK = 1 << 20  # (harmonic, piece end) pairs of Motion.fourier's scratch at once


# ------------------------------------------------------------------ the laws
def _integrate(pieces) -> tuple[list, float]:
    """Displacement pieces ``(u0, a[6], B, w, φ)`` and the end displacement from
    acceleration pieces ``(u0, u1, p[4], B, w, φ)`` (s'' = Σ pₘ tᵐ + B sin(w t + φ),
    t = u − u0), with s and s' continuous from s(0) = s'(0) = 0."""
    out, s0, v0 = [], 0.0, 0.0
    for u0, u1, p, B, w, phi in pieces:
        a = [s0, v0] + [0.0] * (_DEG - 2)
        for m, pm in enumerate(p):
            a[m + 2] += pm / ((m + 1) * (m + 2))
        b = 0.0
        if B:
            a[0] += B * math.sin(phi) / w ** 2
            a[1] += B * math.cos(phi) / w
            b = -B / w ** 2
        out.append((u0, a, b, w, phi))
        t = u1 - u0
        s0 = sum(am * t ** m for m, am in enumerate(a)) + b * math.sin(w * t + phi)
        v0 = sum(m * am * t ** (m - 1) for m, am in enumerate(a) if m) + \
            b * w * math.cos(w * t + phi)
    return out, s0


@functools.cache
def _law_pieces(name: str) -> tuple:
    """The normalised rise of law ``name`` as displacement pieces ``(u0, a, (B, w, φ))``."""
    pi, h = math.pi, math.pi / 2
    if name == "polynomial_345":
        return ((0.0, (0.0, 0.0, 0.0, 10.0, -15.0, 6.0), (0.0, 0.0, 0.0)),)
    accel = {
        "harmonic": [(0, 1, (), pi ** 2 / 2, pi, h)],
        "cycloidal": [(0, 1, (), 2 * pi, 2 * pi, 0.0)],
        "modified_sine": [(0, 1 / 8, (), 1.0, 4 * pi, 0.0),
                          (1 / 8, 7 / 8, (), 1.0, 4 * pi / 3, h),
                          (7 / 8, 1, (), 1.0, 4 * pi, -h)],
        "modified_trapezoid": [(0, 1 / 8, (), 1.0, 4 * pi, 0.0),
                               (1 / 8, 3 / 8, (1.0,), 0.0, 0.0, 0.0),
                               (3 / 8, 5 / 8, (), 1.0, 4 * pi, h),
                               (5 / 8, 7 / 8, (-1.0,), 0.0, 0.0, 0.0),
                               (7 / 8, 1, (), 1.0, 4 * pi, -h)],
    }.get(name)
    if accel is None:
        raise ValueError(f"unknown motion law {name!r}; expected one of {', '.join(LAWS)}"
                         f"{did_you_mean(str(name), LAWS)}")
    pieces, end = _integrate(accel)
    # Harmonic and cycloidal end at 1 by construction; the modified laws fix C = 1/s(1).
    return tuple((u0, tuple(am / end for am in a), (b / end, w, phi))
                 for u0, a, b, w, phi in pieces)


def law(name: str, u) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The normalised rise of law ``name``: s(u), s'(u), s''(u) for u ∈ [0, 1].

    Parameters
    ----------
    name : str
        One of :data:`LAWS`.
    u : array_like
        Fraction of the rise angle; clipped to [0, 1].

    Returns
    -------
    s, ds, dds : ndarray
        Displacement (0 → 1) and its first two derivatives with respect to u.

    Examples
    --------
    >>> s, ds, dds = law("cycloidal", [0.25, 0.5])
    >>> [round(float(x), 12) for x in ds]     # peak velocity 2 at u = 1/2
    [1.0, 2.0]
    """
    start, poly, sine = zip(*_law_pieces(name))
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return Motion("", start, poly, sine, period=1.0).evaluate(u)


# ------------------------------------------------------------------ the motion
@dataclass(frozen=True)
class Motion:
    """A displacement over one revolution of the main shaft, piecewise in closed form.

    Build one with :func:`cam_cycle` or :func:`motion_table` (or a netlist's
    ``drive ... motion=``).  Plain data: it pickles and compares.

    Attributes
    ----------
    spec : str
        The netlist options that give this motion (``motion=cycloidal rise=120 ...``
        or ``motion=PATH``), for messages and for writing the netlist back.
    start : tuple of float
        θᵢ, the start of each piece [rad], increasing from 0.
    poly : tuple of tuple of float
        Coefficients a₀ … a₅ of each piece's polynomial in τ = θ − θᵢ.
    sine : tuple of (B, w, φ)
        Each piece's sinusoid B sin(w τ + φ) (B = 0 for none).
    period : float
        The period of θ: 2π (one revolution).
    error : float
        Estimated error of dx/dθ as a fraction of its largest value: 0 for a law
        (closed form), the interpolation estimate for a table (see
        :func:`motion_table`).
    coarse : Motion or None
        A table's spline through every other row (its difference from this one
        estimates the interpolation error of anything computed from it).
    path : str
        The table file it was read from ("" for a law or a table built in code).
    """

    __repr__ = summary_repr

    spec: str = field(compare=False)
    start: tuple
    poly: tuple
    sine: tuple
    period: float = _TAU
    error: float = 0.0
    coarse: Motion | None = field(default=None, compare=False, repr=False)
    path: str = field(default="", compare=False)
    _cache: dict = field(default_factory=dict, compare=False, repr=False, hash=False)

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_cache"] = {}
        return state

    def _arrays(self):
        if "arrays" not in self._cache:
            start = np.asarray(self.start, dtype=float)
            length = np.diff(np.append(start, self.period))
            self._cache["arrays"] = (start, length, np.asarray(self.poly, dtype=float),
                                     np.asarray(self.sine, dtype=float).reshape(-1, 3))
        return self._cache["arrays"]

    def evaluate(self, theta) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x(θ), dx/dθ and d²x/dθ² at ``theta`` [rad] (taken modulo the period).

        Units: x in the drive's displacement unit [m or rad], the derivatives
        per radian of shaft angle (dx/dθ · Ω is the velocity at shaft speed Ω).
        """
        start, _length, a, sine = self._arrays()
        theta = np.asarray(theta, dtype=float)
        th = np.where(theta == self.period, self.period, np.mod(theta, self.period))
        i = np.clip(np.searchsorted(start, th, side="right") - 1, 0, start.size - 1)
        t = th - start[i]
        ai = a[i]
        x = dx = ddx = np.zeros_like(t)              # rebound below, never written in place
        for m in range(_DEG - 1, -1, -1):           # Horner, with its two derivatives
            ddx = ddx * t + 2 * dx
            dx = dx * t + x
            x = x * t + ai[..., m]
        B, w, phi = sine[i, 0], sine[i, 1], sine[i, 2]
        arg = w * t + phi
        x = x + B * np.sin(arg)
        dx = dx + B * w * np.cos(arg)
        ddx = ddx - B * w * w * np.sin(arg)
        return x, dx, ddx

    def scaled(self, factor: float) -> Motion:
        """This motion times ``factor`` (a change of unit: mm → m, degrees → radians)."""
        return dataclasses.replace(
            self, spec=f"{self.spec} (x {factor:g})", _cache={},
            poly=tuple(tuple(factor * am for am in p) for p in self.poly),
            sine=tuple((factor * B, w, phi) for B, w, phi in self.sine),
            coarse=self.coarse.scaled(factor) if self.coarse is not None else None)

    def fourier(self, kmax: int) -> np.ndarray:
        """Fourier coefficients cₖ of dx/dθ, k = 1 … ``kmax``, exactly (closed form).

        dx/dθ = Σₖ cₖ e^{jkθ} (k from −∞ to ∞; c₀ = 0 for a periodic x, c₋ₖ = cₖ*),
        so dx/dθ = Σ_{k≥1} Re(2 cₖ e^{jkθ}).  Each piece's integral of
        polynomial × e^{−jkθ} is summed by parts (finitely many terms), the
        sinusoid's by the closed form L·e^{jαL/2}·sinc(αL/2).
        """
        key = ("fourier", int(kmax))
        if key in self._cache:
            return self._cache[key]
        start, length, a, sine = self._arrays()
        k = np.arange(1, kmax + 1, dtype=float) * (_TAU / self.period)
        # Polynomial part: q(τ) = Σ m aₘ τ^{m−1}; ∫₀ᴸ q e^{zτ} dτ with z = −jk is
        # [e^{zτ} Σᵣ (−1)ʳ q⁽ʳ⁾(τ) / z^{r+1}]₀ᴸ, a piece's term e^{zL} q⁽ʳ⁾(L) − q⁽ʳ⁾(0) =
        # (e^{zL} − 1) q⁽ʳ⁾(L) + (q⁽ʳ⁾(L) − q⁽ʳ⁾(0)): both small on a short piece (no
        # cancellation), and with the phase e^{−jkθᵢ} two products over the pieces per k.
        q = a[:, 1:] * np.arange(1, _DEG)                               # q's coefficients
        ends = np.empty((2, start.size, _DEG - 1))          # q⁽ʳ⁾ at each piece's end, start
        for r in range(_DEG - 1):           # q⁽ʳ⁾ for r = 0 … 4, the last a constant
            ends[0, :, r] = np.polynomial.polynomial.polyval(length, q.T, tensor=False)
            ends[1, :, r] = q[:, 0]
            q = q[:, 1:] * np.arange(1, q.shape[1])
        ends *= (-1.0) ** np.arange(_DEG - 1)                   # (−1)ʳ q⁽ʳ⁾
        # Sinusoid part (pieces with B ≠ 0 only): B w cos(wτ + φ) =
        # (Bw/2)(e^{j(wτ+φ)} + e^{−j(wτ+φ)}), each ∫₀ᴸ e^{jατ} = L e^{jαL/2} sinc(αL/2).
        live = sine[:, 0] != 0.0
        B, w, phi = sine[live, 0:1], sine[live, 1:2], sine[live, 2:3]
        L, c = length[live, None], np.empty(k.size, dtype=complex)
        step = max(1, _FOURIER_BLOCK // start.size)   # k in blocks: bounded scratch
        for k0 in range(0, k.size, step):
            kk = k[k0:k0 + step]
            phase = np.exp(-1j * np.outer(kk, start))                      # e^{−jkθᵢ}
            half = np.sin(0.5 * np.outer(kk, length))
            turn = (-2 * half * half - 1j * np.sin(np.outer(kk, length))) * phase
            sums = turn @ ends[0] + phase @ (ends[0] - ends[1])             # (k, r)
            z, acc = -1j * kk, np.zeros(kk.size, dtype=complex)
            for r in range(_DEG - 2, -1, -1):                             # Σᵣ sumsᵣ / z^{r+1}
                acc = (acc + sums[:, r]) / z
            for sgn in (1.0, -1.0):
                alpha = sgn * w - kk[None, :]
                integral = L * np.exp(0.5j * alpha * L) * np.sinc(alpha * L / (2 * math.pi))
                acc += (phase[:, live].T * (0.5 * B * w * np.exp(1j * sgn * phi) * integral)
                        ).sum(axis=0)
            c[k0:k0 + step] = acc / self.period
        if len(self._cache) > 16:
            self._cache.clear()
        self._cache[key] = c
        return c


def _piece_map(pieces, theta0: float, beta: float, h: float, rising: bool):
    """The normalised law pieces placed at θ₀ over β, stroke h, rising or returning."""
    out = []
    for u0, a, (b, w, phi) in pieces:
        sc = h if rising else -h
        poly = [sc * am / beta ** m for m, am in enumerate(a)]
        if not rising:
            poly[0] += h
        out.append((theta0 + beta * u0, tuple(poly), (sc * b, w / beta, phi)))
    return out


def cam_cycle(law_name: str, rise: float, dwell: float, ret: float, stroke: float,
              return_law: str | None = None) -> Motion:
    """A cam cycle: rise, dwell, return, dwell, over one revolution.

    Parameters
    ----------
    law_name : str
        One of :data:`LAWS`, for the rise (and the return unless ``return_law``).
    rise, dwell, ret : float
        Cam angles [deg] of the rise (from θ = 0), the dwell at the top and the
        return; the dwell at the bottom is what is left of 360°.  ``rise`` and
        ``ret`` > 0, ``dwell`` ≥ 0, their sum ≤ 360.
    stroke : float
        Lift h [m or rad]; any finite nonzero number (negative: the follower
        moves down first).
    return_law : str, optional
        One of :data:`LAWS` for the return.

    Returns
    -------
    Motion

    Examples
    --------
    >>> m = cam_cycle("cycloidal", 120, 60, 120, 0.05)
    >>> x, dx, ddx = m.evaluate(np.radians([60.0, 150.0]))
    >>> round(float(x[0]), 12), round(float(x[1]), 12)   # mid-rise, top dwell
    (0.025, 0.05)
    """
    ret_law = return_law or law_name
    _check_cycle(law_name, ret_law, rise, dwell, ret, stroke)
    b1, d1, b2 = (math.radians(v) for v in (rise, dwell, ret))
    try:        # a rise of 1e-320 degrees: 1/β⁵ is not a float64
        pieces = _piece_map(_law_pieces(law_name), 0.0, b1, stroke, True)
        if d1 > 0:
            pieces.append((b1, (stroke,) + (0.0,) * (_DEG - 1), (0.0, 0.0, 0.0)))
        pieces += _piece_map(_law_pieces(ret_law), b1 + d1, b2, stroke, False)
    except (ZeroDivisionError, OverflowError):
        pieces = None
    if pieces is None or not all(map(math.isfinite, (c for p in pieces for c in p[1] + p[2]))):
        raise ValueError(f"rise={rise:g} or return={ret:g} degrees is too short for a lift of "
                         f"{stroke:g}: the motion's derivatives are not finite float64 numbers")
    if b1 + d1 + b2 < _TAU * (1 - 1e-12):
        pieces.append((b1 + d1 + b2, (0.0,) * _DEG, (0.0, 0.0, 0.0)))
    spec = (f"motion={law_name} rise={float(rise)!r} dwell={float(dwell)!r} "
            f"return={float(ret)!r} stroke={float(stroke)!r}"
            + (f" return_law={ret_law}" if return_law else ""))
    start, poly, sine = zip(*pieces)
    return Motion(spec, start, poly, sine)


def _check_cycle(law_name, ret_law, rise, dwell, ret, stroke) -> None:
    """The laws known, the angles fit one revolution, the stroke finite and nonzero."""
    for name in (law_name, ret_law):
        if name not in LAWS:
            raise InputError(f"unknown motion law {name!r}; expected one of {', '.join(LAWS)}"
                             f"{did_you_mean(str(name), LAWS)}")
    for what, value in (("rise", rise), ("dwell", dwell), ("return", ret), ("stroke", stroke)):
        if not real_number(value):
            unit = "m or rad" if what == "stroke" else "deg"
            raise InputError(f"{what} must be a number [{unit}], got {brief(value)}")
    if not (math.isfinite(rise) and rise > 0 and math.isfinite(ret) and ret > 0
            and math.isfinite(dwell) and dwell >= 0):
        raise ValueError(f"rise and return must be > 0 and dwell >= 0 degrees, got "
                         f"rise={rise:g}, dwell={dwell:g}, return={ret:g}")
    if rise + dwell + ret > 360 * (1 + 1e-12):
        raise ValueError(f"rise + dwell + return = {rise + dwell + ret:g} degrees, more than "
                         "one revolution (360)")
    if not (math.isfinite(stroke) and stroke != 0):
        raise ValueError(f"stroke must be a finite nonzero number, got {stroke!r}")
    if abs(stroke) > MAX_LIFT:
        raise ValueError(f"stroke={stroke:g} is beyond the bound |stroke| <= {MAX_LIFT:g} "
                         "(the drive's velocities and forces would overflow float64)")


# ------------------------------------------------------------------ tables
def quintic(h, a, b) -> list:
    """The quintic Hermite piece through the (y, y', y'') ``a`` at the left end of an
    interval of width ``h`` and ``b`` at its right end: its coefficients of τ⁰ … τ⁵ (τ
    the offset from the left end), arrays of the y's shape (h: one, or broadcast with them).

    a₀, a₁, a₂ are the left end's; a₃h³, a₄h⁴, a₅h⁵ solve the right end's 3 × 3 system
    [[1, 1, 1], [3, 4, 5], [6, 12, 20]] with the residuals scaled by 1, h, h², whose
    inverse is [[10, −4, ½], [−15, 7, −1], [6, −3, ½]] (one formula for any h).
    """
    a0, a1, a2 = a[0], a[1], 0.5 * a[2]
    s0 = b[0] - (a0 + a1 * h + a2 * h * h)
    s1 = (b[1] - (a1 + 2 * a2 * h)) * h
    s2 = (b[2] - 2 * a2) * h * h
    return [a0, a1, a2, (10 * s0 - 4 * s1 + 0.5 * s2) / h ** 3,
            (-15 * s0 + 7 * s1 - s2) / h ** 4, (6 * s0 - 3 * s1 + 0.5 * s2) / h ** 5]


def hermite_table(h, f, f1, f2) -> np.ndarray:
    """Quintic Hermite pieces (n, 6) through values, slopes and curvatures at n + 1 nodes
    (:func:`quintic`).

    Parameters
    ----------
    h : float or ndarray
        The interval width, or each of the n.
    f, f1, f2 : ndarray
        Values, first and second derivatives at the nodes, shape (n + 1,).

    Returns
    -------
    ndarray, shape (n, 6)
        a0 … a5 of each piece, in powers of the offset from its left node.
    """
    f, f1, f2 = (np.asarray(a, float) for a in (f, f1, f2))
    return np.ascontiguousarray(np.column_stack(quintic(h, (f[:-1], f1[:-1], f2[:-1]),
                                                        (f[1:], f1[1:], f2[1:]))))


def _table_pieces(theta, x, slope, curvature):
    """(polynomial pieces, the scipy spline or None): quintic Hermite with ``slope``, else
    the periodic cubic spline."""
    if slope is not None:
        c = hermite_table(np.diff(theta), x, slope, curvature)
        if not np.all(np.isfinite(c)):
            raise ValueError("the interpolant through the samples is not finite in float64")
        return tuple(map(tuple, c.tolist())), None
    from scipy.interpolate import CubicSpline

    try:
        spl = CubicSpline(theta, x, bc_type="periodic")
    except ValueError:                         # scipy: the slopes overflowed
        spl = None
    if spl is None or not np.all(np.isfinite(spl.c)):
        raise ValueError("the spline through the table is not finite in float64 "
                         "(displacements too large)")
    c = spl.c                                          # (4, n−1), highest power first
    return tuple((c[3, i], c[2, i], c[1, i], c[0, i], 0.0, 0.0) for i in range(c.shape[1])), spl

def motion_table(angle_deg, displacement, spec: str = "motion=<table>", *, slope=None,
                 curvature=None) -> Motion:
    """The periodic cubic spline through a table of one revolution, as a :class:`Motion`.

    With ``slope`` and ``curvature`` (dx/dθ and d²x/dθ² at every row, per
    radian, as a linkage's kinematics gives them) the pieces are instead the
    quintic Hermite polynomials matching x, dx/dθ and d²x/dθ² at both ends of
    each interval (error O(h⁶) in x, O(h⁵) in dx/dθ).

    Parameters
    ----------
    angle_deg : array_like
        Crank angles [deg], strictly increasing, the last 360° after the first
        (which is θ = 0 of the motion).
    displacement : array_like
        The displacement at each angle [m or rad]; the last equal to the first
        within :data:`PERIODIC_TOLERANCE` of the range (then set equal).
    spec : str
        What to call it (the netlist's ``motion=PATH``).
    slope, curvature : array_like, optional
        dx/dθ [per rad] and d²x/dθ² [per rad²] at every row.

    Returns
    -------
    Motion
        With ``error``: the largest difference of dx/dθ between this spline and
        the one through every other row, as a fraction of max |dx/dθ| — an
        estimate of the interpolation error that errs high (for smooth data the
        full table's error is about 16 times smaller).  Tables of fewer than 9
        rows get no estimate (``inf``).
    """
    ang, x = np.asarray(angle_deg, dtype=float), np.array(displacement, dtype=float)
    theta = np.radians(ang - ang[0])
    theta[-1] = _TAU
    x[-1] = x[0]
    hermite = slope is not None
    poly, spl = _table_pieces(theta, x, slope, curvature)
    m = Motion(spec, tuple(theta[:-1]), poly, ((0.0, 0.0, 0.0),) * len(poly))
    if np.abs(x).max(initial=0.0) > MAX_LIFT:
        raise ValueError(f"a displacement of {np.abs(x).max():g} is beyond the bound "
                         f"{MAX_LIFT:g} (the drive's velocities and forces would overflow)")
    error, coarse = math.inf, None
    if ang.size >= 9:          # against the table through every other row
        keep = np.unique(np.append(np.arange(0, ang.size, 2), ang.size - 1))
        coarse = motion_table(ang[keep], x[keep], spec + " (every other row)",
                              slope=None if not hermite else np.asarray(slope)[keep],
                              curvature=None if not hermite else np.asarray(curvature)[keep])
        dense = np.linspace(0, _TAU, 16 * ang.size)
        fine = m.evaluate(dense)[1] if hermite else spl(dense, 1)
        scale = float(np.max(np.abs(fine)))
        error = float(np.max(np.abs(fine - coarse.evaluate(dense)[1]))) / scale \
            if scale > 0 else 0.0
    return dataclasses.replace(m, error=error, coarse=coarse, _cache={})


def read_motion_table(path: str | os.PathLike, spec: str | None = None) -> Motion:
    """Read a motion table (CSV: columns ``angle_deg`` and ``displacement``) into a Motion.

    The first non-comment line is the header naming the two columns (in any
    order; other columns are ignored); ``#`` starts a comment line.  The
    angles must increase strictly and span exactly one revolution (last =
    first + 360, within 1e-9°), the two ends' displacements must meet within
    :data:`PERIODIC_TOLERANCE` of the range, every value finite.  Nothing in
    the file is executed.

    Parameters
    ----------
    path : str or PathLike
    spec : str, optional
        The motion's ``spec`` (default ``motion=PATH``).

    Returns
    -------
    Motion

    Raises
    ------
    NetlistError
        At ``file:row:column`` of the first bad value, with what is expected.
    """
    source = os.fspath(path)
    text = read_source(path, "a motion table (CSV: angle_deg,displacement)")
    rows, header = _table_rows(text, source)
    x = _check_revolution(rows, header, source)
    try:
        m = motion_table([r[0] for r in rows], x, spec or f"motion={source}")
    except ValueError as exc:                  # 1e308 m: the slopes overflow
        big = max(rows, key=lambda r: abs(r[1]))
        raise NetlistError(f"{exc}; the largest displacement is {big[1]:g}", source, big[2],
                           big[3][header[1]], f"displacements within ±{MAX_LIFT:g} whose "
                           "slopes are finite float64 numbers") from None
    return dataclasses.replace(m, path=source)


def _header(cells, source: str, lineno: int) -> tuple:
    """(index of angle_deg, index of displacement, the column names) of the header row."""
    names = [c.strip().lower() for c in cells]
    for need in ("angle_deg", "displacement"):
        if need not in names:
            found = ", ".join(brief(n[:40]) for n in names[:4])
            raise NetlistError(f"the header has no column {need!r} (found {found}"
                               f"{', ...' if len(names) > 4 else ''})", source, lineno, 1,
                               "a first line 'angle_deg,displacement'")
    return names.index("angle_deg"), names.index("displacement"), names


def _table_rows(text: str, source: str):
    """The rows (angle, displacement, line, columns) of a motion table and its header."""
    rows: list[tuple] = []
    header = None
    for lineno, cells, cols, pos in csv_rows(text, source):
        if header is None:
            header = _header(cells, source, lineno)
            continue
        values = []
        for j in header[:2]:
            if j >= len(cells):
                raise NetlistError(f"row has {len(cells)} column(s), the header "
                                   f"{len(header[2])}", source, lineno, pos,
                                   f"{len(header[2])} comma-separated values")
            try:
                v = float(cells[j])
            except ValueError:
                raise NetlistError(f"{cells[j].strip()!r} is not a number", source, lineno,
                                   cols[j], "a finite number") from None
            if not math.isfinite(v):
                raise NetlistError(f"{cells[j].strip()} is not a finite number", source,
                                   lineno, cols[j], "a finite number")
            values.append(v)
        if rows and not values[0] > rows[-1][0]:
            prev = rows[-1]
            what = "repeats" if values[0] == prev[0] else "is below"
            raise NetlistError(f"angle {values[0]:g} {what} the previous row's {prev[0]:g} "
                               f"(line {prev[2]})", source, lineno, cols[header[0]],
                               "angles strictly increasing over one revolution")
        rows.append((values[0], values[1], lineno, cols))
    return rows, header


def _check_revolution(rows, header, source: str) -> np.ndarray:
    """The displacements, once the rows are enough, span one turn and meet at its ends."""
    if header is None or len(rows) < 4:
        raise NetlistError(f"the table has {len(rows)} row(s)", source, 0, 0,
                           "a header 'angle_deg,displacement' and at least 4 rows covering "
                           "one revolution, the last row 360 degrees after the first")
    first, last = rows[0], rows[-1]
    span = last[0] - first[0]
    if abs(span - 360.0) > 1e-9:
        raise NetlistError(f"the angles span {span:.12g} degrees ({first[0]:g} to {last[0]:g}),"
                           " not one revolution", source, last[2], last[3][header[0]],
                           f"a last row at {first[0] + 360:g} degrees (the first + 360), with "
                           "the first row's displacement")
    x = np.array([r[1] for r in rows])
    rng = float(np.ptp(x))
    tol = PERIODIC_TOLERANCE * rng if rng > 0 else 1e-12
    if abs(last[1] - first[1]) > tol:
        raise NetlistError(f"the motion is not periodic: displacement {last[1]:.12g} at "
                           f"{last[0]:g} degrees, {first[1]:.12g} at {first[0]:g} degrees "
                           f"(differ by {abs(last[1] - first[1]):.3g}, more than the tolerance "
                           f"{tol:.3g} = {PERIODIC_TOLERANCE:g} of the range)", source,
                           last[2], last[3][header[1]],
                           "the same displacement at both ends of the revolution")
    return x
