"""Beat-up four-bar synthesis after patent CN104178888.

The crank-rocker ABCD has crank AB = a, coupler BC = b, rocker CD = c and
frame AD = d [mm]; ratios are written β = b/a, κ = c/a, δ = d/a.  The front
dead centre (beat-up) has crank and coupler extended in line, the back dead
centre has them folded; Φ1'', Φ2'' are d²Φ/dθ² there [1/rad] and the swing is
Ψ = |Φ2 − Φ1|.  The patent's criteria, with the patent's equation numbers:

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
(sin μ2 / sin μ1), is used only to screen a grid quickly: :func:`synthesize`
screens its grid with closed forms (eq. 1, 3, 5, 8, 9 and the swing from the
dead-centre triangles), vectorised, then re-evaluates the best screened designs
directly (:func:`evaluate_design`, with :class:`~mechcirc.kinematics.FourBar`)
and drops any whose direct evaluation disagrees.

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

import contextlib
import dataclasses
import itertools
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ..errors import GeometryError
from ..sources import did_you_mean, summary_repr
from .fourbar import FourBar

__all__ = [
    "LOAD_CRANK_MM", "Criterion", "Design", "SynthesisResult",
    "dead_centre_angles", "acceleration_ratio_eq5", "solve_eq10",
    "evaluate_design", "synthesize",
]

#: Crank length range [mm] by loom class (patent step 1).
LOAD_CRANK_MM: dict[str, tuple[float, float]] = {
    "light": (33.0, 34.0), "medium": (35.0, 36.0), "heavy": (37.0, 38.0)}

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
        ``crank_length``, ``front_transmission``, ``min_transmission``,
        ``acceleration_ratio``, ``frame_length``, ``rocker_ratio`` or ``swing``.
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
        Every criterion (:attr:`Criterion.name`), by name.
    mu1_deg, mu2_deg : float
        Angles BCD at the front and back dead centres, eq. (1) [deg].
    phi1_dd, phi2_dd : float
        d²Φ/dθ² at the front and back dead centres [1/rad].
    swing_deg : float
        Swing Ψ computed from the linkage [deg].
    """

    __repr__ = summary_repr

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
    grid_objective: float = float("nan")

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
        return {"a": self.a, "b": self.b, "c": self.c, "d": self.d,
                "swing_deg": self.swing_deg, "mu1_deg": self.mu1_deg, "mu2_deg": self.mu2_deg,
                "phi1_dd": self.phi1_dd, "phi2_dd": self.phi2_dd,
                "feasible": self.feasible, "binding": list(self.binding),
                "objective": self.objective, "grid_objective": self.grid_objective,
                "shape": {"b_a": self.b / self.a, "c_a": self.c / self.a, "d_a": self.d / self.a},
                "criteria": {n: {"value": c.value, "limit": c.limit, "passed": c.passed,
                                 "margin": c.margin} for n, c in self.criteria.items()}}


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

    __repr__ = summary_repr

    designs: tuple
    objective: str
    load: str
    swing_deg: tuple
    explored: int
    rejected: dict
    conflicts: tuple = field(default=())
    swing_range: tuple = SWING_RANGE_DEG
    fixed: dict = field(default_factory=dict)
    refined: bool = False

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
                "conflicts": [list(c) for c in self.conflicts],
                "swing_range_deg": list(self.swing_range), "fixed_mm": dict(self.fixed),
                "refined": self.refined}


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
    """Eq. (5): |Φ1''/Φ2''| = ((b/a + 1)/(b/a − 1)) · sin μ2 / sin μ1 [1].

    Parameters
    ----------
    b_a : float or ndarray
        b/a.
    mu1, mu2 : float or ndarray
        Angles BCD at the front and back dead centres [rad].

    Returns
    -------
    float or ndarray
    """
    b_a = np.asarray(b_a, dtype=float)
    return (b_a + 1) / (b_a - 1) * np.sin(mu2) / np.sin(mu1)



