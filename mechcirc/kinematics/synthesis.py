"""Beat-up four-bar synthesis after patent CN104178888 (DIGEST §3).

The crank-rocker ABCD has crank AB = a, coupler BC = b, rocker CD = c and
frame AD = d [mm]; ratios are written β = b/a, κ = c/a, δ = d/a.  The front
dead centre (beat-up) has crank and coupler extended in line, the back dead
centre has them folded; Φ1'', Φ2'' are d²Φ/dθ² there [1/rad] and the swing is
Ψ = |Φ2 − Φ1|.  The patent's criteria, with the equation numbers of the seed:

=========================  ===============================================  ========
name                       criterion                                        equation
=========================  ===============================================  ========
``crank_length``           a in the load's range: light 33–34, medium       step 1
                           35–36, heavy 37–38 mm
``front_transmission``     transmission angle at the front dead centre      (1), (2)
                           (acute version of μ1) > 70°
``min_transmission``       minimum transmission angle over a turn > 45°     (3)
``acceleration_ratio``     |Φ2''| / |Φ1''| < 0.3                            (4)–(6)
``frame_length``           d < 180 mm                                       (8)
``rocker_ratio``           c/a > (b/a)·(360/Ψ)/(2π), Ψ in degrees           (9)
``swing``                  23° ≤ Ψ ≤ 26°                                    step 4
=========================  ===============================================  ========

μ1, μ2 of eq. (1) are the angles BCD at the dead centres, in [0°, 180°]; the
patent calls the acute angle between coupler and rocker the transmission
angle, so eq. (2) is applied to ``min(μ1, 180° − μ1)`` (our reading; it makes
no difference when μ1 ≤ 90°).  Eq. (5), |Φ1''/Φ2''| = ((β + 1)/(β − 1))·
(sin μ2 / sin μ1), is used only to screen a grid quickly; every design that is
returned is re-evaluated directly with :class:`~mechcirc.kinematics.FourBar`.

Eq. (10), the law of cosines at D for the two dead-centre triangles, is
quadratic in κ² (and, by symmetry, in δ²)::

    X = κ² + δ² − (β + 1)²,  Y = κ² + δ² − (β − 1)²
    X² + Y² − 2 cos Ψ · X Y − 4 κ² δ² sin² Ψ = 0

which is the patent's form multiplied by (2κδ)².  It also holds for the
mirror configuration in which the rocker swings across the frame line (swing
α_f + α_b instead of |α_f − α_b|), so each root is checked against the swing
of the linkage itself.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ..errors import GeometryError
from .fourbar import FourBar

__all__ = [
    "LOAD_CRANK_MM", "CRITERIA", "Criterion", "Design", "SynthesisResult",
    "dead_centre_angles", "acceleration_ratio_eq5", "eq10_residual", "solve_eq10",
    "evaluate_design", "synthesize",
]

#: Crank length range [mm] by loom class (patent step 1).
LOAD_CRANK_MM: dict[str, tuple[float, float]] = {
    "light": (33.0, 34.0), "medium": (35.0, 36.0), "heavy": (37.0, 38.0)}

#: Criterion names in report order.
CRITERIA: tuple[str, ...] = ("crank_length", "front_transmission", "min_transmission",
                             "acceleration_ratio", "frame_length", "rocker_ratio", "swing")

FRONT_TRANSMISSION_MIN_DEG = 70.0
MIN_TRANSMISSION_MIN_DEG = 45.0
ACCELERATION_RATIO_MAX = 0.3
FRAME_MAX_MM = 180.0
SWING_RANGE_DEG = (23.0, 26.0)

#: Criteria that constrain the shape (the swing and crank length hold by construction in synthesize).
_SHAPE_CRITERIA = ("front_transmission", "min_transmission", "acceleration_ratio",
                   "frame_length", "rocker_ratio")

#: Relative margin below which a criterion is reported as binding.
BINDING_MARGIN = 0.05


@dataclass(frozen=True)
class Criterion:
    """One criterion of a design.

    Attributes
    ----------
    name : str
        One of :data:`CRITERIA`.
    value : float
        The design's value (degrees for angles, mm for lengths, 1 for ratios).
    limit : str
        The requirement, as text (e.g. ``"> 70°"``).
    passed : bool
        Whether the requirement holds.
    margin : float
        Relative distance to the limit (> 0 inside, < 0 violated) [1].
    """

    name: str
    value: float
    limit: str
    passed: bool
    margin: float


@dataclass(frozen=True)
class Design:
    """A beat-up four-bar and the value of every patent criterion.

    Attributes
    ----------
    a, b, c, d : float
        Crank, coupler, rocker and frame lengths [mm].
    criteria : dict[str, Criterion]
        Every criterion of :data:`CRITERIA`, by name.
    mu1_deg, mu2_deg : float
        Angles BCD at the front and back dead centres, eq. (1) [deg].
    phi1_dd, phi2_dd : float
        d²Φ/dθ² at the front and back dead centres [1/rad].
    swing_deg : float
        Swing Ψ computed from the linkage [deg].
    """

    a: float
    b: float
    c: float
    d: float
    criteria: dict
    mu1_deg: float
    mu2_deg: float
    phi1_dd: float
    phi2_dd: float
    swing_deg: float
    objective: float = float("nan")

    @property
    def feasible(self) -> bool:
        """True when every criterion holds."""
        return all(c.passed for c in self.criteria.values())

    @property
    def binding(self) -> tuple[str, ...]:
        """Shape criteria within :data:`BINDING_MARGIN` of their limit (at least the tightest)."""
        shape = [self.criteria[n] for n in _SHAPE_CRITERIA]
        close = tuple(c.name for c in sorted(shape, key=lambda c: c.margin)
                      if c.margin < BINDING_MARGIN)
        return close or (min(shape, key=lambda c: c.margin).name,)

    def fourbar(self) -> FourBar:
        """The linkage as a :class:`FourBar` (lengths in mm)."""
        return FourBar(self.a, self.b, self.c, self.d)

    def as_dict(self) -> dict:
        """Plain data: lengths [mm] and every criterion's value, limit, pass and margin."""
        out = {"a": self.a, "b": self.b, "c": self.c, "d": self.d,
               "swing_deg": self.swing_deg, "mu1_deg": self.mu1_deg, "mu2_deg": self.mu2_deg,
               "phi1_dd": self.phi1_dd, "phi2_dd": self.phi2_dd,
               "feasible": self.feasible, "binding": list(self.binding),
               "objective": self.objective}
        out["criteria"] = {n: {"value": c.value, "limit": c.limit, "passed": c.passed,
                               "margin": c.margin} for n, c in self.criteria.items()}
        return out


