"""Closed-form kinematics of the planar four-bar linkage.

Conventions
-----------
The frame pivot of the crank is A at the origin, the frame pivot of the rocker
is D at ``(frame, 0)``: the frame line A→D is the x axis.  All angles are in
radians, measured counter-clockwise from the direction A→D:

* θ  -- crank angle, direction of A→B;
* φ3 -- coupler angle, direction of B→C;
* φ4 -- rocker angle, direction of D→C (so a rocker pointing back at A has
  φ4 ≈ π).

The crank turns with θ increasing (counter-clockwise) at a crank speed ω > 0.
Loop closure (Mrázek, eq. (3); patent CN104178888): ``a e^{iθ} + b e^{iφ3} = d + c e^{iφ4}``
with a = crank AB, b = coupler BC, c = rocker CD, d = frame AD.

Branch (assembly mode): with β the direction of D→B and ψ ∈ [0, π] the angle
BDC, ``φ4 = β − branch·ψ``; ``branch=+1`` puts C clockwise of the ray D→B
(for a crank-rocker whose rocker leans back over the crank, C above the frame
line).  For Mrázek's beat-up drive (29/37/188/189 mm,
Mrázek) ``branch=+1`` is the assembly whose theoretical rocker
acceleration ε4T = ν·ω² spans [−2319, 2915] s⁻² at ω = 100 s⁻¹, the values
the paper prints; ``branch=-1`` is its mirror image (ε4T ∈ [−2915, 2319]).

Transfer functions (exact, from the derivatives of loop closure)::

    μ  = dφ4/dθ  = a sin(θ − φ3) / (c sin(φ4 − φ3))
    μ3 = dφ3/dθ  = a sin(θ − φ4) / (b sin(φ4 − φ3))
    ν  = d²φ4/dθ² = [a cos(θ − φ3) + b μ3² − c μ² cos(φ4 − φ3)] / (c sin(φ4 − φ3))
    ν3 = d²φ3/dθ² = [a cos(θ − φ4) + b μ3² cos(φ4 − φ3) − c μ²] / (b sin(φ4 − φ3))

so that φ̇4 = μ ω and φ̈4 = ν ω² + μ ω̇ (Mrázek, eq. (3)).  The
transmission angle γ is the acute angle between the coupler and the rocker
lines; ``interior_angle`` is the angle BCD in [0, π].

Lengths may be in any consistent unit; the angles and the ratios μ, ν do not
depend on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import GeometryError, InputError
from ..sources import brief, finite_number, real_number, real_values
from ._dyad_forms import rrr

__all__ = ["FourBar", "FourBarState", "DeadCentre", "TransmissionRange"]

TWO_PI = 2.0 * math.pi

LinkageType = Literal["crank-rocker", "double-crank", "double-rocker",
                      "rocker-crank", "triple-rocker", "parallelogram", "deltoid",
                      "change-point"]

#: Largest and smallest link length accepted: squares and products of lengths
#: must stay finite and normal in float64.
MAX_LENGTH, MIN_LENGTH = 1e150, 1e-150


@dataclass(frozen=True)
class FourBarState:
    """Positions and transfer functions of a four-bar at a set of crank angles.

    Attributes
    ----------
    theta : ndarray
        Crank angle θ [rad].
    phi3, phi4 : ndarray
        Coupler and rocker angles [rad].
    mu, nu : ndarray
        dφ4/dθ [1] and d²φ4/dθ² [1/rad].
    mu3, nu3 : ndarray
        dφ3/dθ [1] and d²φ3/dθ² [1/rad].
    gamma : ndarray
        Transmission angle, acute angle between coupler and rocker [rad].
    """

    theta: NDArray[np.float64]
    phi3: NDArray[np.float64]
    phi4: NDArray[np.float64]
    mu: NDArray[np.float64]
    nu: NDArray[np.float64]
    mu3: NDArray[np.float64]
    nu3: NDArray[np.float64]
    gamma: NDArray[np.float64]


@dataclass(frozen=True)
class DeadCentre:
    """A dead centre of a crank-rocker: rocker at an extreme of its swing.

    Attributes
    ----------
    kind : {"front", "back"}
        Front: crank and coupler extended in line (beat-up); back: folded.
    theta : float
        Crank angle [rad], in [0, 2π).
    phi4 : float
        Rocker angle [rad].
    nu : float
        d²φ4/dθ² there [1/rad]; the rocker's angular acceleration is ν·ω².
    interior_angle : float
        Angle BCD between coupler and rocker there [rad].
    """

    kind: str
    theta: float
    phi4: float
    nu: float
    interior_angle: float

    def rocker_acceleration(self, omega: float) -> float:
        """Rocker angular acceleration ν·ω² [rad/s²] at crank speed ``omega`` [rad/s]."""
        w = _crank_speed(omega)
        return self.nu * w * w


@dataclass(frozen=True)
class TransmissionRange:
    """Extremes of the transmission angle over the crank's reachable range.

    Attributes
    ----------
    gamma_min, gamma_max : float
        Smallest and largest transmission angle [rad].
    theta_at_min, theta_at_max : tuple of float
        Every crank angle in [0, 2π) where they occur [rad].
    """

    gamma_min: float
    theta_at_min: tuple[float, ...]
    gamma_max: float
    theta_at_max: tuple[float, ...]


#: Least distance [rad] from a branch crossing at which :meth:`FourBar.nu_extrema` evaluates
#: the closed form (0/0 at the crossing: digits lost as the distance shrinks).
CROSSING_GAP = 1e-3


def _crank_speed(omega) -> float:
    """``omega`` [rad/s] if it is a finite number whose square is finite, else a
    :class:`GeometryError` saying so."""
    try:
        ok = real_number(omega) and math.isfinite(float(omega) * float(omega))
    except OverflowError:                  # an integer past float64
        ok = False
    if not ok:
        raise GeometryError(f"crank speed ω must be a finite number whose square is "
                            f"finite [rad/s], got {brief(omega)}")
    return float(omega)


def _wrap(x):
    """Wrap an angle to [−π, π)."""
    return (x + math.pi) % TWO_PI - math.pi


@dataclass(frozen=True)
class FourBar:
    """A planar four-bar linkage ABCD with the crank AB as input.

    Parameters
    ----------
    crank : float
        Crank length AB = a [any length unit], > 0.
    coupler : float
        Coupler length BC = b [same unit], > 0.
    rocker : float
        Rocker length CD = c [same unit], > 0.
    frame : float
        Frame length AD = d [same unit], > 0.
    branch : {+1, -1}
        Assembly mode; see the module docstring.

    Raises
    ------
    GeometryError
        A length is not a positive finite number, the branch is not ±1, or one
        length is at least the sum of the other three (no assembly exists).

    Examples
    --------
    >>> fb = FourBar(29.0, 37.0, 188.0, 189.0)
    >>> fb.linkage_type
    'crank-rocker'
    >>> lo, hi = fb.rocker_acceleration_range(100.0)
    >>> round(lo), round(hi)
    (-2319, 2915)
    """

    crank: float
    coupler: float
    rocker: float
    frame: float
    branch: int = 1
    _ref: float = field(init=False, repr=False, compare=False)
    _turns: bool = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        names = ("crank", "coupler", "rocker", "frame")
        lengths = (self.crank, self.coupler, self.rocker, self.frame)
        for name, value in zip(names, lengths):
            if not isinstance(value, (int, float, np.floating, np.integer)) \
                    or not math.isfinite(value) or value <= 0:
                raise GeometryError(f"four-bar {name} length must be a positive finite "
                                    f"number, got {value!r}")
            if not MIN_LENGTH <= value <= MAX_LENGTH:
                raise GeometryError(f"four-bar {name} length {value:g} is out of range: lengths "
                                    f"must lie in [{MIN_LENGTH:g}, {MAX_LENGTH:g}] (their squares "
                                    f"must stay finite); change the unit")
            object.__setattr__(self, name, float(value))
        if self.branch not in (1, -1):
            raise GeometryError(f"four-bar branch must be +1 or -1, got {self.branch!r}")
        object.__setattr__(self, "branch", int(self.branch))
        total = sum(lengths)
        for name, value in zip(names, lengths):
            if value >= total - value:
                raise GeometryError(
                    f"four-bar cannot be assembled: the {name} ({value:g}) is not shorter "
                    f"than the sum of the other three links ({total - value:g})")
        # a double-crank's output turns with the crank: track φ4 − θ instead of φ4
        object.__setattr__(self, "_turns", self.crank_rotates_fully and (
            self._shortest_type() == "double-crank" or self.linkage_type == "parallelogram"))
        object.__setattr__(self, "_ref", self._reference_angle())

    # ------------------------------------------------------------------ class
    @property
    def grashof_class(self) -> Literal["Grashof", "non-Grashof", "change-point"]:
        """Grashof class: s + l < p + q ('Grashof'), > ('non-Grashof'), = ('change-point')."""
        ls = sorted((self.crank, self.coupler, self.rocker, self.frame))
        lhs, rhs = ls[0] + ls[3], ls[1] + ls[2]
        if math.isclose(lhs, rhs, rel_tol=1e-12, abs_tol=0.0):
            return "change-point"
        return "Grashof" if lhs < rhs else "non-Grashof"

    @property
    def linkage_type(self) -> LinkageType:
        """Type by the shortest link (Grashof), 'triple-rocker' (non-Grashof), or a change point.

        Grashof: 'crank-rocker' (crank shortest), 'double-crank' (frame
        shortest), 'double-rocker' (coupler shortest), 'rocker-crank' (rocker
        shortest: the rocker turns fully, the input rocks).

        Change point (s + l = p + q): 'parallelogram' (crank = rocker and
        coupler = frame; it can fold into the antiparallelogram), 'deltoid'
        (two pairs of equal adjacent links), else 'change-point'.  Each passes
        through positions with all four joints on one line, where its two
        assembly modes meet (:meth:`branch_crossings`): the motion beyond is not
        determined by the geometry, and the closed form switches branch there.
        """
        if self.grashof_class == "change-point":
            a, b, c, d = self.crank, self.coupler, self.rocker, self.frame

            def eq(x, y):
                return math.isclose(x, y, rel_tol=1e-12)

            if eq(a, c) and eq(b, d):
                return "parallelogram"
            if (eq(a, b) and eq(c, d)) or (eq(a, d) and eq(b, c)):
                return "deltoid"
            return "change-point"
        return "triple-rocker" if self.grashof_class == "non-Grashof" else self._shortest_type()

    def _shortest_type(self) -> LinkageType:
        by_shortest = ((self.crank, "crank-rocker"), (self.frame, "double-crank"),
                       (self.coupler, "double-rocker"), (self.rocker, "rocker-crank"))
        return cast(LinkageType, min(by_shortest, key=lambda x: x[0])[1])    # first of a tie

    def _crossings_note(self, crossings) -> str:
        """The summary's note on a change-point linkage's branch crossings."""
        # B on D (a deltoid with crank = frame and coupler = rocker, θ = 0): no line of
        # four joints there, but coupler and rocker on each other, their angles undefined
        on_d = [t for t in crossings if t == 0.0 and self.crank == self.frame
                and self.coupler == self.rocker]
        inline = [t for t in crossings if t not in on_d]
        where = " and ".join(f"{math.degrees(t):g}°" for t in inline)
        what = []
        if on_d:
            what.append("B falls on D at θ = 0°, where coupler and rocker lie on each other "
                        "and may turn freely (their angles, μ and ν are undefined there)")
        if inline:
            what.append(f"all four joints fall on one line at θ = {where}, where μ and ν are 0/0")
        return ("change-point linkage"
                + ("" if self.linkage_type == "change-point" else f" ({self.linkage_type})")
                + ": " + "; ".join(what) + "; its two assembly modes cross there and the motion "
                "beyond depends on which branch the linkage takes, so the ν range and ε4T are "
                "not given")

    def branch_crossings(self) -> tuple[float, ...]:
        """Crank angles θ [rad] in [0, 2π) where the four joints are collinear and the branches cross.

        Only a change-point linkage (Grashof equality) has them: there the
        constraint Jacobian is singular, μ and ν of the closed form are 0/0, and
        the linkage may leave on either assembly mode.  B is on the frame line
        (θ = 0 or π) and C on the same line: BD = |d − a| or d + a equals
        b + c or |b − c|.
        """
        if self.grashof_class != "change-point":
            return ()
        a, b, c, d = self.crank, self.coupler, self.rocker, self.frame
        tol = 1e-9 * max(a, b, c, d)
        return tuple(theta for theta, bd in ((0.0, abs(d - a)), (math.pi, d + a))
                     if abs(bd - (b + c)) <= tol or abs(bd - abs(b - c)) <= tol)

    @property
    def crank_rotates_fully(self) -> bool:
        """True when the input link can make full revolutions (|d − a| ≥ |b − c| and d + a ≤ b + c)."""
        a, b, c, d = self.crank, self.coupler, self.rocker, self.frame
        return abs(d - a) >= abs(b - c) and d + a <= b + c

    @property
    def is_full_turn_crank_rocker(self) -> bool:
        """True for a crank-rocker whose crank turns fully: the linkage of the dead centres and
        the swing (:meth:`dead_centres`), the beat-up drive and the synthesis."""
        return self.linkage_type == "crank-rocker" and self.crank_rotates_fully

    def crank_range(self) -> tuple[float, float]:
        """Reachable crank angles as ``(theta_lo, theta_hi)`` [rad].

        Full rotation gives ``(0, 2π)``.  Otherwise the distance BD must stay in
        [|b − c|, b + c]; the crank then rocks in a window about θ = 0
        (returned as ``(−t, t)``), about θ = π, or, when neither θ = 0 nor θ = π
        is reachable, in two mirror windows, of which the one in (0, π) is
        returned (the other is ``(2π − hi, 2π − lo)``).
        """
        if self.crank_rotates_fully:
            return 0.0, TWO_PI
        a, b, c, d = self.crank, self.coupler, self.rocker, self.frame
        bd_lo, bd_hi = max(abs(d - a), abs(b - c)), min(d + a, b + c)
        t_lo, t_hi = (math.acos(max(-1.0, min(1.0, (a * a + d * d - bd ** 2) / (2 * a * d))))
                      for bd in (bd_lo, bd_hi))
        if bd_lo == abs(d - a):      # θ = 0 reachable
            return -t_hi, t_hi
        if bd_hi == d + a:           # θ = π reachable
            return t_lo, TWO_PI - t_lo
        return t_lo, t_hi

    # -------------------------------------------------------------- positions
    def _raw(self, theta):
        """Unwrapped-by-branch rocker angle and the cosine of angle BDC (vectorised)."""
        a, d = self.crank, self.frame
        bx, by = a * np.cos(theta) - d, a * np.sin(theta)
        return bx, by, self._cos_bdc(bx * bx + by * by)

    def _cos_bdc(self, e2):
        """cos ψ, ψ the angle BDC, from BD² = ``e2`` (vectorised).  B on D (crank = frame,
        at θ = 0) is assembled when coupler = rocker, the deltoid's singular position: its
        limit cos ψ = BD / 2c → 0 is returned there, for :meth:`_check`; the rocker angle
        itself is undefined (NaN) there."""
        b, c = self.coupler, self.rocker
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_psi = (c * c + e2 - b * b) / (2.0 * c * np.sqrt(e2))
        return np.where(e2 == 0.0, 0.0, cos_psi) if b == c else cos_psi

    def _rocker(self, bx, by):
        """Rocker angle (wrapped) with B at (bx, by) from D: C is the inner joint of the
        RRR dyad D–C–B, by the closed form the linkage solver uses (:func:`._dyad_forms.rrr`);
        branch +1 puts C clockwise of the ray D → B."""
        with np.errstate(divide="ignore", invalid="ignore"):
            c_d, _ = rrr(0j, bx + 1j * by, self.rocker, self.coupler, -self.branch)
        return np.angle(c_d)

    def _check(self, theta, cos_psi):
        bad = ~(np.abs(cos_psi) <= 1.0 + 1e-12)
        if np.any(bad):
            first = float(np.asarray(theta)[bad].flat[0]) if np.ndim(theta) else float(theta)
            lo, hi = self.crank_range()
            raise GeometryError(
                f"four-bar locks: it cannot be assembled at crank angle θ = "
                f"{math.degrees(first):.6g}° ({self.linkage_type}; the crank reaches "
                f"θ ∈ [{math.degrees(lo):.6g}°, {math.degrees(hi):.6g}°] only)")

    def _reference_angle(self) -> float:
        """Centre of the rocker's range (relative to θ for a turning rocker) [rad]."""
        lo, hi = self.crank_range()
        span = hi - lo
        th = np.linspace(lo + 1e-9 * span, hi - 1e-9 * span, 1441)
        raw = self._rocker(*self._raw(th)[:2]) - (th if self._turns else 0.0)
        un = np.unwrap(raw[np.isfinite(raw)])       # without a deltoid's B = D (NaN)
        return float(_wrap(0.5 * (un.max() + un.min())))

    def evaluate(self, theta: ArrayLike) -> FourBarState:
        """All positions and transfer functions at crank angles ``theta`` [rad], in one pass.

        Parameters
        ----------
        theta : array_like
            Crank angle θ [rad]; any shape.

        Returns
        -------
        FourBarState
            Arrays of the shape of ``theta``.

        Raises
        ------
        GeometryError
            The linkage cannot be assembled at some θ (it locks); the message
            names the first such θ and the reachable range.

        Notes
        -----
        Closed form, O(n); about 30 numpy passes for n angles.  At a singular position
        (a lock end, a branch crossing) the rates are 0/0 or huge; where B lies on D (a
        deltoid with crank = frame and coupler = rocker, at θ = 0) the angles and rates are
        NaN: coupler and rocker lie on each other and may turn freely.
        """
        theta = real_values(theta, "theta", "rad")
        a, b, c = self.crank, self.coupler, self.rocker
        bx, by, cos_psi = self._raw(theta)
        self._check(theta, cos_psi)
        raw = self._rocker(bx, by)
        ref = self._ref + theta if self._turns else self._ref
        phi4 = ref + _wrap(raw - ref)
        # (bx, by) is B relative to D and C = D + c e^{iφ4}: coupler direction B→C
        phi3 = np.arctan2(c * np.sin(phi4) - by, c * np.cos(phi4) - bx)
        s43, c43 = np.sin(phi4 - phi3), np.cos(phi4 - phi3)
        with np.errstate(divide="ignore", invalid="ignore"):     # s43 = 0: a singular position
            mu = a * np.sin(theta - phi3) / (c * s43)
            mu3 = a * np.sin(theta - phi4) / (b * s43)
            nu = (a * np.cos(theta - phi3) + b * mu3 * mu3 - c * mu * mu * c43) / (c * s43)
            nu3 = (a * np.cos(theta - phi4) + b * mu3 * mu3 * c43 - c * mu * mu) / (b * s43)
        gamma = np.arctan2(np.abs(s43), np.abs(c43))
        return FourBarState(theta, phi3, phi4, mu, nu, mu3, nu3, gamma)

    def rocker_angle(self, theta: ArrayLike):
        """Rocker angle φ4 [rad] at crank angle ``theta`` [rad] (float in, float out)."""
        return self._out(theta, "phi4")

    def mu(self, theta: ArrayLike):
        """Rocker velocity ratio μ = dφ4/dθ [1] at crank angle ``theta`` [rad]."""
        return self._out(theta, "mu")

    def nu(self, theta: ArrayLike):
        """Rocker acceleration ratio ν = d²φ4/dθ² [1/rad] at crank angle ``theta`` [rad]."""
        return self._out(theta, "nu")

    def interior_angle(self, theta: ArrayLike):
        """Angle BCD between coupler and rocker, in [0, π] [rad], at ``theta`` [rad].

        Independent of the branch: cos BCD = (b² + c² − BD²) / (2bc).
        """
        a, b, c, d = self.crank, self.coupler, self.rocker, self.frame
        th = np.asarray(theta, dtype=float)
        bd2 = a * a + d * d - 2 * a * d * np.cos(th)
        cos_d = (b * b + c * c - bd2) / (2 * b * c)
        self._check(th, self._cos_bdc(bd2))
        out = np.arccos(np.clip(cos_d, -1.0, 1.0))
        return float(out) if np.ndim(out) == 0 and isinstance(theta, (float, int)) else out

    def rocker_acceleration(self, theta: ArrayLike, omega: float):
        """Theoretical rocker acceleration ε4T = ν·ω² [rad/s²] at constant crank speed ``omega`` [rad/s]."""
        w = _crank_speed(omega)
        return self.nu(theta) * (w * w)

    def _out(self, theta, name):
        """Field ``name`` (``phi4``, ``mu`` or ``nu``) of :meth:`evaluate`; at one angle a
        float from :meth:`transfer` (which refuses the singular positions)."""
        if not isinstance(theta, (float, int)):
            return getattr(self.evaluate(theta), name)
        return self.transfer(theta)[("phi4", "mu", "nu").index(name)]

    def transfer(self, theta: float) -> tuple[float, float, float]:
        """(φ4 [rad], μ [1], ν [1/rad]) at one crank angle ``theta`` [rad], as floats.

        :meth:`evaluate` at one angle (the one closed form), refusing the
        positions where coupler and rocker are in line (μ and ν undefined).

        Raises
        ------
        GeometryError
            The linkage locks at ``theta``, or is at such a singular position.
        """
        s = self.evaluate(theta if finite_number(theta) else real_values(theta, "theta", "rad"))
        if not abs(math.sin(float(s.phi4) - float(s.phi3))) > 0.0:    # 0, or NaN where B = D
            raise GeometryError(
                f"four-bar at a singular position at θ = {math.degrees(theta):.6g}°: coupler and "
                f"rocker in line, μ and ν undefined"
                + (" (a branch crossing of this change-point linkage)"
                   if self.grashof_class == "change-point" else ""))
        return float(s.phi4), float(s.mu), float(s.nu)

    def joints(self, theta: float) -> tuple[tuple[float, float], ...]:
        """Joints A, B, C, D as (x, y) [length unit] at one crank angle ``theta`` [rad] (A at the
        origin, D on the x axis; :meth:`transfer` places C)."""
        phi4 = self.transfer(theta)[0]
        a, c, d = self.crank, self.rocker, self.frame
        return ((0.0, 0.0), (a * math.cos(theta), a * math.sin(theta)),
                (d + c * math.cos(phi4), c * math.sin(phi4)), (d, 0.0))

    # ------------------------------------------------------------- summaries
    def dead_centres(self) -> tuple[DeadCentre, DeadCentre]:
        """Front (crank and coupler extended) and back (folded) dead centres.

        Returns
        -------
        (front, back) : DeadCentre
            θ from the triangle A-C-D with AC = b ± a, the branch chosen so
            that C lies where :meth:`rocker_angle` puts it.

        Raises
        ------
        GeometryError
            The linkage is not a crank-rocker.
        """
        if not self.is_full_turn_crank_rocker:
            raise GeometryError(
                f"a dead centre is defined for a crank-rocker only; this four-bar "
                f"(a={self.crank:g}, b={self.coupler:g}, c={self.rocker:g}, d={self.frame:g}) "
                f"is a {self.grashof_class} {self.linkage_type}")
        a, b, c, d = self.crank, self.coupler, self.rocker, self.frame
        out = []
        for kind, ac, flip in (("front", b + a, 0.0), ("back", b - a, math.pi)):
            alpha = math.acos(max(-1.0, min(1.0, (ac * ac + d * d - c * c) / (2 * ac * d))))
            best: tuple[float, ...] = ()
            for sign in (1.0, -1.0):
                # C on the ray from A at angle sign*alpha; crank along it (front) or opposite (back)
                theta = (sign * alpha + flip) % TWO_PI
                cx, cy = ac * math.cos(sign * alpha), ac * math.sin(sign * alpha)
                phi4 = self.transfer(theta)[0]
                err = math.hypot(d + c * math.cos(phi4) - cx, c * math.sin(phi4) - cy)
                if not best or err < best[0]:
                    best = (err, theta, phi4)
            _, theta, phi4 = best
            out.append(DeadCentre(kind, theta, phi4, self.transfer(theta)[2],
                                  float(self.interior_angle(theta))))
        return out[0], out[1]

    def swing(self) -> float:
        """Rocker swing Ψ = |φ4(back) − φ4(front)| [rad] of a crank-rocker."""
        front, back = self.dead_centres()
        return abs(back.phi4 - front.phi4)

    def transmission_range(self) -> TransmissionRange:
        """Extremes of γ over the crank's reachable range, in closed form.

        The angle BCD depends on θ only through BD² = a² + d² − 2ad cos θ, so its
        extremes are at the ends of the reachable BD interval; γ = 90° is reached
        wherever BCD crosses 90° (BD² = b² + c²).
        """
        a, b, c, d = self.crank, self.coupler, self.rocker, self.frame
        bd_lo, bd_hi = max(abs(d - a), abs(b - c)), min(d + a, b + c)

        def thetas_for(bd):
            cth = max(-1.0, min(1.0, (a * a + d * d - bd * bd) / (2 * a * d)))
            t = math.acos(cth)
            return tuple(sorted({round(t % TWO_PI, 15), round((-t) % TWO_PI, 15)}))

        def gamma_at(bd):       # the acute angle between coupler and rocker
            bcd = math.acos(max(-1.0, min(1.0, (b * b + c * c - bd * bd) / (2 * b * c))))
            return float(np.arctan2(np.abs(np.sin(bcd)), np.abs(np.cos(bcd))))

        candidates = [(gamma_at(bd), thetas_for(bd)) for bd in (bd_lo, bd_hi)]
        gmin = min(g for g, _ in candidates)
        tmin = tuple(sorted(set().union(*(t for g, t in candidates
                                           if math.isclose(g, gmin, abs_tol=1e-15)))))
        right = math.sqrt(b * b + c * c)
        gmax, tmax = (math.pi / 2, thetas_for(right)) if bd_lo <= right <= bd_hi else \
            max(candidates, key=lambda t: t[0])
        return TransmissionRange(gmin, tmin, gmax, tmax)

    def nu_extrema(self, n: int = 3600) -> tuple[tuple[float, float], tuple[float, float]]:
        """((θ, ν_min), (θ, ν_max)) over the reachable crank range [rad], [1/rad].

        A grid of ``n`` angles brackets each extremum, then a bounded Brent
        search on the closed-form ν refines it to rounding.

        A change-point linkage's closed form switches assembly mode at each
        branch crossing (:meth:`branch_crossings`): the rocker angle has a kink
        there, μ jumps, and ν is unbounded, ``-inf`` at that θ when μ jumps down
        (``+inf`` up).  The other extremum is the finite one of the smooth
        pieces; grid and search keep :data:`CROSSING_GAP` off a crossing, where
        the closed form is 0/0 and loses digits.
        """
        from scipy.optimize import minimize_scalar

        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 3 <= n <= 10**6:
            raise InputError(f"n must be a whole number of angles from 3 to 1,000,000, got "
                             f"{brief(n)}")
        lo, hi = self.crank_range()
        th = np.linspace(lo, hi, n + 1)
        if not self.crank_rotates_fully:
            th = th[1:-1]
        step, gap = th[1] - th[0], CROSSING_GAP
        jumps = self._mu_jumps(gap)
        for tc in jumps:
            th = th[np.abs(_wrap(th - tc)) >= gap]
        nu, out = self.evaluate(th).nu, []
        for sign, idx in ((1.0, int(np.argmin(nu))), (-1.0, int(np.argmax(nu)))):
            kinks = [tc for tc, jump in jumps.items() if sign * jump < 0]
            if kinks:                                 # a kink of this sign: unbounded
                out.append((kinks[0], -sign * math.inf))
                continue
            t0 = th[idx]
            left, right = t0 - step, t0 + step
            if not self.crank_rotates_fully:
                left, right = max(left, th[0]), min(right, th[-1])
            for tc in jumps:                          # the bracket stays off a crossing
                off = _wrap(tc - t0)
                if 0 < off < right - t0 + gap:
                    right = t0 + off - gap
                elif 0 > off > left - t0 - gap:
                    left = t0 + off + gap
            res = minimize_scalar(lambda t, sign=sign: sign * self.transfer(float(t))[2],
                                  bounds=(left, right), method="bounded",
                                  options={"xatol": 1e-12})
            t_best, v_best = (float(res.x), float(sign * res.fun))
            if sign * v_best > sign * nu[idx]:   # grid point was better (edge case)
                t_best, v_best = float(t0), float(nu[idx])
            out.append((t_best % TWO_PI if self.crank_rotates_fully else t_best, v_best))
        return out[0], out[1]

    def _mu_jumps(self, gap: float) -> dict[float, float]:
        """Crossing θ → μ(θ+) − μ(θ−) of the closed form at each branch crossing (empty for
        other linkages): each side's limit extrapolated from ``gap`` and 2·``gap`` away."""
        out = {}
        for tc in self.branch_crossings():
            t = tc + gap * np.array([-2.0, -1.0, 1.0, 2.0])
            mu = self.evaluate(t).mu
            before, after = 2 * mu[1] - mu[0], 2 * mu[2] - mu[3]
            if abs(after - before) > 1e-6 * (1.0 + abs(before) + abs(after)):
                out[tc] = float(after - before)
        return out

    def rocker_acceleration_range(self, omega: float) -> tuple[float, float]:
        """(min, max) of ε4T = ν·ω² [rad/s²] over a revolution at crank speed ``omega`` [rad/s]."""
        w = _crank_speed(omega)
        w2 = w * w
        (_, nmin), (_, nmax) = self.nu_extrema()
        return nmin * w2, nmax * w2

    def summary(self, omega: float | None = None) -> dict:
        """Plain-data summary (angles in degrees) for reports and ``--json``."""
        if omega is not None:
            _crank_speed(omega)
        doc: dict[str, Any] = {
            "crank": self.crank, "coupler": self.coupler, "rocker": self.rocker,
            "frame": self.frame, "branch": self.branch,
            "grashof_class": self.grashof_class, "linkage_type": self.linkage_type,
            "crank_rotates_fully": self.crank_rotates_fully,
            "crank_range_deg": [math.degrees(t) for t in self.crank_range()]}
        tr = self.transmission_range()
        doc["gamma_min_deg"] = math.degrees(tr.gamma_min)
        doc["theta_at_gamma_min_deg"] = [math.degrees(t) for t in tr.theta_at_min]
        doc["gamma_max_deg"] = math.degrees(tr.gamma_max)
        doc["theta_at_gamma_max_deg"] = [math.degrees(t) for t in tr.theta_at_max]
        if self.is_full_turn_crank_rocker:
            front, back = self.dead_centres()
            doc["swing_deg"] = math.degrees(abs(back.phi4 - front.phi4))
            doc["dead_centres"] = []
            for dc in (front, back):
                entry = {"kind": dc.kind, "theta_deg": math.degrees(dc.theta),
                         "phi4_deg": math.degrees(dc.phi4), "nu": dc.nu,
                         "interior_angle_deg": math.degrees(dc.interior_angle)}
                if omega is not None:
                    entry["rocker_acceleration"] = dc.rocker_acceleration(omega)
                doc["dead_centres"].append(entry)
        crossings = self.branch_crossings()
        doc["branch_crossings_deg"] = [math.degrees(t) for t in crossings]
        doc["notes"] = [self._crossings_note(crossings)] if crossings else []
        if omega is not None:
            doc["omega"] = omega
        if crossings:
            doc["nu_min"] = doc["nu_max"] = None
            doc["theta_at_nu_min_deg"] = doc["theta_at_nu_max_deg"] = None
            if omega is not None:
                doc["eps4T_min"] = doc["eps4T_max"] = None
            return doc
        (tlo, nlo), (thi, nhi) = self.nu_extrema()
        doc["nu_min"], doc["theta_at_nu_min_deg"] = nlo, math.degrees(tlo)
        doc["nu_max"], doc["theta_at_nu_max_deg"] = nhi, math.degrees(thi)
        if omega is not None:
            doc["eps4T_min"], doc["eps4T_max"] = nlo * omega * omega, nhi * omega * omega
        return doc