def _eq10_roots_squared(psi, b_a, other):
    """Positive roots u = κ² (or δ²) of eq. (10) as a quadratic A·u² + B·u + C = 0 in
    u = κ² (or δ²); vectorised, NaN if none.

    Returns two arrays (larger root, smaller root).
    """
    cp, o2 = np.cos(psi), other * other
    k1 = o2 - (b_a + 1) ** 2
    k2 = o2 - (b_a - 1) ** 2
    A = 2 - 2 * cp
    B = 2 * (k1 + k2) * (1 - cp) - 4 * o2 * np.sin(psi) ** 2
    C = k1 * k1 + k2 * k2 - 2 * cp * k1 * k2
    with np.errstate(invalid="ignore"):
        sq = np.sqrt(B * B - 4 * A * C)
        return tuple(np.where(u > 0, u, np.nan) for u in ((-B + sq) / (2 * A), (-B - sq) / (2 * A)))


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
    given = c_a if c_a is not None else d_a
    if given is None or (c_a is not None and d_a is not None):
        raise GeometryError("solve_eq10 needs exactly one of c_a and d_a")
    if not b_a > 1:
        raise GeometryError(f"eq. (10) needs b/a > 1 (a crank shorter than the coupler), got {b_a}")
    if not 0 < swing < math.pi:
        raise GeometryError(f"swing must be in (0, π) rad, got {swing}")
    roots = []
    for u in _eq10_roots_squared(swing, b_a, float(given)):
        if not np.isfinite(u):
            continue
        x = math.sqrt(float(u))
        c, d = (x, given) if c_a is None else (given, x)
        with contextlib.suppress(GeometryError):
            fb = FourBar(1.0, b_a, c, d)
            if fb.is_full_turn_crank_rocker and abs(fb.swing() - swing) <= tol:
                roots.append(x)
    return tuple(sorted(set(roots)))


# ------------------------------------------------------------ one design
def _crit(name, value, limit_text, margin, closed: bool = False):
    """The criterion ``name``; on a ``closed`` range a value exactly on an end (margin within
    1e-9 of 0) passes, with margin 0."""
    if closed and abs(margin) < 1e-9:
        return Criterion(name, float(value), limit_text, True, 0.0)
    return Criterion(name, float(value), limit_text, bool(margin > 0), float(margin))


def evaluate_design(a: float, b: float, c: float, d: float, *,
                    load: str | None = None, swing_range: tuple = SWING_RANGE_DEG,
                    crank_range: tuple | None = None) -> Design:
    """Evaluate every patent criterion for the four-bar a, b, c, d [mm], directly.

    Dead-centre accelerations come from :class:`FourBar` (not eq. (5)); the
    swing is the linkage's own.  ``load`` picks the crank range of step 1
    (default: any of 33–38 mm); ``crank_range`` [mm] overrides it (a crank
    length the user fixed).  ``swing_range`` [deg] is the swing criterion.

    Parameters
    ----------
    a, b, c, d : float
        Crank, coupler, rocker and frame lengths [mm].
    load : str, optional
        Picks the crank range of step 1 (default: any of 33–38 mm).
    swing_range : tuple of float
        (min, max) of the rocker's swing [deg] that passes the swing criterion.
    crank_range : tuple of float, optional
        (min, max) crank length [mm]; overrides the range ``load`` picks.

    Returns
    -------
    Design
        The criteria's values and whether each passes.

    Raises
    ------
    GeometryError
        The lengths do not make a crank-rocker.
    """
    fb = FourBar(a, b, c, d)
    front, back = fb.dead_centres()            # raises for a non-crank-rocker
    crank_range = crank_range or (LOAD_CRANK_MM[load] if load else (33.0, 38.0))
    mu1, mu2 = (math.degrees(x) for x in dead_centre_angles(b / a, c / a, d / a))
    swing = math.degrees(fb.swing())
    crit = _criteria(a, b, c, d, min(mu1, 180.0 - mu1),
                     math.degrees(fb.transmission_range().gamma_min),
                     abs(back.nu) / abs(front.nu), swing, crank_range, swing_range)
    return Design(a, b, c, d, crit, mu1, mu2, front.nu, back.nu, swing)