@dataclass(frozen=True)
class SynthesisResult:
    """Outcome of :func:`synthesize`.

    Attributes
    ----------
    designs : tuple of Design
        Feasible designs, best first.
    objective : str
        How they are ranked, in words.
    load : str
        Loom class.
    swing_deg : tuple of float
        Swing values explored [deg].
    explored : int
        Assemblable crank-rockers examined (grid points with an eq. (10) root).
    rejected : dict[str, int]
        How many of them each criterion rejects.
    conflicts : tuple of tuple of str
        When no design is feasible: the smallest sets of criteria that no
        examined design meets together.
    """

    designs: tuple
    objective: str
    load: str
    swing_deg: tuple
    explored: int
    rejected: dict
    conflicts: tuple = field(default=())

    @property
    def message(self) -> str:
        """One sentence: how many designs, or why there are none."""
        if self.designs:
            return (f"{len(self.designs)} feasible design(s) for a {self.load} loom, "
                    f"ranked to {self.objective}")
        if self.explored == 0:
            return (f"no crank-rocker on the explored grid reaches a swing of "
                    f"{', '.join(f'{s:g}' for s in self.swing_deg)}° (eq. 10 has no "
                    f"admissible root); widen b_a_range/d_a_range or change the swing")
        sets = "; ".join(" + ".join(c) for c in self.conflicts) or "all criteria together"
        return (f"no design meets every criterion among {self.explored} explored crank-rockers; "
                f"these criteria cannot hold together: {sets}")

    def as_dict(self) -> dict:
        return {"designs": [d.as_dict() for d in self.designs], "objective": self.objective,
                "message": self.message,
                "load": self.load, "swing_deg": list(self.swing_deg),
                "explored": self.explored, "rejected": self.rejected,
                "conflicts": [list(c) for c in self.conflicts]}


# --------------------------------------------------------------- the equations
def dead_centre_angles(b_a, c_a, d_a):
    """Eq. (1): angles BCD at the front and back dead centres (μ1, μ2) [rad].

    Parameters
    ----------
    b_a, c_a, d_a : array_like
        Ratios b/a, c/a, d/a [1].

    Returns
    -------
    mu1, mu2 : ndarray
        In [0, π]; NaN where the triangle does not close.
    """
    b_a, c_a, d_a = (np.asarray(x, dtype=float) for x in (b_a, c_a, d_a))
    with np.errstate(invalid="ignore", divide="ignore"):
        c1 = (c_a ** 2 + (1 + b_a) ** 2 - d_a ** 2) / (2 * (1 + b_a) * c_a)
        c2 = (c_a ** 2 + (b_a - 1) ** 2 - d_a ** 2) / (2 * (b_a - 1) * c_a)
        return np.arccos(c1), np.arccos(c2)


def acceleration_ratio_eq5(b_a, mu1, mu2):
    """Eq. (5): |Φ1''/Φ2''| = ((b/a + 1)/(b/a − 1)) · sin μ2 / sin μ1 [1]."""
    b_a = np.asarray(b_a, dtype=float)
    return (b_a + 1) / (b_a - 1) * np.sin(mu2) / np.sin(mu1)


def eq10_residual(psi, b_a, c_a, d_a):
    """Left-hand side of eq. (10), exactly as the patent writes it [1].

    (M − P)² + (N − P)² − 2 cos Ψ (M − P)(N − P) + cos² Ψ − 1 with
    M = (b/a − 1)²/(2(c/a)(d/a)), N = (b/a + 1)²/(2(c/a)(d/a)),
    P = (c² + d²)/(2cd); Ψ [rad].
    """
    two_cd = 2 * c_a * d_a
    M = (b_a - 1) ** 2 / two_cd
    N = (b_a + 1) ** 2 / two_cd
    P = (c_a ** 2 + d_a ** 2) / two_cd
    cp = math.cos(psi) if np.ndim(psi) == 0 else np.cos(psi)
    return (M - P) ** 2 + (N - P) ** 2 - 2 * cp * (M - P) * (N - P) + cp * cp - 1


def _eq10_roots_squared(psi, b_a, other):
    """Positive roots u = κ² (or δ²) of eq. (10) as a quadratic; vectorised, NaN if none.

    Returns two arrays (larger root, smaller root).
    """
    cp, sp2 = np.cos(psi), np.sin(psi) ** 2
    o2 = other * other
    k1 = o2 - (b_a + 1) ** 2
    k2 = o2 - (b_a - 1) ** 2
    A = 2 - 2 * cp
    B = 2 * (k1 + k2) * (1 - cp) - 4 * o2 * sp2
    C = k1 * k1 + k2 * k2 - 2 * cp * k1 * k2
    disc = B * B - 4 * A * C
    with np.errstate(invalid="ignore"):
        sq = np.sqrt(disc)
        u1 = (-B + sq) / (2 * A)
        u2 = (-B - sq) / (2 * A)
    u1 = np.where(u1 > 0, u1, np.nan)
    u2 = np.where(u2 > 0, u2, np.nan)
    return u1, u2


def solve_eq10(swing: float, b_a: float, *, c_a: float | None = None,
               d_a: float | None = None, tol: float = 1e-9) -> tuple[float, ...]:
    """Solve eq. (10) for c/a (given d/a) or for d/a (given c/a).

    Parameters
    ----------
    swing : float
        Swing Ψ [rad], in (0, π).
    b_a : float
        b/a [1], > 1.
    c_a, d_a : float
        Give exactly one; the other is solved for.
    tol : float
        Accept a root when the swing of the resulting linkage matches Ψ to
        this absolute tolerance [rad].

    Returns
    -------
    tuple of float
        The roots, ascending, for which the linkage (a = 1) is a crank-rocker
        whose own swing (:meth:`FourBar.swing`) equals Ψ.  Roots of the
        quartic that belong to another configuration are dropped.

    Raises
    ------
    GeometryError
        Neither or both of ``c_a`` and ``d_a`` given, or b/a ≤ 1, or Ψ outside (0, π).
    """
    if (c_a is None) == (d_a is None):
        raise GeometryError("solve_eq10 needs exactly one of c_a and d_a")
    if not b_a > 1:
        raise GeometryError(f"eq. (10) needs b/a > 1 (a crank shorter than the coupler), got {b_a}")
    if not 0 < swing < math.pi:
        raise GeometryError(f"swing must be in (0, π) rad, got {swing}")
    given = c_a if c_a is not None else d_a
    roots = []
    for u in _eq10_roots_squared(swing, b_a, float(given)):
        if not np.isfinite(u):
            continue
        x = math.sqrt(float(u))
        c, d = (x, given) if c_a is None else (given, x)
        try:
            fb = FourBar(1.0, b_a, c, d)
            ok = (fb.linkage_type == "crank-rocker" and fb.crank_rotates_fully
                  and abs(fb.swing() - swing) <= tol)
        except GeometryError:
            ok = False
        if ok:
            roots.append(x)
    return tuple(sorted(set(roots)))