def _criteria(a, b, c, d, gamma1, gmin, ratio, swing, crank_range, swing_range):
    """The patent's criteria judged for lengths a, b, c, d [mm] with front transmission
    angle ``gamma1``, least one ``gmin``, swing ``swing`` [deg] and acceleration ratio
    ``ratio``; a value exactly on the closed crank or swing range passes."""
    lo, hi = crank_range
    s_lo, s_hi = swing_range
    bound = (b / a) * (360.0 / swing) / (2 * math.pi)
    limits = {"front_transmission": f"> {FRONT_TRANSMISSION_MIN_DEG:g}°",
              "min_transmission": f"> {MIN_TRANSMISSION_MIN_DEG:g}°",
              "acceleration_ratio": f"< {ACCELERATION_RATIO_MAX:g}",
              "frame_length": f"< {FRAME_MAX_MM:g} mm", "rocker_ratio": f"> {bound:.4g}"}
    crit = {"crank_length": _crit("crank_length", a, f"{lo:g}–{hi:g} mm",
                                  min(a - lo, hi - a) / (hi - lo) if hi > lo else 0.0, True)}
    for name, (value, margin) in _shape_margins(gamma1, gmin, ratio, d, c / a, bound).items():
        crit[name] = _crit(name, value, limits[name], margin)
    crit["swing"] = _crit("swing", swing, f"{s_lo:g}–{s_hi:g}°",
                          min(swing - s_lo, s_hi - swing) / (s_hi - s_lo) if s_hi > s_lo
                          else -abs(swing - s_lo) / s_lo, True)
    return crit


# --------------------------------------------------------------- synthesis
_OBJECTIVES = {
    "margin": "maximise the smallest relative margin of the shape criteria "
              "(eq. 2, 3, 4–6, 8, 9): the design farthest from every limit",
    "ratio": "minimise |Φ2''|/|Φ1''| (eq. 4–6): the calmest back dead centre",
}


_FIXABLE = ("crank", "coupler", "rocker", "frame")


def synthesize(load: Literal["light", "medium", "heavy"] = "medium", swing: float | None = None,
               *, objective: Literal["margin", "ratio"] = "margin", limit: int = 10,
               b_a_range=(1.5, 8.0), d_a_range=(1.5, 8.0), step: float = 0.05,
               crank_step: float = 0.5, swing_step: float = 0.5, swing_range: tuple | None = None,
               fixed: dict | None = None, refine: bool = True) -> SynthesisResult:
    """Explore the patent's feasible region and rank the designs that meet every criterion.

    Parameters
    ----------
    load : {"light", "medium", "heavy"}
        Loom class; fixes the crank range (step 1).
    swing : float, optional
        Swing Ψ [deg], fixed (still judged by ``swing_range``); default: the grid of ``swing_step``.
    objective : {"margin", "ratio"}
        "margin" (default): maximise the smallest relative margin of the
        shape criteria; "ratio": minimise |Φ2''|/|Φ1''|.
    limit : int
        Number of designs returned (distinct shapes).
    b_a_range, d_a_range : (float, float)
        Ranges of b/a and d/a explored, in steps of ``step`` (c/a from eq. (10);
        d < 180 mm caps d/a); the refinement stays inside them.
    step : float
        Grid step of b/a and d/a [1].
    crank_step : float
        Crank lengths explored within the load's range [mm].
    swing_step : float
        Grid step of the swing [deg].
    swing_range : (float, float), optional
        Admissible swing [deg] of the criterion and the grid (default 23–26°).
    fixed : dict, optional
        Lengths held fixed [mm] by name: "crank" (replaces the load's range),
        "coupler", "rocker" or "frame" (not both of the last two).
    refine : bool
        Improve each grid candidate by a bounded Nelder–Mead search of the objective over the free
        parameters (c/a or d/a, eq. (10)); kept if feasible when evaluated directly and no worse.

    Returns
    -------
    SynthesisResult
        Designs best first, one per shape b/a, c/a, d/a (scaled copies dropped), each with its
        binding criteria; if none is feasible, ``conflicts`` names the criteria in conflict.

    Raises
    ------
    GeometryError
        Unknown load, a swing outside (0°, 180°), a bad fixed length, a grid too large.
    """
    fixed, s_range, crank_range = _checked(load, objective, fixed, swing, swing_range, b_a_range,
                                           d_a_range, step, crank_step, swing_step)
    space = _Space(fixed, b_a_range, d_a_range, crank_range, s_range, swing)
    axes = space.grid_axes(step, crank_step, swing_step)
    grid, cols, valid, passes = _screened_grid(space, *axes)
    rejected = {name: int((valid & ~p).sum()) for name, p in passes.items()}
    ok = np.logical_and.reduce([valid, *passes.values()])
    designs = _candidates(grid, cols, ok, space, objective, limit, refine)
    return SynthesisResult(tuple(designs), _OBJECTIVES[objective], load,
                           tuple(axes[1].tolist()), int(valid.sum()), rejected,
                           () if ok.any() else _conflicts(passes, valid), s_range, fixed, refine)


def _checked(load, objective, fixed, swing, swing_range, b_a_range, d_a_range, step,
             crank_step, swing_step):
    """The arguments of :func:`synthesize` checked: (fixed lengths, swing range, crank range)."""
    _known("load", load, LOAD_CRANK_MM)
    _known("objective", objective, _OBJECTIVES)
    fixed = dict(fixed or {})
    for name, value in fixed.items():
        _known("fixed length", name, _FIXABLE)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and 0 < value < 1e6):
            raise GeometryError(f"fixed {name} length must be a positive number of mm, got "
                                f"{value!r}")
    if "rocker" in fixed and "frame" in fixed:
        raise GeometryError("fix the rocker or the frame, not both: eq. (10) then fixes b/a, "
                            "which is not searched for")
    s_range = tuple(float(x) for x in (swing_range or SWING_RANGE_DEG))
    if not (len(s_range) == 2 and 0 < s_range[0] <= s_range[1] < 180):
        raise GeometryError(f"swing range must be 0 < low ≤ high < 180 degrees, got {s_range}")
    if swing is not None and not 0 < swing < 180:
        raise GeometryError(f"swing must be in (0°, 180°), got {swing}°")
    for name, rng in (("b_a_range", b_a_range), ("d_a_range", d_a_range)):
        if not (len(rng) == 2 and 1 < rng[0] <= rng[1] < 1e3):
            raise GeometryError(f"{name} must be 1 < low ≤ high < 1000, got {tuple(rng)}")
    if not (step > 0 and crank_step > 0 and swing_step > 0):
        raise GeometryError("step, crank_step and swing_step must be > 0")
    return fixed, s_range, (fixed["crank"],) * 2 if "crank" in fixed else LOAD_CRANK_MM[load]


def _known(what: str, value, known) -> None:
    """Refuse a ``value`` not among the names ``known``."""
    if value not in known:
        raise GeometryError(f"unknown {what} {value!r}; expected one of {', '.join(known)}"
                            f"{did_you_mean(str(value), known)}")