# ------------------------------------------------------------ one design
def _crit(name, value, limit_text, margin):
    return Criterion(name, float(value), limit_text, bool(margin > 0), float(margin))


def evaluate_design(a: float, b: float, c: float, d: float, *,
                    load: str | None = None) -> Design:
    """Evaluate every patent criterion for the four-bar a, b, c, d [mm], directly.

    Dead-centre accelerations come from :class:`FourBar` (not eq. (5)); the
    swing is the linkage's own.  ``load`` picks the crank range of step 1
    (default: any of 33–38 mm).

    Raises
    ------
    GeometryError
        The lengths do not make a crank-rocker.
    """
    fb = FourBar(a, b, c, d)
    front, back = fb.dead_centres()            # raises for a non-crank-rocker
    lo, hi = LOAD_CRANK_MM[load] if load else (33.0, 38.0)
    mu1, mu2 = (math.degrees(x) for x in dead_centre_angles(b / a, c / a, d / a))
    gamma1 = min(mu1, 180.0 - mu1)
    gmin = math.degrees(fb.transmission_range().gamma_min)
    ratio = abs(back.nu) / abs(front.nu)
    swing = math.degrees(fb.swing())
    bound = (b / a) * (360.0 / swing) / (2 * math.pi)
    crit = {
        "crank_length": _crit("crank_length", a, f"{lo:g}–{hi:g} mm",
                              min(a - lo, hi - a) / (hi - lo) if hi > lo else 0.0),
        "front_transmission": _crit("front_transmission", gamma1,
                                    f"> {FRONT_TRANSMISSION_MIN_DEG:g}°",
                                    (gamma1 - FRONT_TRANSMISSION_MIN_DEG) / FRONT_TRANSMISSION_MIN_DEG),
        "min_transmission": _crit("min_transmission", gmin, f"> {MIN_TRANSMISSION_MIN_DEG:g}°",
                                  (gmin - MIN_TRANSMISSION_MIN_DEG) / MIN_TRANSMISSION_MIN_DEG),
        "acceleration_ratio": _crit("acceleration_ratio", ratio, f"< {ACCELERATION_RATIO_MAX:g}",
                                    (ACCELERATION_RATIO_MAX - ratio) / ACCELERATION_RATIO_MAX),
        "frame_length": _crit("frame_length", d, f"< {FRAME_MAX_MM:g} mm",
                              (FRAME_MAX_MM - d) / FRAME_MAX_MM),
        "rocker_ratio": _crit("rocker_ratio", c / a, f"> {bound:.4g}", (c / a - bound) / bound),
        "swing": _crit("swing", swing, f"{SWING_RANGE_DEG[0]:g}–{SWING_RANGE_DEG[1]:g}°",
                       min(swing - SWING_RANGE_DEG[0], SWING_RANGE_DEG[1] - swing)
                       / (SWING_RANGE_DEG[1] - SWING_RANGE_DEG[0])),
    }
    # crank_length and swing: a value exactly on the closed range is allowed
    for name in ("crank_length", "swing"):
        cr = crit[name]
        if cr.margin == 0.0 or abs(cr.margin) < 1e-12:
            crit[name] = Criterion(cr.name, cr.value, cr.limit, True, 0.0)
    return Design(a, b, c, d, crit, mu1, mu2, front.nu, back.nu, swing)


# --------------------------------------------------------------- synthesis
_OBJECTIVES = {
    "margin": "maximise the smallest relative margin of the shape criteria "
              "(eq. 2, 3, 4–6, 8, 9): the design farthest from every limit",
    "ratio": "minimise |Φ2''|/|Φ1''| (eq. 4–6): the calmest back dead centre",
}


def synthesize(load: Literal["light", "medium", "heavy"] = "medium",
               swing: float | None = None, *,
               objective: Literal["margin", "ratio"] = "margin",
               limit: int = 10, b_a_range=(1.5, 8.0), d_a_range=(1.5, 8.0),
               step: float = 0.05, crank_step: float = 0.5,
               swing_step: float = 0.5) -> SynthesisResult:
    """Explore the patent's feasible region and rank the designs that meet every criterion.

    Parameters
    ----------
    load : {"light", "medium", "heavy"}
        Loom class; fixes the crank range (step 1).
    swing : float, optional
        Swing Ψ [deg]; default: every ``swing_step`` over 23–26°.
    objective : {"margin", "ratio"}
        "margin" (default): maximise the smallest relative margin of the
        shape criteria; "ratio": minimise |Φ2''|/|Φ1''|.
    limit : int
        Number of designs returned.
    b_a_range, d_a_range : (float, float)
        Ranges of b/a and d/a explored, in steps of ``step``; c/a follows
        from eq. (10).  d/a is also capped by d < 180 mm.
    crank_step : float
        Crank lengths explored within the load's range [mm].

    Returns
    -------
    SynthesisResult
        Designs best first, each with its binding criteria; if none is
        feasible, ``conflicts`` names the criteria that cannot hold together.

    Raises
    ------
    GeometryError
        Unknown load, a swing outside (0°, 180°), or an empty grid.

    Notes
    -----
    The grid is screened with closed forms (eq. 1, 3, 5, 8, 9 and the swing
    from the dead-centre triangles), vectorised; the best screened designs are
    then re-evaluated directly (:func:`evaluate_design`) and any whose direct
    evaluation disagrees is dropped.
    """
    if load not in LOAD_CRANK_MM:
        raise GeometryError(f"unknown load {load!r}; expected one of "
                            f"{', '.join(LOAD_CRANK_MM)}")
    if objective not in _OBJECTIVES:
        raise GeometryError(f"unknown objective {objective!r}; expected one of "
                            f"{', '.join(_OBJECTIVES)}")
    if swing is not None and not 0 < swing < 180:
        raise GeometryError(f"swing must be in (0°, 180°), got {swing}°")
    lo, hi = LOAD_CRANK_MM[load]
    cranks = np.arange(lo, hi + 1e-9, crank_step)
    swings = (np.array([float(swing)]) if swing is not None else
              np.arange(SWING_RANGE_DEG[0], SWING_RANGE_DEG[1] + 1e-9, swing_step))
    b_as = np.arange(b_a_range[0], b_a_range[1] + 1e-9, step)
    d_as = np.arange(d_a_range[0], d_a_range[1] + 1e-9, step)
    if b_as.size == 0 or d_as.size == 0:
        raise GeometryError("empty synthesis grid: check b_a_range, d_a_range and step")

    A, PSI, BA, DA = (g.ravel() for g in np.meshgrid(cranks, np.radians(swings), b_as, d_as,
                                                     indexing="ij"))
    u1, u2 = _eq10_roots_squared(PSI, BA, DA)
    A, PSI, BA, DA = (np.concatenate([x, x]) for x in (A, PSI, BA, DA))
    with np.errstate(invalid="ignore"):
        CA = np.sqrt(np.concatenate([u1, u2]))
    cols = _screen(A, PSI, BA, CA, DA)
    valid = cols.pop("_valid")
    explored = int(valid.sum())
    passes = {name: cols[name][0] & valid for name in _SHAPE_CRITERIA}
    psi_deg = np.degrees(PSI)
    passes["swing"] = valid & (psi_deg >= SWING_RANGE_DEG[0] - 1e-9) \
        & (psi_deg <= SWING_RANGE_DEG[1] + 1e-9)
    rejected = {name: int((valid & ~p).sum()) for name, p in passes.items()}
    ok = valid.copy()
    for p in passes.values():
        ok &= p

    if not ok.any():
        conflicts = _conflicts(passes, valid)
        return SynthesisResult((), _OBJECTIVES[objective], load, tuple(swings.tolist()),
                               explored, rejected, conflicts)

    idx = np.flatnonzero(ok)
    if objective == "margin":
        score = np.min(np.stack([cols[n][1][idx] for n in _SHAPE_CRITERIA]), axis=0)
        order = idx[np.argsort(-score, kind="stable")]
    else:
        order = idx[np.argsort(cols["acceleration_ratio"][2][idx], kind="stable")]

    designs, seen = [], set()
    for k in order:
        a = float(A[k])
        key = tuple(round(float(x), 9) for x in (a, BA[k], CA[k], DA[k]))
        if key in seen:
            continue
        seen.add(key)
        try:
            des = evaluate_design(a, a * BA[k], a * CA[k], a * DA[k], load=load)
        except GeometryError:
            continue
        if not des.feasible or abs(des.swing_deg - math.degrees(PSI[k])) > 1e-6:
            continue            # eq. (10) root of the mirror configuration, or a screen slip
        value = (min(des.criteria[n].margin for n in _SHAPE_CRITERIA) if objective == "margin"
                 else des.criteria["acceleration_ratio"].value)
        designs.append(dataclasses.replace(des, objective=value))
        if len(designs) >= limit:
            break
    return SynthesisResult(tuple(designs), _OBJECTIVES[objective], load,
                           tuple(swings.tolist()), explored, rejected)