def _screened_grid(space, cranks, swings, b_as, d_as):
    """Every grid point (both eq. (10) roots) screened by the closed forms.

    Returns ((A, PSI, BA, OTHER, ROOT, CA, DA), the screen's columns, the
    valid mask, each criterion's pass mask).
    """
    A, PSI, BA, OTHER = (g.ravel() for g in np.meshgrid(
        cranks, np.radians(swings), [np.nan] if "coupler" in space.fixed else b_as,
        [np.nan] if {"rocker", "frame"} & set(space.fixed) else d_as, indexing="ij"))
    BA, OTHER = space.ratios(A, BA, OTHER)
    u1, u2 = _eq10_roots_squared(PSI, BA, OTHER)
    A, PSI, BA, OTHER = (np.concatenate([x, x]) for x in (A, PSI, BA, OTHER))
    ROOT = np.repeat([0, 1], u1.size)
    with np.errstate(invalid="ignore"):
        X = np.sqrt(np.concatenate([u1, u2]))
    CA, DA = space.split(X, OTHER)
    cols = _screen(A, PSI, BA, CA, DA)
    valid = cols.pop("_valid")
    passes = {name: cols[name][0] & valid for name in _SHAPE_CRITERIA}
    (s_lo, s_hi), psi_deg = space.swing_range, np.degrees(PSI)
    passes["swing"] = valid & (psi_deg >= s_lo - 1e-9) & (psi_deg <= s_hi + 1e-9)
    if space.limits_in_ratio:
        # a fixed length makes a ratio follow the crank: keep it in its range
        passes["ratio_ranges"] = valid & space.in_ranges(BA, DA)
    return (A, PSI, BA, OTHER, ROOT, CA, DA), cols, valid, passes


def _candidates(grid, cols, ok, space, objective, limit, refine):
    """The passing grid points evaluated directly (and refined), one per shape, best first
    (judged on the search's crank and swing ranges)."""
    A, PSI, BA, OTHER, ROOT, CA, DA = grid
    idx = np.flatnonzero(ok)
    if objective == "margin":
        score = np.min(np.stack([cols[n][1][idx] for n in _SHAPE_CRITERIA]), axis=0)
        order = idx[np.argsort(-score, kind="stable")]
    else:
        order = idx[np.argsort(cols["acceleration_ratio"][2][idx], kind="stable")]

    def value_of(des):
        return (min(des.criteria[n].margin for n in _SHAPE_CRITERIA) if objective == "margin"
                else des.criteria["acceleration_ratio"].value)

    sign = -1.0 if objective == "margin" else 1.0       # ranks by sign · value, least first
    ranges = {"swing_range": space.swing_range, "crank_range": space.crank_range}
    designs, seen = [], set()
    for k in order:
        a = float(A[k])
        # one candidate per shape: the best-ranked crank length of each b/a, c/a, d/a
        shape = tuple(round(float(x), 9) for x in (BA[k], CA[k], DA[k]))
        if shape in seen:
            continue
        seen.add(shape)
        try:
            des = evaluate_design(a, a * BA[k], a * CA[k], a * DA[k], **ranges)
        except GeometryError:
            continue
        if not des.feasible or abs(des.swing_deg - math.degrees(PSI[k])) > 1e-6:
            continue            # eq. (10) root of the mirror configuration, or a screen slip
        grid_value = value_of(des)
        des = dataclasses.replace(des, objective=grid_value, grid_objective=grid_value)
        if any(_same_shape(des, other) for other in designs):
            continue
        if refine and (x := space.refine(objective, a, float(PSI[k]), float(BA[k]),
                                         float(OTHER[k]), int(ROOT[k]))) is not None:
            with contextlib.suppress(GeometryError):
                r = evaluate_design(*x, **ranges)
                # keep the refinement when it is feasible, no worse, and not
                # a shape already reported (several grid points often climb
                # to one optimum: the grid point then stands for itself)
                if r.feasible and sign * value_of(r) <= sign * grid_value and \
                        not any(_same_shape(r, other) for other in designs):
                    des = dataclasses.replace(r, objective=value_of(r), grid_objective=grid_value)
        designs.append(des)
        if len(designs) >= limit:
            break
    designs.sort(key=lambda d: sign * d.objective)
    return designs


#: Two designs whose b/a, c/a and d/a agree to this (relative) are one shape: the
#: grid's scaled copies agree exactly, refinements that end on one optimum to
#: the optimiser's tolerance (about 1e-5 here).
SAME_SHAPE_REL = 1e-3


def _same_shape(d1: Design, d2: Design, rel: float = SAME_SHAPE_REL) -> bool:
    """Equal b/a, c/a, d/a to ``rel`` (scaled copies of one linkage)."""
    r1, r2 = ((d.b / d.a, d.c / d.a, d.d / d.a) for d in (d1, d2))
    return all(abs(x - y) <= rel * abs(y) for x, y in zip(r1, r2))


class _Space:
    """The free parameters of a search and how the ratios follow from them.

    Parameters p = (a [mm], Ψ [rad], β = b/a, o) with o = δ = d/a (c/a solved
    from eq. 10) or, with the rocker fixed, o = κ = c/a (d/a solved).  A fixed
    coupler makes β = b/a, a fixed frame δ = d/a, a fixed rocker κ = c/a.
    """

    def __init__(self, fixed, b_a_range, d_a_range, crank_range, swing_range, swing):
        self.fixed = fixed
        self.b_a_range, self.d_a_range = tuple(b_a_range), tuple(d_a_range)
        self.crank_range, self.swing_range, self.swing = crank_range, swing_range, swing
        self.solve_d = "rocker" in fixed
        self.limits_in_ratio = bool({"coupler", "frame"} & set(fixed))

    def grid_axes(self, step, crank_step, swing_step):
        """The grid's cranks [mm], swings [deg], b/a and d/a, refused when too large.

        Each axis holds at least its low end (:func:`_checked` has low ≤ high), so the grid
        is never empty; its size is counted before any array is made, as ``np.arange``
        counts (ceil((stop − start)/step)).
        """
        lo, hi = self.crank_range

        def size(a, b, h):
            return math.ceil((b + 1e-9 - a) / h)

        n_grid = size(lo, hi, crank_step) * \
            (1 if self.swing is not None else size(*self.swing_range, swing_step)) * \
            (1 if "coupler" in self.fixed else size(*self.b_a_range, step)) * \
            (1 if {"rocker", "frame"} & set(self.fixed) else size(*self.d_a_range, step))
        if n_grid > 20_000_000:
            raise GeometryError(f"synthesis grid of {n_grid:.3g} points is too large (limit 2e7); "
                                f"use larger steps or narrower ranges")
        swings = (np.array([float(self.swing)]) if self.swing is not None else
                  np.arange(self.swing_range[0], self.swing_range[1] + 1e-9, swing_step))
        return (np.arange(lo, hi + 1e-9, crank_step), swings,
                np.arange(self.b_a_range[0], self.b_a_range[1] + 1e-9, step),
                np.arange(self.d_a_range[0], self.d_a_range[1] + 1e-9, step))

    def ratios(self, A, BA, OTHER):
        f = self.fixed
        if "coupler" in f:
            BA = f["coupler"] / A
        if "frame" in f:
            OTHER = f["frame"] / A
        elif "rocker" in f:
            OTHER = f["rocker"] / A
        return BA, OTHER

    def split(self, X, OTHER):
        """(c/a, d/a) from the eq. (10) root X and the other ratio."""
        return (OTHER, X) if self.solve_d else (X, OTHER)

    def in_ranges(self, BA, DA):
        (b0, b1), (d0, d1) = self.b_a_range, self.d_a_range
        return (BA >= b0 - 1e-12) & (BA <= b1 + 1e-12) & (DA >= d0 - 1e-12) & (DA <= d1 + 1e-12)

    def refine(self, objective, a, psi, ba, other, root):
        """Lengths (a, b, c, d) [mm] of the refined design, or None."""
        from scipy.optimize import minimize

        base = {"a": a, "psi": psi, "ba": ba, "other": other}
        free, x0, bounds = self.free_parameters(base)
        if not free:
            return None

        def cost(x):
            p = dict(base, **dict(zip(free, x)))
            shape = self.shape(p, root)
            if self.limits_in_ratio and not self.in_ranges(shape[2], shape[4]):
                return 1e6
            cols = _screen(*shape)
            if not cols["_valid"]:
                return 1e6
            worst = float(min(cols[n][1] for n in _SHAPE_CRITERIA))
            if objective == "margin":
                return -worst
            return float(cols["acceleration_ratio"][2]) if worst > 0 else 1e3 - worst

        res = minimize(cost, np.array(x0), method="Nelder-Mead", bounds=bounds,
                       options={"xatol": 1e-8, "fatol": 1e-11, "maxiter": 2000})
        if not np.isfinite(res.fun) or res.fun >= 1e3:
            return None
        return self.lengths(dict(base, **dict(zip(free, res.x))), root)

    def free_parameters(self, p):
        """The search's free parameters among ``p`` (a, psi, ba, other): their names,
        start values and bounds."""
        free, x0, bounds = [], [], []
        for name, rng, is_free in (
                ("a", self.crank_range, self.crank_range[1] > self.crank_range[0]),
                ("psi", tuple(math.radians(v) for v in self.swing_range),
                 self.swing is None and self.swing_range[1] > self.swing_range[0]),
                ("ba", self.b_a_range, "coupler" not in self.fixed),
                ("other", self.d_a_range, not {"rocker", "frame"} & set(self.fixed))):
            if is_free:
                free.append(name)
                x0.append(p[name])
                bounds.append(rng)
        return free, x0, bounds

    def shape(self, p, root):
        """(a, ψ, b/a, c/a, d/a) at the parameters ``p``, c/a or d/a from root ``root`` of
        eq. (10) (NaN where it has none)."""
        a, psi = p["a"], p["psi"]
        ba, other = self.ratios(a, p["ba"], p["other"])
        u = _eq10_roots_squared(psi, ba, other)[root]
        with np.errstate(invalid="ignore"):
            ca, da = self.split(np.sqrt(u), other)
        return a, psi, ba, ca, da

    def lengths(self, p, root):
        """Lengths (a, b, c, d) [mm] at the parameters ``p``, c/a or d/a from root
        ``root`` of eq. (10)."""
        a, _, ba, ca, da = (float(x) for x in self.shape(p, root))
        return a, a * ba, a * ca, a * da


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
    for name, (value, margin) in _shape_margins(g1, gmin, ratio, d_mm, CA, bound).items():
        margin = np.where(valid, margin, -np.inf)
        out[name] = (margin > 0, margin, value)
    return out


def _shape_margins(gamma1, gmin, ratio, d, c_a, bound):
    """The shape criteria (:data:`_SHAPE_CRITERIA`) on floats or arrays: name -> (value, relative
    margin), from the front and least transmission angles [deg], |Φ2''|/|Φ1''|, the frame [mm],
    c/a and the least c/a of eq. (9)."""
    return {"front_transmission": (gamma1, (gamma1 - FRONT_TRANSMISSION_MIN_DEG)
                                   / FRONT_TRANSMISSION_MIN_DEG),
            "min_transmission": (gmin, (gmin - MIN_TRANSMISSION_MIN_DEG) / MIN_TRANSMISSION_MIN_DEG),
            "acceleration_ratio": (ratio, (ACCELERATION_RATIO_MAX - ratio) / ACCELERATION_RATIO_MAX),
            "frame_length": (d, (FRAME_MAX_MM - d) / FRAME_MAX_MM),
            "rocker_ratio": (c_a, (c_a - bound) / bound)}


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
            if not np.logical_and.reduce([valid, *(passes[n] for n in combo)]).any():
                found.append(combo)
    return tuple(found)