def _screen(A, PSI, BA, CA, DA):
    """Closed-form criteria on arrays: name -> (passes, relative margin, value)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        mu1, mu2 = dead_centre_angles(BA, CA, DA)
        # crank-rocker: crank shortest and Grashof (a = 1)
        longest = np.maximum(np.maximum(BA, CA), DA)
        grashof = (1 + longest < BA + CA + DA - longest) & (BA > 1) & (CA > 1) & (DA > 1)
        alpha_f = np.arccos((CA ** 2 + DA ** 2 - (BA + 1) ** 2) / (2 * CA * DA))
        alpha_b = np.arccos((CA ** 2 + DA ** 2 - (BA - 1) ** 2) / (2 * CA * DA))
        # the screen keeps roots with C on one side of the frame line at both dead
        # centres; on the default grid (Ψ ≤ 26°) no crank-rocker root of the
        # crossing configuration (swing α_f + α_b) exists, checked by brute force
        same_side_swing = np.abs(alpha_f - alpha_b)
        valid = (np.isfinite(CA) & grashof & np.isfinite(mu1) & np.isfinite(mu2)
                 & (np.abs(same_side_swing - PSI) < 1e-7))
        g1 = np.degrees(np.minimum(mu1, np.pi - mu1))
        # interior angle extremes at BD = d ± a
        def acute_at(bd):
            ang = np.arccos(np.clip((BA ** 2 + CA ** 2 - bd ** 2) / (2 * BA * CA), -1, 1))
            return np.minimum(ang, np.pi - ang)
        gmin = np.degrees(np.minimum(acute_at(DA - 1), acute_at(DA + 1)))
        ratio = 1.0 / acceleration_ratio_eq5(BA, mu1, mu2)
        d_mm = A * DA
        bound = BA / PSI
    out = {"_valid": valid}
    for name, value, margin in (
            ("front_transmission", g1, (g1 - FRONT_TRANSMISSION_MIN_DEG) / FRONT_TRANSMISSION_MIN_DEG),
            ("min_transmission", gmin, (gmin - MIN_TRANSMISSION_MIN_DEG) / MIN_TRANSMISSION_MIN_DEG),
            ("acceleration_ratio", ratio, (ACCELERATION_RATIO_MAX - ratio) / ACCELERATION_RATIO_MAX),
            ("frame_length", d_mm, (FRAME_MAX_MM - d_mm) / FRAME_MAX_MM),
            ("rocker_ratio", CA, (CA - bound) / bound)):
        margin = np.where(valid, margin, -np.inf)
        out[name] = (margin > 0, margin, value)
    return out


def _conflicts(passes: dict, valid) -> tuple[tuple[str, ...], ...]:
    """Minimal sets of criteria that no valid design meets together (no set contains another)."""
    if not valid.any():
        return ()                # nothing assemblable to compare: see SynthesisResult.message
    names = list(passes)
    found: list[tuple[str, ...]] = []
    for size in range(1, len(names) + 1):
        for combo in itertools.combinations(names, size):
            if any(set(f) <= set(combo) for f in found):
                continue
            joint = valid.copy()
            for n in combo:
                joint &= passes[n]
            if not joint.any():
                found.append(combo)
    return tuple(found)
