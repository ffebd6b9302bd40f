"""Fast position, velocity and acceleration analysis of a :class:`~.linkage.Linkage`.

Two solvers, chosen per linkage once (:func:`plan`):

* ``"dyads"`` — when every Assur group is a dyad (two links, three pairs:
  one inside, one to a known body on each link) with at most one slider —
  RRR, RRP (the slider an outer pair) or RPR (the slider inside) — each group
  is solved in closed form (:mod:`._dyad_forms`), vectorised over all crank
  positions: the RRR inner joint is the intersection of two circles, the RRP
  one of a circle and the guide's line, on the side where the pose puts it
  (the assembly mode, which fixes the branch for good); the RPR links turn
  so that the outer joints keep their distance across the sliding line.  The
  link rates (and the slide's) come from one 2×2 system per group, written
  out by Cramer's rule.  A four-bar costs about as much as
  :meth:`FourBar.evaluate`.
* ``"newton"`` — any other structure (a class-III group, say): Newton on the
  constraint equations Φ(q, t) = 0 with the analytic Jacobian, assembled from
  index arrays built once.  A sequential continuation visits coarse nodes at
  most ``max_step_deg`` of the fastest crank apart (Taylor predictor from the
  node's q, q̇, q̈; step halving; sign of det J tracked, a change is a branch
  jump); the requested positions are then solved together, batched, each
  started from the Taylor predictor of the node just before it, and their
  velocities and accelerations come from two batched linear solves.

With numba installed (the ``fast`` extra) Newton runs as one compiled loop over
the positions instead (:mod:`._linkage_kernels`): a sequential continuation
through every target, warm-started from the previous one, q̇ and q̈ from the LU
of J at each converged q — the same cost per position at 360 positions as at
3,600.  ``mechcirc._jit.COMPILED = False`` keeps the numpy Newton (tests run
both).  The numpy Newton is kept beside the kernel on purpose, by measurement:
the kernel run as Python, without numba, is 6–66× slower on the shipped
linkages.  The dyads are written once, in numpy, by the same measurement: a
compiled loop beside them made no shipped command faster, and as Python it was
14–47× slower (:mod:`._linkage_kernels`, docs/performance.md).

A change-point linkage (an RRR or RRP dyad lining up where its two assembly
modes cross; one crank) continues on the branch whose velocity is continuous, by
either solver: the crossings are located once per linkage, the dyad changes
sides at each, and positions within a small zone around it are interpolated
from the zone's ends (:func:`_solve`).

Both return a :class:`LinkageMotion` of plain arrays.  The result types
(:class:`LinkageState`, :class:`LinkageMotion`) live here, below
:mod:`.linkage`, which re-exports them, so the two modules import one way.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field, fields
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from .. import _jit
from ..errors import GeometryError, InputError, NetlistError, OutOfReach, did_you_mean
from ..motion_laws import quintic
from ..sources import brief, positive_number, real_values, summary_repr
from ._dyad_forms import im_conj, rpr, rrp, rrr, solve2

__all__ = ["LinkageMotion", "LinkageState", "MAX_CONTINUATION_STEPS", "plan", "motion"]


#: Most continuation steps :meth:`Linkage.solve` takes (about 20 s of work);
#: more is refused at once with the number needed.
MAX_CONTINUATION_STEPS = 100_000


@dataclass(frozen=True)
class LinkageState:
    """Positions, velocities and accelerations at one drive position.

    Attributes
    ----------
    theta : float
        Rotation of the first crank from the pose [rad].
    t : float
        Time θ/ω_1 [s].
    q, qdot, qddot : ndarray, shape (3n,)
        (x, y, φ) of each moving link's frame and their time derivatives.
    points, velocities, accelerations : dict[str, ndarray (2,)]
        Every named point [length], [length/s], [length/s²].
    angular_velocities : dict[str, float]
        φ̇ of each moving link [rad/s].
    contributions : dict[str, dict[str, ndarray (2,)]]
        Crank name → point → velocity with every other crank stopped [length/s].
    """

    __repr__ = summary_repr

    theta: float
    t: float
    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    qddot: NDArray[np.float64]
    points: dict
    velocities: dict
    accelerations: dict
    angular_velocities: dict
    contributions: dict

    # States made by LinkageMotion.states() fill the five dictionaries on first
    # access from rows shared by all the states of one solve: building 40-odd
    # small dicts and array views per position costs more than the solve.
    def __getattr__(self, name):
        rows = self.__dict__.get("_rows")
        if rows is None or name not in _LAZY_FIELDS:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        value = rows.field(name, self.__dict__["_i"])
        self.__dict__[name] = value
        return value

    def __getstate__(self):
        # plain data: every field, not the shared rows
        return {f: getattr(self, f) for f in _STATE_FIELDS}

    def as_dict(self) -> dict:
        """Plain data for JSON output."""
        return {
            "theta_deg": math.degrees(self.theta), "t": self.t,
            **{f: {k: v.tolist() for k, v in getattr(self, f).items()}
               for f in ("points", "velocities", "accelerations")},
            "angular_velocities": dict(self.angular_velocities),
            "conditional_stop": {c: {k: v.tolist() for k, v in d.items()}
                                 for c, d in self.contributions.items()},
        }


_STATE_FIELDS = tuple(f.name for f in fields(LinkageState))
_LAZY_FIELDS = frozenset(_STATE_FIELDS[5:])


class _StateRows:
    """Private copies of a motion's point arrays (its positions ``rows``), from which states
    build their dicts.

    The point kinematics are computed (and copied) when the first state's
    first dictionary is asked for.
    """

    def __init__(self, m, rows=slice(None)):
        self.names, self.links, self.cranks = m.point_names, m.link_names, m.crank_links
        self._motion, self.rows = m, rows

    def _fill(self):
        m, rows = self._motion, self.rows
        self.arrays = {f: getattr(m, f)[rows].copy() for f in ("points", "velocities", "accelerations")}
        self.C = np.moveaxis(m.contributions[:, rows], 0, 1).copy()
        self.w = m.qdot[rows, 2::3].tolist()
        self._motion = None

    def field(self, name, i):
        if self._motion is not None:
            self._fill()
        if name in self.arrays:
            return dict(zip(self.names, self.arrays[name][i]))
        if name == "angular_velocities":
            return dict(zip(self.links, self.w[i]))
        C = self.C[i]
        return {c: dict(zip(self.names, C[j])) for j, c in enumerate(self.cranks)}


def _derived(k: int, doc: str) -> property:
    """The k-th of a motion's point kinematics (see ``LinkageMotion._points``)."""
    return property(lambda self: self._points[k], doc=doc)


@dataclass(frozen=True)
class LinkageMotion:
    """Kinematics of a linkage at N drive positions, as arrays (first axis: position).

    Attributes
    ----------
    theta, t : ndarray (N,)
        First-crank rotation from the pose [rad]; time θ/ω_1 [s].
    q, qdot, qddot : ndarray (N, 3n)
        (x [length], y [length], φ [rad]) of each moving link's frame and
        their first and second time derivatives.
    parts : ndarray (N, 3n, n_cranks)
        q̇ with every crank but one stopped (conditional stop); ``q̇ = Σ parts``.
    point_names, link_names, crank_links : tuple of str
        Names of the P points, of the n moving links (the order of ``q``) and the cranks' links.
    points, velocities, accelerations : ndarray (N, P, 2)
        Every named point [length], [length/s], [length/s²].
    contributions : ndarray (n_cranks, N, P, 2)
        Point velocities with every other crank stopped [length/s].
    method : str
        ``"dyads"`` or ``"newton"``.
    """

    theta: NDArray[np.float64]
    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    qddot: NDArray[np.float64]
    parts: NDArray[np.float64]
    point_names: tuple
    link_names: tuple
    crank_links: tuple
    method: str
    _plan: object = field(repr=False, compare=False)

    # point kinematics are derived from q, q̇, q̈ on first use (the solve
    # itself, like FourBar.evaluate, yields the links' coordinates and rates)
    @cached_property
    def _points(self):
        return _point_kinematics(self._plan, self.q, self.qdot, self.qddot, self.parts)

    points = _derived(0, "Every named point, shape (N, P, 2) [length].")
    velocities = _derived(1, "Point velocities, shape (N, P, 2) [length/s].")
    accelerations = _derived(2, "Point accelerations, shape (N, P, 2) [length/s²].")
    contributions = _derived(3, "Point velocities with every other crank stopped, "
                                "(n_cranks, N, P, 2) [length/s].")

    def __len__(self) -> int:
        return len(self.theta)

    def __repr__(self) -> str:
        return (f"LinkageMotion({len(self)} positions, {len(self.link_names)} links, "
                f"{len(self.point_names)} points, method={self.method!r})")

    @property
    def angular_velocities(self) -> NDArray[np.float64]:
        """φ̇ of each moving link, shape (N, n) [rad/s]."""
        return self.qdot[:, 2::3]

    @property
    def angular_accelerations(self) -> NDArray[np.float64]:
        """φ̈ of each moving link, shape (N, n) [rad/s²]."""
        return self.qddot[:, 2::3]

    def states(self) -> list:
        """Every position as a :class:`~.linkage.LinkageState` (what ``Linkage.solve`` returns).

        The arrays are copied once; each state's vectors are disjoint views of
        that private copy, and its dictionaries are made on first access.
        """
        rows = _StateRows(self)
        q, qd, qdd = self.q.copy(), self.qdot.copy(), self.qddot.copy()
        th, t = self.theta.tolist(), self.t.tolist()
        out, new = [], object.__new__
        for i in range(len(th)):
            # filled as unpickling does: the frozen dataclass's __init__ (one
            # object.__setattr__ per field) costs more than the rest of a state
            st = new(LinkageState)
            st.__dict__.update(theta=th[i], t=t[i], q=q[i], qdot=qd[i], qddot=qdd[i],
                               _rows=rows, _i=i)
            out.append(st)
        return out

    def state(self, i: int):
        """The :class:`~.linkage.LinkageState` of position ``i``."""
        rows = _StateRows(self, slice(i, i + 1 or None))      # one copy of position i's rows
        return LinkageState(float(self.theta[i]), float(self.t[i]), self.q[i].copy(),
                            self.qdot[i].copy(), self.qddot[i].copy(),
                            *(rows.field(f, 0) for f in _STATE_FIELDS[5:]))


# ------------------------------------------------------------------- structure
@dataclass(frozen=True)
class _Plan:
    method: str
    nb: int                              # moving links
    offsets: NDArray                     # (P, 2): point offset in its owner's frame (or ground xy)
    owner: NDArray                       # (P,): owner link index, nb for a ground point
    crank_idx: NDArray                   # (nc,)
    omega: NDArray                       # (nc,)
    dyads: tuple = ()
    # newton
    ia: NDArray | None = None            # (m,) body index of side a (nb = ground)
    ib: NDArray | None = None
    sa: NDArray | None = None            # (m, 2)
    sb: NDArray | None = None
    q0: NDArray | None = None
    scale: float = 1.0
    # prismatic pairs: guide body (nb = ground), slider body, the guide line's
    # point and unit direction in the guide's frame, the slider's point in its own
    ga: NDArray | None = None
    gb: NDArray | None = None
    gs: NDArray | None = None
    gu: NDArray | None = None
    bs: NDArray | None = None
    # per-linkage solver objects (the dyads' geometry), made on first use
    cache: dict = field(default_factory=dict, repr=False, compare=False)


def plan(lk) -> _Plan:
    """Structure of ``lk`` compiled to index arrays, and the solver that fits it.

    Parameters
    ----------
    lk : Linkage
        The linkage to compile.

    Returns
    -------
    _Plan
        Dyads, or Newton's method when the structure has no dyad order.
    """
    idx = lk.link_index()
    nb, local = len(idx), lk.local_offsets()
    points = tuple(lk.pose)
    crank_idx = np.array([idx[c.link] for c in lk.cranks])
    omega = np.array([c.omega for c in lk.cranks], dtype=float)
    rows = lk.constraint_rows()
    m = len(rows)

    def body(b):
        return nb if b == "ground" else idx[b]

    def off(b, p):
        return lk.pose[p] if b == "ground" else local[b][p]

    # each point's owner: the first link holding it, else the ground
    owner = [next((l for l, ps in lk.links.items() if p in ps), "ground") for p in points]
    common = dict(nb=nb, crank_idx=crank_idx, omega=omega,
                  owner=np.array([body(o) for o in owner]),
                  offsets=np.array(list(map(off, owner, points)), dtype=float).reshape(-1, 2),
                  ia=np.array([body(a) for _, a, _ in rows], dtype=int).reshape(m),
                  ib=np.array([body(b) for _, _, b in rows], dtype=int).reshape(m),
                  sa=np.array([off(a, p) for p, a, _ in rows], dtype=float).reshape(m, 2),
                  sb=np.array([off(b, p) for p, _, b in rows], dtype=float).reshape(m, 2),
                  q0=lk.q0(), scale=lk.length_scale())
    sl = lk.sliders
    u = np.array([s.direction for s in sl], dtype=float).reshape(-1, 2)
    common.update(ga=np.array([body(s.guide) for s in sl], dtype=int),
                  gb=np.array([idx[s.link] for s in sl], dtype=int),
                  gs=np.array([off(s.guide, s.point) if s.guide == "ground" else
                               lk.pose[s.point] - lk.pose[lk.links[s.guide][0]] for s in sl],
                              dtype=float).reshape(-1, 2),
                  gu=u / np.hypot(u[:, 0], u[:, 1])[:, None] if len(sl) else u,
                  bs=np.array([local[s.link][s.point] for s in sl], dtype=float).reshape(-1, 2))
    dyads = _dyads(lk, idx)
    return _Plan("newton" if dyads is None else "dyads", dyads=dyads or (), **common)


@dataclass(frozen=True)
class _Dyad:
    """One class-II group solved in closed form (see :mod:`._dyad_forms`).

    ``kind`` "RRR": links L1, L2 meet at the revolute ``inner``; each turns
    about its outer joint on a known body.  "RRP": L1 turns about its outer
    joint, L2 meets it at ``inner`` and slides, without turning, on the known
    body K2 (its guide, or the block it guides): ``inner`` runs along the
    line through ``at`` (its pose place in K2's frame) along ``u``.  "RPR":
    L1 and L2 slide on one another along ``u`` (turning together), each
    turning about its outer joint; ``h0`` is the outer joints' distance
    across the line.
    """

    kind: str
    links: tuple          # (L1, L2) link indices
    inner: str            # the joint between them (the slider's pair for RPR)
    outer: tuple          # (P1 on L1, P2 on L2; for RRP the slider's pair)
    known: tuple          # body index carrying P1 and P2 (-1: ground)
    l1: float             # |P3 − P1| (RRR, RRP) and |P3 − P2| (RRR) from the pose
    l2: float
    sign: float           # the assembly side in the pose (see the forms)
    u: complex = 0j       # sliding direction, pose coordinates (RRP, RPR)
    at: complex = 0j      # RRP: the inner joint in K2's frame in the pose
    h0: float = 0.0       # RPR


def _dyads(lk, idx):
    """The Assur groups as RRR, RRP and RPR dyads in solving order, or None if one is not."""
    try:
        groups = lk.assur_groups()
    except GeometryError:
        return None
    pairs, slides = lk.pairs(), {s.pair: s for s in lk.sliders}
    known = {"ground"} | {c.link for c in lk.cranks}
    out = []
    for g in groups:
        if g.group_class != 2 or len(g.internal_pairs) != 1 or len(g.external_pairs) != 2:
            return None
        (P3,) = g.internal_pairs
        if set(pairs[P3]) != set(g.links):
            return None
        outer = {}
        for L in g.links:
            mine = [p for p in g.external_pairs if L in pairs[p]]
            others = [b for b in pairs[mine[0]] if b != L] if len(mine) == 1 else []
            if not others or not all(b in known for b in others):
                return None
            outer[L] = (mine[0], -1 if others[0] == "ground" else idx[others[0]])
        prism = [L for L in g.links if outer[L][0] in slides]
        if len(prism) + (P3 in slides) > 1:
            return None           # two sliders in one dyad: Newton
        L1, L2 = sorted(g.links, key=lambda L: L in prism)    # a sliding outer pair on L2
        dy = _dyad(lk, slides, P3, (idx[L1], idx[L2]), outer[L1], outer[L2])
        if dy is None:
            return None
        out.append(dy)
        known |= set(g.links)
    return tuple(out)


def _dyad(lk, slides, P3, links, o1, o2):
    """The :class:`_Dyad` of one group, or None when it is singular in the pose."""
    (P1, K1), (P2, K2) = o1, o2
    x1, scale = lk.pose[P1], lk.length_scale()
    if P3 in slides:                                           # RPR
        u = complex(*slides[P3].direction)
        d0 = complex(*(lk.pose[P2] - x1)) / u              # (along, across) u
        if abs(d0.real) <= 1e-9 * scale:
            return None
        return _Dyad("RPR", links, P3, (P1, P2), (K1, K2), 0.0, 0.0,
                     math.copysign(1.0, d0.real), u, 0j, d0.imag)
    x3 = lk.pose[P3]
    l1 = float(np.hypot(*(x3 - x1)))
    if P2 in slides:                                           # RRP
        u = complex(*slides[P2].direction)
        along = complex(*(x3 - x1)) / u
        if l1 == 0 or abs(along.real) <= 1e-9 * l1:
            return None
        at = x3 - (lk.pose[lk.links[lk.link_names[K2]][0]] if K2 >= 0 else 0.0)
        return _Dyad("RRP", links, P3, (P1, P2), (K1, K2), l1, 0.0,
                     math.copysign(1.0, along.real), u, complex(*at))
    x2 = lk.pose[P2]
    e, r = x2 - x1, x3 - x1
    cross = e[0] * r[1] - e[1] * r[0]
    l2 = float(np.hypot(*(x3 - x2)))
    if l1 == 0 or l2 == 0 or abs(cross) <= 1e-9 * l1 * float(np.hypot(*e)):
        return None           # degenerate or singular in the pose: let Newton say so
    return _Dyad("RRR", links, P3, (P1, P2), (K1, K2), l1, l2, math.copysign(1.0, cross))


# ------------------------------------------------------------------ helpers
# Points and vectors are complex numbers x + iy: R(φ)s = e^{iφ}s, and the
# perpendicular (−y, x) of a vector is i times it.

def _times(lk, thetas, max_step_deg):
    if not positive_number(max_step_deg):
        raise InputError(f"max_step_deg must be a finite number > 0 [deg], got {brief(max_step_deg)}")
    w1 = lk.cranks[0].omega
    wmax = max(abs(c.omega) for c in lk.cranks)
    with np.errstate(all="ignore"):
        t = thetas / w1
        path = np.concatenate(([0.0], t))
        steps = float(np.sum(np.abs(np.diff(path)))) * wmax / math.radians(max_step_deg)
    if not steps <= MAX_CONTINUATION_STEPS:
        far = float(np.max(np.abs(np.degrees(thetas))))
        raise OutOfReach(
            f"{lk.source}: reaching θ = {far:.6g}° needs about {steps:.3g} continuation steps "
            f"of {max_step_deg:g}° of the fastest crank (|ω| = {wmax:g} rad/s against the "
            f"first crank's {abs(w1):g} rad/s); the limit is {MAX_CONTINUATION_STEPS}, a path "
            f"of {MAX_CONTINUATION_STEPS * max_step_deg * abs(w1) / wmax:.6g}° from the pose")
    return t, math.radians(max_step_deg) / wmax


def _path(t, dt_max, t0=0.0):
    """Times along the traversal t0 → t[0] → t[1] …, no two more than dt_max apart.

    Returns (nodes, index of each target in nodes).
    """
    path = np.concatenate(([t0], t))
    d = np.diff(path)
    n = np.maximum(1, np.ceil(np.abs(d) / dt_max).astype(int))
    if np.all(n == 1):
        return path, np.arange(1, len(path))
    pieces = [path[k] + d[k] * np.arange(1, n[k] + 1) / n[k] for k in range(len(d))]
    return np.concatenate([path[:1], *pieces]), np.cumsum(n)


def to_complex(xy):
    """Points (..., 2) as x + iy (...,)."""
    xy = np.asarray(xy, dtype=float)
    return xy[..., 0] + 1j * xy[..., 1]


def to_xy(z):
    """x + iy (...,) as points (..., 2)."""
    return np.stack([z.real, z.imag], axis=-1)


def _with_ground(a, ground=0.0):
    """``a`` (N, nb), one column per moving body, with the ground's column (``ground``) last."""
    return np.concatenate([a, np.full((len(a), 1), ground, dtype=a.dtype)], axis=1)


def _point_kinematics(pl, q, qdot, qddot, parts):
    """Every point's position, velocity, acceleration and conditional-stop velocities."""
    o = pl.owner
    s = to_complex(pl.offsets)

    def ext(a):                       # per point, its owner's a (0 for the ground)
        return _with_ground(a)[:, o]

    def origin(x):                    # per point, its owner's frame origin x + iy (or a rate)
        return ext(x[:, 0::3] + 1j * x[:, 1::3])

    Rs = np.exp(1j * ext(q[:, 2::3])) * s
    pts, vel, acc = rigid_points((origin(q), origin(qdot), origin(qddot)),
                                 (ext(qdot[:, 2::3]), ext(qddot[:, 2::3])), Rs)
    # each crank's part of the velocity: the velocity at its part of the rates
    contrib = [rigid_points((0, origin(parts[:, :, j]), 0), (ext(parts[:, 2::3, j]), 0), Rs)[1]
               for j in range(parts.shape[2])]
    return to_xy(pts), to_xy(vel), to_xy(acc), to_xy(np.array(contrib))


def rigid_points(origin, rates, Rs):
    """Position, velocity and acceleration (x + iy) of points fixed in moving bodies: at
    ``Rs`` = e^{iφ}·s (s in the body's frame, turned by the body's angle φ) from the
    frame's origin, whose position, velocity and acceleration are ``origin``, the body
    turning at ω with ω̇ (``rates``)."""
    w, al = rates
    return origin[0] + Rs, origin[1] + 1j * w * Rs, origin[2] + (1j * al - w * w) * Rs


def motion(lk, pl: _Plan, theta, *, max_step_deg: float = 2.0, method: str = "auto"):
    """Solve ``lk`` at first-crank rotations ``theta`` [rad] (1-D array); see the module.

    Parameters
    ----------
    lk : Linkage
        The linkage to solve.
    pl : _Plan
        From :func:`plan`.
    theta : ndarray
        First-crank rotations from the pose [rad], traversed in order.
    max_step_deg : float
        The largest continuation step [deg].
    method : {"auto", "dyads", "newton"}
        ``"auto"``: the plan's solver.

    Returns
    -------
    LinkageMotion
    """
    thetas = real_values(theta, "theta", "rad").reshape(-1)
    t, dt_max = _times(lk, thetas, max_step_deg)
    use = pl.method if method == "auto" else method
    if use not in ("dyads", "newton"):
        raise InputError(f"method must be 'auto', 'dyads' or 'newton', got {brief(method)}"
                         f"{did_you_mean(str(method), ('auto', 'dyads', 'newton'))}")
    if use == "dyads" and pl.method != "dyads":
        raise GeometryError(f"{lk.source}: the linkage is not made of RRR dyads only; "
                            f"use method='newton'")
    q, qd, qdd, parts = _solve(lk, pl, use, t, dt_max)
    out = LinkageMotion(thetas, t, q, qd, qdd, parts, tuple(lk.pose), lk.link_names,
                        tuple(c.link for c in lk.cranks), use, pl)
    for s in lk.sliders:
        if s.stroke:
            P, G1, G2 = (out.points[:, out.point_names.index(p)] for p in (s.point, *s.line))
            check_stroke(lk, s, thetas, P, G1, G2)
    return out


def check_stroke(lk, s, theta, P, G1, G2, what: str = "position asked") -> None:
    """Raise the located error of slider ``s`` if its point ``P`` leaves its stroke at
    any of the crank rotations ``theta`` [rad] (``P``, ``G1``, ``G2``: (n, 2) positions
    of its point and guide line, in the linkage's units); ``what`` names a position in
    the message ("the first position asked beyond it")."""
    u = G2 - G1
    along = np.sum((P - G1) * u, axis=1) / np.hypot(u[:, 0], u[:, 1])
    lo, hi = s.stroke
    over = np.maximum(lo - along, along - hi)
    bad = ~(over <= 1e-9 * lk.length_scale())
    if np.any(bad):
        k = int(np.argmax(bad))
        end = f"min {lo:g}" if along[k] < lo else f"max {hi:g}"
        raise NetlistError(
            f"slider {s.link!r} leaves its guide at θ = {math.degrees(theta[k]):.6g}° (the "
            f"first {what} beyond it): its point {s.point!r} is at {along[k]:.6g} "
            f"along {s.line[0]}→{s.line[1]}, {over[k]:.6g} beyond the stroke's {end}",
            lk.source, s.stroke_at[0], s.stroke_at[1],
            expected=f"a stroke containing {along[k]:.6g}, or crank angles that keep "
                     f"{s.point!r} within [{lo:g}, {hi:g}]")


# ------------------------------------------------------------- change points
#: Half-width of the zone around a change point's crossing where positions and rates
#: are interpolated (see :func:`_solve`), as rotation of the fastest crank [rad].
_ZONE = 6e-3
#: A dyad whose sin² of the inner angle dips to this and opens again crosses a change point.
_CROSS = 1e-12
#: Most samples per piece of the scan for crossings.
_SCAN = 2000


def _solve(lk, pl, use, t, dt_max):
    """(q, q̇, q̈, parts) at times ``t`` by the solver ``use``.

    A change-point linkage (an RRR or RRP dyad that lines up where its two assembly
    modes cross, :func:`_crossings`; one crank) continues on the branch whose velocity is
    continuous: the dyad changes sides there.  The closed form and Newton are
    ill-conditioned within a rotation ``_ZONE`` of the crossing (positions to about
    √eps, rates 0/0), so the solvers visit the zone's ends instead (Newton steps from
    one to the other as across any step, :func:`_newton_segments`) and every position
    inside it is the quintic through their q, q̇, q̈ (error ~ (2·_ZONE)⁶ q⁽⁶⁾/46080 in
    q, ~ (2·_ZONE)⁴ q⁽⁶⁾ in q̈).  The zone's half-width balances that against the
    ends' own error (~ eps/sin³ in q̈): measured on three change-point four-bars,
    q̈ to 1.2e-8 ω², q̇ to 4e-11 ω (on 20/60/50/30, q̈ to 1.8e-7 with a zone of
    ±0.002 rad, 1.1e-8 at ±0.006, 6.4e-8 at ±0.01, 2e-6 at ±0.02).
    """
    one_crank_dyads = pl.method == "dyads" and len(pl.crank_idx) == 1
    cross = _crossings(_dyad_solver(lk, pl), t, dt_max) if one_crank_dyads else []
    if not cross:
        return (_solve_dyads if use == "dyads" else _solve_newton)(lk, pl, t, dt_max)
    dz = _ZONE / abs(float(pl.omega[0]))
    zones = [(tc - dz, tc + dz) for tc, _ in sorted(cross)]
    pts, where, zone_of = _traverse(t, zones)
    got = _solve_dyads(lk, pl, pts, dt_max, cross, zones) if use == "dyads" else \
        _newton_segments(lk, pl, pts, dt_max, zones)
    return _bridged(lk, pl, got, t, pts, where, zone_of, zones)


def _signs(pl, cross, t):
    """Each dyad's assembly side at times ``t`` (n_dyads, N): the pose's, changed at each
    change point ``cross`` ((time, dyad) pairs) between the pose (t = 0) and t."""
    s = np.repeat(np.array([[d.sign] for d in pl.dyads], dtype=float), len(t), axis=1)
    for d in {d for _, d in cross}:
        tc = np.sort([c for c, k in cross if k == d])
        up, down = tc[tc > 0], tc[tc < 0]
        passed = np.searchsorted(up, t) + len(down) - np.searchsorted(down, t, side="right")
        s[d] *= 1 - 2 * (passed % 2)
    return s


def _sin2(ds, t, cross):
    """sin² of each RRR dyad's inner angle, and of the angle between an RRP dyad's rod
    and its guide, at times ``t`` (n_dyads, N); negative where it cannot assemble, +inf
    for RPR dyads.  Independent of the dyad's own side."""
    inner = ds.positions(t, cross)[3]
    out = np.full((len(inner), len(t)), np.inf)
    for k, (dy, rates) in enumerate(zip(ds.pl.dyads, inner)):
        if dy.kind == "RRR":
            e = rates[1] - rates[0]
            c = (dy.l1 ** 2 + dy.l2 ** 2 - (e.real ** 2 + e.imag ** 2)) / (2 * dy.l1 * dy.l2)
        elif dy.kind == "RRP":         # the rod's reach across the guide (exact off it too)
            c = im_conj(rates[4], rates[5]) / dy.l1
        else:
            continue
        out[k] = 1.0 - c * c
    return out


def _crossings(ds, t, dt_max):
    """The change points the smooth branch meets between the pose and the farthest
    targets on either side: [(time, dyad)], nearest the pose first on each side.

    The sin² of every RRR and RRP dyad's angle (:func:`_sin2`) is sampled every ``dt_max`` (at most 2°)
    out from the pose; at a sampled minimum that a parabola puts near 0, the minimum is
    narrowed (16-fold per round, 10 rounds).  It is a change point when it is at
    most ``_CROSS`` and the dyad assembles again a ``_ZONE`` beyond (a dead
    position, where the linkage locks, does not).  They depend on the linkage
    only: kept with the range scanned, rescanned when a call reaches beyond it.
    """
    lo, hi = float(np.min(t, initial=0.0)), float(np.max(t, initial=0.0))
    w = abs(float(ds.pl.omega[0]))
    step = min(dt_max, math.radians(2.0) / w)      # coarser samples miss minima
    kept = ds.__dict__.get("_crossings")
    if kept is not None and kept[0] == step and kept[1] <= lo and hi <= kept[2]:
        return kept[3]
    cross: list = []
    dz = _ZONE / w
    for end in (hi, lo):
        t0 = 0.0
        while end != 0.0:
            # in pieces of at most _SCAN samples (a long range at large steps)
            n = min(int(math.ceil(abs(end - t0) / step)) + 3, _SCAN)
            grid = t0 + math.copysign(step, end) * np.arange(n)
            found = _first_crossing(ds, grid, _sin2(ds, grid, cross), cross, dz)
            if found is None and n == _SCAN:
                t0 = grid[-3]                   # overlapping: a minimum at the seam
                continue
            if found is None:
                break
            cross.append(found)
            t0 = found[0] + math.copysign(dz, end)
    ds._crossings = (step, lo, hi, cross)
    return cross


def _first_crossing(ds, grid, s2, cross, dz):
    """The first change point (time, dyad) along ``grid`` (sin² ``s2`` there), or None."""
    fine = np.all(s2 >= -_CROSS, axis=0)
    s2 = s2[:, :len(grid) if fine.all() else int(np.argmin(fine))]  # up to a lock
    lo, mid, hi = s2[:, :-2], s2[:, 1:-1], s2[:, 2:]
    with np.errstate(all="ignore"):
        vertex = mid - (hi - lo) ** 2 / (8 * (hi - 2 * mid + lo))
    cand = (mid <= lo) & (mid <= hi) & ((mid < 1e-6) | (vertex < 0.1 * mid))
    for k, d in sorted(zip(*np.nonzero(cand.T))):
        a, b = grid[k], grid[k + 2]
        for _ in range(10):
            g = np.linspace(a, b, 33)
            v = _sin2(ds, g, cross)[d]
            j = int(np.argmin(v))
            a, b = g[max(j - 1, 0)], g[min(j + 1, 32)]
        ends = _sin2(ds, np.array([g[j] - dz, g[j] + dz]), cross)[d]
        if v[j] <= _CROSS and np.all(ends > _CROSS):
            return float(g[j]), int(d)
    return None


def _traverse(t, zones):
    """The traversal 0 → t[0] → t[1] … with every zone it enters replaced by its two
    ends, in order: (times to solve, row of each target there or −1, its zone or −1).
    ``zones`` in increasing order."""
    prev = np.concatenate(([0.0], t[:-1]))
    za, zb = np.array(zones).T
    hit = (za[:, None] <= np.maximum(prev, t)) & (zb[:, None] >= np.minimum(prev, t))
    pts: list = []
    where, zone_of = np.full(len(t), -1), np.full(len(t), -1)
    last = 0
    for i in np.flatnonzero(hit.any(axis=0)).tolist() + [len(t)]:
        where[last:i] = len(pts) + np.arange(i - last)        # the steps that meet none
        pts.extend(t[last:i].tolist())
        if i == len(t):
            break
        a, b = float(prev[i]), float(t[i])
        for z in sorted(np.flatnonzero(hit[:, i]).tolist(), reverse=b < a):
            pts.extend(zones[z] if b >= a else zones[z][::-1])
            if zones[z][0] < b < zones[z][1]:
                zone_of[i] = z
        if zone_of[i] < 0:
            where[i] = len(pts)
            pts.append(b)
        last = i + 1
    return np.array(pts), where, zone_of


def _newton_segments(lk, pl, pts, dt_max, zones):
    """Newton's continuation through ``pts``; across a change point's zone (one end to
    the other) it steps from the Taylor predictor, where det J changes sign."""
    ends = {z for z in zones} | {z[::-1] for z in zones}
    cuts = [i + 1 for i in range(len(pts) - 1) if (pts[i], pts[i + 1]) in ends]
    lo, start, pieces = 0, None, []
    for hi in cuts + [len(pts)]:
        got = _solve_newton(lk, pl, pts[lo:hi], dt_max, start)
        pieces.append(got)
        if hi < len(pts):
            dt = pts[hi] - pts[hi - 1]
            q, qd, qdd = got[0][-1], got[1][-1], got[2][-1]
            res = Newton(pl).step(q + qd * dt + 0.5 * qdd * dt * dt, pl.omega * pts[hi])
            if res is None:
                raise _branch_jump(lk, pts[hi - 1] * pl.omega[0], pts[hi] * pl.omega[0])
            start = (res[0], pts[hi])
        lo = hi
    return tuple(np.concatenate(p) for p in zip(*pieces))


def _bridged(lk, pl, got, t, pts, where, zone_of, zones):
    """The targets from the solved ``pts``: inside a zone, the quintic through the
    zone's ends, after checking that the velocity is continuous across it."""
    Q, QD, QDD = got[:3]
    w1 = pl.omega[0]
    out = [a[np.maximum(where, 0)] for a in got]
    for z, (za, zb) in enumerate(zones):
        if not np.any(pts == za):
            continue                                   # not reached
        ia, ib = int(np.flatnonzero(pts == za)[0]), int(np.flatnonzero(pts == zb)[0])
        h = zb - za
        # on the other branch the rates would jump (by 2/3 ω for a parallelogram); the
        # trapezoid rule's error is h³ q⁗/12, about 1e-7 ω
        jump = QD[ib] - QD[ia] - 0.5 * (QDD[ia] + QDD[ib]) * h
        if not np.max(np.abs(jump[2::3])) <= 1e-2 * abs(w1):
            raise _branch_jump(lk, za * w1, zb * w1)
        sel = np.flatnonzero(zone_of == z)
        u = (t[sel] - za) / h
        qb = Q[ib].copy()              # the angles continuous across (the dyads' wrap)
        qb[2::3] -= 2 * np.pi * np.round((qb[2::3] - Q[ia, 2::3]) / (2 * np.pi))
        ends = [(Q[ia][None], QD[ia][None], QDD[ia][None]), (qb[None], QD[ib][None], QDD[ib][None])]
        for k in range(3):
            out[k][sel] = _quintic(u, np.full(len(sel), h), *ends, k=k)
        out[3][sel] = out[1][sel][:, :, None]        # one crank: its part is q̇
    return tuple(out)


# ------------------------------------------------------------ dyads, closed form
def _dot(a, b):
    """Re(conj(a)·b) = a · b."""
    return a.real * b.real + a.imag * b.imag


class _DyadSolver:
    """Closed-form dyads (:mod:`._dyad_forms`), vectorised over positions.

    Per body (the ground last, at index −1): angle φ (N,), e^{iφ}, origin r
    (N,) complex, ω, v, α, a.  A dyad's rates solve one 2×2 system
    x·c1 + y·c2 = b whose columns come from the positions: (ω1, ω2) for RRR,
    (ω1, σ̇) for RRP, (ω, σ̇) for RPR, σ the slide.
    """

    def __init__(self, lk, pl):
        self.lk, self.pl = lk, pl
        local = lk.local_offsets()
        self.local = [{p: complex(*x) for p, x in local[n].items()} for n in lk.link_names]
        self.pose = {p: complex(*x) for p, x in lk.pose.items()}
        self.crank_arm = [-self.local[pl.crank_idx[j]][c.pivot] for j, c in enumerate(lk.cranks)]
        # per dyad: the outer joints in their carriers' frames (X2: the inner
        # joint's for RRP), the pose angles of P3 − P1 and P3 − P2, and each
        # link's origin from its anchor (P1; P2, or P3 for RRP) in its frame
        self.geo = []
        for dy in pl.dyads:
            (L1, L2), (P1, P2), (K1, K2) = dy.links, dy.outer, dy.known
            z1, z3 = self.pose[P1], self.pose[dy.inner] if dy.kind != "RPR" else 0j
            X1 = z1 if K1 == -1 else self.local[K1][P1]
            X2 = dy.at if dy.kind == "RRP" else \
                self.pose[P2] if K2 == -1 else self.local[K2][P2]
            a2 = dy.inner if dy.kind == "RRP" else P2
            ang = (float(np.angle(z3 - z1)),
                   float(np.angle(z3 - self.pose[P2])) if dy.kind == "RRR" else 0.0)
            self.geo.append((X1, X2, ang, -self.local[L1][P1], -self.local[L2][a2]))

    def positions(self, t, cross=()):
        """Every body at times ``t``, each dyad on its side of the change points ``cross``
        passed (:func:`_signs`; none: the pose's side)."""
        pl, lk = self.pl, self.lk
        signs = _signs(pl, cross, t) if cross else None
        N = len(t)
        E = np.ones((pl.nb + 1, N), dtype=complex)          # e^{iφ}; the ground last
        phi, r = np.zeros((pl.nb + 1, N)), np.zeros((pl.nb + 1, N), dtype=complex)
        inner, margin = [], np.full(N, np.inf)
        for j, (c, ci) in enumerate(zip(lk.cranks, pl.crank_idx)):
            phi[ci] = pl.omega[j] * t
            E[ci] = np.exp(1j * phi[ci])
            r[ci] = self.pose[c.pivot] + E[ci] * self.crank_arm[j]
        for k, (dy, (X1, X2, ang, arm1, arm2)) in enumerate(zip(pl.dyads, self.geo)):
            (L1, L2), (K1, K2) = dy.links, dy.known
            sign = dy.sign if signs is None else signs[k]
            x1, x2 = r[K1] + E[K1] * X1, r[K2] + E[K2] * X2
            with np.errstate(all="ignore"):
                if dy.kind == "RPR":
                    E1, h2 = rpr(x1, x2, dy.h0, dy.u, sign)
                    e, u = x2 - x1, E1 * dy.u
                    sin_ = np.abs(_dot(u, e)) / np.abs(e)    # 0: the links across the line
                    phi[L1] = phi[L2] = np.angle(E1)
                    E[L1] = E[L2] = E1
                    rates = (x1, x2, x2, 1j * e, u, e)
                elif dy.kind == "RRP":
                    u = E[K2] * dy.u
                    x3, h2 = rrp(x1, dy.l1, x2, u, sign)
                    r1 = x3 - x1
                    sin_ = np.abs(_dot(u, r1)) / dy.l1       # 0: the rod across the guide
                    phi[L1], E[L1] = np.angle(r1) - ang[0], r1 * (np.exp(-1j * ang[0]) / dy.l1)
                    phi[L2], E[L2] = phi[K2], E[K2]
                    rates = (x1, x3, x3, 1j * r1, -u, r1)
                else:
                    x3, h2 = rrr(x1, x2, dy.l1, dy.l2, sign)
                    r1, r2 = x3 - x1, x3 - x2
                    # sin of the angle between the links at the inner joint: 0 when
                    # the dyad is stretched or folded (its Jacobian is singular there)
                    sin_ = np.abs(im_conj(r1, r2)) / (dy.l1 * dy.l2)
                    # |r1|, |r2| are the links' lengths by construction (to rounding)
                    phi[L1], E[L1] = np.angle(r1) - ang[0], r1 * (np.exp(-1j * ang[0]) / dy.l1)
                    phi[L2], E[L2] = np.angle(r2) - ang[1], r2 * (np.exp(-1j * ang[1]) / dy.l2)
                    rates = (x1, x2, x2, 1j * r1, -1j * r2, r1, r2)
            m = np.where(h2 >= 0, sin_, -1.0)
            margin = np.minimum(margin, np.where(np.isfinite(m), m, -1.0))
            r[L1] = x1 + E[L1] * arm1
            r[L2] = rates[2] + E[L2] * arm2
            inner.append(rates)
        return phi, E, r, inner, margin

    def velocities(self, E, r, inner, w_cranks):
        """(ω, origin velocity (complex), σ̇ per dyad), for crank speeds ``w_cranks``."""
        w, v = np.zeros(E.shape), np.zeros(E.shape, dtype=complex)
        for c, ci, wc in zip(self.lk.cranks, self.pl.crank_idx, w_cranks):
            w[ci] = wc
            v[ci] = 1j * wc * (r[ci] - self.pose[c.pivot])
        return self._rates(r, inner, w, v, np.zeros(E.shape))

    def accelerations(self, E, r, inner, w, sdot):
        al, a = np.zeros(E.shape), np.zeros(E.shape, dtype=complex)
        for c, ci in zip(self.lk.cranks, self.pl.crank_idx):
            a[ci] = -w[ci] ** 2 * (r[ci] - self.pose[c.pivot])
        return self._rates(r, inner, al, a, w ** 2, w, sdot)[:2]

    def _rates(self, r, inner, ang, lin, sq, w=None, sdot=None):
        """The dyads' angular rates ``ang`` and their origins' linear ones ``lin`` (complex),
        both given for the cranks, and the slides' rates: the velocities (ω, v, σ̇) with
        ``sq`` zero; with ``sq`` = ω² and the velocities' ω ``w`` and σ̇ ``sdot``, the
        accelerations (α, a, σ̈).  A point p of body K moves at
        lin[K] + (i·ang[K] − sq[K])·(p − r[K]).
        """
        slides = []
        for k, (dy, (x1, y2, o2, c1, c2, *rr)) in enumerate(zip(self.pl.dyads, inner)):
            (L1, L2), (K1, K2) = dy.links, dy.known
            l1 = lin[K1] + (1j * ang[K1] - sq[K1]) * (x1 - r[K1])
            b = lin[K2] + (1j * ang[K2] - sq[K2]) * (y2 - r[K2]) - l1
            if sdot is not None:
                if dy.kind == "RRR":    # i(α1 r1 − α2 r2) = a2 − a1 + ω1² r1 − ω2² r2
                    b = b + w[L1] ** 2 * rr[0] - w[L2] ** 2 * rr[1]
                elif dy.kind == "RRP":  # iα1 r1 − σ̈u = a_K − a1 + ω1² r1 + 2iω_K σ̇ u
                    b = b + w[L1] ** 2 * rr[0] - 2j * w[K2] * sdot[k] * c2
                else:                   # iα e + σ̈u = a2 − a1 + ω² e − 2iω σ̇ u
                    b = b + w[L1] ** 2 * rr[0] - 2j * w[L1] * sdot[k] * c2
            x, y = solve2(c1, c2, b)
            ang[L1], ang[L2] = x, (y if dy.kind == "RRR" else x if dy.kind == "RPR" else ang[K2])
            slides.append(y)
            lin[L1] = l1 + (1j * ang[L1] - sq[L1]) * (r[L1] - x1)
            lo2 = l1 + (1j * x - sq[L1]) * (o2 - x1) if dy.kind == "RRP" else \
                lin[K2] + (1j * ang[K2] - sq[K2]) * (o2 - r[K2])
            lin[L2] = lo2 + (1j * ang[L2] - sq[L2]) * (r[L2] - o2)
        return ang, lin, slides


_SINGULAR = 1e-10


def _pack(r, phi):
    """(nb + 1, N) complex origins and angles (the ground last) → q rows (N, 3 nb)."""
    nb, N = r.shape[0] - 1, r.shape[1]
    q = np.empty((3 * nb, N))       # rows filled as they lie, then one transposed copy
    q[0::3], q[1::3], q[2::3] = r[:nb].real, r[:nb].imag, phi[:nb]
    return q.T.copy()               # 6x faster than stacking the transposes (3,600 × 3)


def _dyad_solver(lk, pl):
    """The plan's :class:`_DyadSolver`, made on first use."""
    if "dyads" not in pl.cache:
        pl.cache["dyads"] = _DyadSolver(lk, pl)
    return pl.cache["dyads"]


def _solve_dyads(lk, pl, t, dt_max, cross=(), zones=()):
    """The dyads at times ``t``, each on its side of the change points ``cross`` passed
    (:func:`_signs`); the path outside ``zones`` must assemble."""
    ds = _dyad_solver(lk, pl)
    phi, E, r, inner, margin = ds.positions(t, cross)
    # the traversal from the pose must stay assemblable: check the path between
    # the targets too where they are further apart than a continuation step
    check_t = _path(t, dt_max)[0][1:]
    check_m = margin if len(check_t) == len(t) else ds.positions(check_t, cross)[4]
    for a, b in zones:          # inside a change point's zone it is not used (_bridged)
        check_m = np.where((check_t > a) & (check_t < b), np.inf, check_m)
    if not np.all(check_m > _SINGULAR):
        k = int(np.argmax(~(check_m > _SINGULAR)))
        _lock_error(lk, ds, 0.0 if k == 0 else check_t[k - 1], check_t[k], cross)
    w, v, sdot = ds.velocities(E, r, inner, pl.omega)
    qd = _pack(v, w)
    if len(lk.cranks) == 1:                   # one crank: its part is the whole velocity
        parts = qd[:, :, None]
    else:                           # crank j turning, the others stopped
        turning = (ds.velocities(E, r, inner, wc) for wc in np.diag(pl.omega))
        parts = np.stack([_pack(vj, wj) for wj, vj, _ in turning], axis=2)
    al, a = ds.accelerations(E, r, inner, w, sdot)
    return _pack(r, phi), qd, _pack(a, al), parts


#: Inner points per round of the search for where a linkage locks (:func:`_lock_error`).
_LOCK_GRID = 31


def _lock_error(lk, ds, t_good, t_bad, cross=()):
    """Locate where the dyads (on the sides of the change points ``cross`` passed) stop
    assembling (or turn singular) and say so."""
    w1 = lk.cranks[0].omega
    if t_good == 0.0 and ds.positions(np.array([0.0]))[4][0] <= _SINGULAR:
        raise _singular_pose(lk)
    # Narrowed 32-fold per round on a grid of 31 inner points (one vectorised call
    # each, where bisection spent a call per halving); the first point that does
    # not assemble bounds the next round, so the earliest lock in [t_good, t_bad]
    # is the one named.
    lo, hi = t_good, t_bad
    for _ in range(16):
        if abs(hi - lo) * abs(w1) < 1e-12:
            break
        grid = np.linspace(lo, hi, _LOCK_GRID + 2)[1:-1]
        bad = ~(ds.positions(grid, cross)[4] > _SINGULAR)
        if bad.any():
            k = int(np.argmax(bad))
            lo, hi = (grid[k - 1] if k else lo), grid[k]
        else:
            lo = grid[-1]
    raise _lock(lk, hi * w1)


def _singular_pose(lk):
    """The error of a linkage whose constraint Jacobian is singular in its pose."""
    return GeometryError(f"{lk.source}: the linkage is singular in its pose "
                         "(constraint Jacobian not invertible)")


def _lock(lk, theta):
    """The error of a linkage that locks near crank rotation ``theta`` [rad]."""
    return GeometryError(
        f"{lk.source}: the linkage locks near θ = {math.degrees(theta):.6g}° (first crank "
        f"rotation from the pose): no assembly beyond it on this branch")


def _branch_jump(lk, theta0, theta1=None):
    """The error of a position that changed branch between crank rotations ``theta0`` and
    ``theta1`` [rad] (None: near ``theta0``)."""
    where = f"near θ = {math.degrees(theta0):.6g}°" if theta1 is None else \
        f"between θ = {math.degrees(theta0):.6g}° and {math.degrees(theta1):.6g}°"
    return GeometryError(
        f"{lk.source}: branch jump {where}: the position passed a "
        f"singular configuration (det J changed sign); reduce max_step_deg "
        f"or the linkage reaches a change point there")


# ------------------------------------------------------------------ Newton
class Newton:
    """Residual, Jacobian and γ of Φ(q, t) = 0, batched over positions (first axis).

    The path without numba (and before the compiled ``newton_path`` is cached):
    the twin of :func:`._linkage_kernels.newton_path`, kept because that loop run
    as Python costs 6–66× more (measured: see :mod:`._linkage_kernels`).

    Joint rows are computed as complex numbers whose float view is the
    interleaved (x, y) rows; the Jacobian is a constant template with the
    φ-columns filled in by one flat-index assignment per side.
    """

    def __init__(self, pl):
        self.pl = pl
        nb = pl.nb
        self.n = n = 3 * nb
        self.m = m = len(pl.ia)
        self.J0 = J0 = np.zeros((n, n))
        k = np.arange(m)
        a_mov, b_mov = pl.ia < nb, pl.ib < nb
        self.ka, self.kb = ka, kb = k[a_mov], k[b_mov]
        ia, ib = pl.ia[a_mov], pl.ib[b_mov]
        for rows, cols, sign in ((ka, ia, 1.0), (kb, ib, -1.0)):      # ±1 on the (x, y) columns
            J0[2 * rows, 3 * cols] = sign
            J0[2 * rows + 1, 3 * cols + 1] = sign
        # prismatic rows after the joint rows: ns line rows, then ns angle rows
        self.ns = ns = len(pl.ga)
        self.c0 = 2 * m + 2 * ns                 # the first crank row
        angle_rows, moving = 2 * m + ns + np.arange(ns), pl.ga < nb
        J0[angle_rows, 3 * pl.gb + 2] = 1.0
        J0[angle_rows[moving], 3 * pl.ga[moving] + 2] = -1.0
        J0[self.c0 + np.arange(len(pl.crank_idx)), 3 * pl.crank_idx + 2] = 1.0
        self.gu, self.gs, self.bs = to_complex(pl.gu), to_complex(pl.gs), to_complex(pl.bs)
        # flat indices of the φ-column entries, rows (2k, 2k+1) interleaved
        self.flat_a, self.flat_b = (
            np.stack([(2 * rows) * n + 3 * cols + 2, (2 * rows + 1) * n + 3 * cols + 2],
                     axis=-1).reshape(-1) for rows, cols in ((ka, ia), (kb, ib)))
        self.sa, self.sb = to_complex(pl.sa), to_complex(pl.sb)
        self.cphi = 3 * pl.crank_idx + 2
        self.tol = 1e-12 * pl.scale

    def _sides(self, q):
        """(R s, P) of both sides of every joint row, complex (N, m) each."""
        pl = self.pl
        z = _with_ground(q[:, 0::3] + 1j * q[:, 1::3])
        e = _with_ground(np.exp(1j * q[:, 2::3]), 1.0)
        Ra = e[:, pl.ia] * self.sa
        Rb = e[:, pl.ib] * self.sb
        return Ra, z[:, pl.ia] + Ra, Rb, z[:, pl.ib] + Rb

    def _prism(self, q):
        """Guide direction w, R s of guide and slider points, and d = P_slider − P_guide,
        complex (N, ns) each; and the relative angle φ_slider − φ_guide (N, ns)."""
        pl = self.pl
        phi = _with_ground(q[:, 2::3])
        z = _with_ground(q[:, 0::3] + 1j * q[:, 1::3])
        e = np.exp(1j * phi)
        w = e[:, pl.ga] * self.gu
        RA, RB = e[:, pl.ga] * self.gs, e[:, pl.gb] * self.bs
        d = z[:, pl.gb] + RB - z[:, pl.ga] - RA
        return w, RA, RB, d, phi[:, pl.gb] - phi[:, pl.ga]

    def residual(self, q, angles, sides=None):
        _, Pa, _, Pb = sides if sides is not None else self._sides(q)
        r = np.empty((len(q), self.n))
        m2, ns = 2 * self.m, self.ns
        r[:, :m2] = np.ascontiguousarray(Pa - Pb).view(np.float64)
        if ns:
            w, _, _, d, dphi = self._prism(q)
            r[:, m2:m2 + ns] = im_conj(w, d)
            r[:, m2 + ns:self.c0] = dphi
        r[:, self.c0:] = q[:, self.cphi] - angles
        return r

    def jacobian(self, q, sides=None):
        Ra, _, Rb, _ = sides if sides is not None else self._sides(q)
        N = len(q)
        J = np.repeat(self.J0[None], N, axis=0).reshape(N, -1)
        J[:, self.flat_a] = np.ascontiguousarray(1j * Ra[:, self.ka]).view(np.float64)
        J[:, self.flat_b] = np.ascontiguousarray(-1j * Rb[:, self.kb]).view(np.float64)
        J = J.reshape(N, self.n, self.n)
        if self.ns:
            # line row u × d: ∂/∂r_b = i u, ∂/∂φ_b = u·R_b s_b, and the negatives on
            # the guide, whose turning also turns u: ∂/∂φ_a = −u·d − u·R_a s_a
            pl = self.pl
            w, RA, RB, d, _ = self._prism(q)
            iw = 1j * w
            for k in range(self.ns):
                row, a, b = 2 * self.m + k, pl.ga[k], pl.gb[k]
                J[:, row, 3 * b:3 * b + 3] = np.stack(
                    [iw[:, k].real, iw[:, k].imag, _dot(w[:, k], RB[:, k])], axis=-1)
                if a < pl.nb:
                    J[:, row, 3 * a:3 * a + 3] = -np.stack(
                        [iw[:, k].real, iw[:, k].imag, _dot(w[:, k], d[:, k] + RA[:, k])], axis=-1)
        return J

    def gamma(self, q, qdot, sides=None):
        Ra, _, Rb, _ = sides if sides is not None else self._sides(q)
        pl, N = self.pl, len(q)
        w2, g = _with_ground(qdot[:, 2::3] ** 2), np.zeros((N, self.n))
        g[:, :2 * self.m] = np.ascontiguousarray(Ra * w2[:, pl.ia] - Rb * w2[:, pl.ib]).view(
            np.float64)
        if self.ns:
            # line row: −(ü × d + 2 u̇ × ḋ + u × d̈) without the q̈ terms, u̇ = iω_a u
            w, RA, RB, d, _ = self._prism(q)
            om = _with_ground(qdot[:, 2::3])
            v = _with_ground(qdot[:, 0::3] + 1j * qdot[:, 1::3])
            wa, wb = om[:, pl.ga], om[:, pl.gb]
            dd = v[:, pl.gb] + 1j * wb * RB - v[:, pl.ga] - 1j * wa * RA
            g[:, 2 * self.m:2 * self.m + self.ns] = -(
                im_conj(-wa * wa * w, d) + 2 * im_conj(1j * wa * w, dd)
                + im_conj(w, wa * wa * RA - wb * wb * RB))
        return g

    def derivatives(self, q):
        """(J, q̇, q̈, parts) batched; NaN rows where J is singular."""
        pl, N = self.pl, len(q)
        sides = self._sides(q)
        J = self.jacobian(q, sides)
        nc = len(pl.crank_idx)
        rhs = np.zeros((N, self.n, nc))
        rhs[:, self.c0 + np.arange(nc), np.arange(nc)] = pl.omega
        with np.errstate(all="ignore"):
            try:
                parts = np.linalg.solve(J, rhs)
            except np.linalg.LinAlgError:
                parts = np.full((N, self.n, nc), np.nan)
                for i in range(N):
                    with contextlib.suppress(np.linalg.LinAlgError):
                        parts[i] = np.linalg.solve(J[i], rhs[i])
            qdot = parts.sum(axis=2)
            g = self.gamma(q, qdot, sides)
            qddot, fine = np.full_like(qdot, np.nan), np.all(np.isfinite(qdot), axis=1)
            if np.any(fine):
                qddot[fine] = np.linalg.solve(J[fine], g[fine][..., None])[..., 0]
        return J, qdot, qddot, parts

    def newton(self, q, angles, max_iter=30):
        """Batched Newton from q (N, n); returns (q, converged mask)."""
        q = q.copy()
        previous = np.full(len(q), np.inf)
        active, ok = np.ones(len(q), dtype=bool), np.zeros(len(q), dtype=bool)
        for k in range(max_iter):
            idx = np.flatnonzero(active)
            if idx.size == 0:
                break
            qi = q[idx]
            sides = self._sides(qi)
            r = self.residual(qi, angles[idx], sides)
            size = np.max(np.abs(r), axis=1)
            done = size < self.tol
            ok[idx[done]] = True
            # a growing residual means no assembly near here: give up at once
            diverging = ((size > previous[idx]) & (k >= 2)) | ~np.isfinite(size)
            previous[idx] = size
            # a converged row takes one more step: from a residual just below
            # tol, quadratic convergence then leaves rounding only
            go = done | ~diverging
            active[idx[~go | done]] = False
            if not np.any(go):
                break
            J = self.jacobian(qi[go], tuple(x[go] for x in sides))
            sel, r = idx[go], r[go]
            try:
                q[sel] -= np.linalg.solve(J, r[..., None])[..., 0]
            except np.linalg.LinAlgError:
                for i, Ji, ri in zip(sel, J, r):       # one singular matrix: row by row
                    try:
                        q[i] -= np.linalg.solve(Ji, ri)
                    except np.linalg.LinAlgError:
                        active[i] = ok[i] = False
        return q, ok

    def step(self, q, angles):
        """One position, sequentially: Newton, then q̇, q̈ and the sign of det J.

        Returns (q, q̇, q̈, sign) or None (no convergence, or J near singular).
        LAPACK's dgesv/dgetrs are called directly: for one small matrix the
        numpy wrappers cost more than the arithmetic.
        """
        from scipy.linalg import lapack

        previous = math.inf
        q = q[None].copy()
        angles = angles[None]
        for k in range(30):
            sides = self._sides(q)
            r = self.residual(q, angles, sides)[0]
            size = float(np.max(np.abs(r)))
            if not math.isfinite(size) or (k >= 2 and size > previous):
                return None
            previous = size
            lu, piv, dq, info = lapack.dgesv(self.jacobian(q, sides)[0], r)
            if info != 0:
                return None
            if size < self.tol:
                # converged: the LU of J at q serves the derivatives (they only
                # feed predictors; the targets are polished in the batch)
                break
            q[0] -= dq
        else:
            return None
        d = np.abs(lu.diagonal())
        if not d.min() > 1e-12 * d.max():
            return None
        pl = self.pl
        # one column at a time: a multi-column dgetrs hands the triangular
        # solves to a threaded BLAS that costs milliseconds on a busy machine
        qdot = np.zeros(self.n)
        for j in range(len(pl.crank_idx)):
            e = np.zeros(self.n)
            e[self.c0 + j] = pl.omega[j]
            qdot += lapack.dgetrs(lu, piv, e)[0]
        qddot = lapack.dgetrs(lu, piv, self.gamma(q, qdot[None], sides)[0])[0]
        swaps = int(np.count_nonzero(piv != np.arange(len(piv))))
        sign = math.copysign(1.0, float(np.prod(lu.diagonal()))) * (-1) ** swaps
        return q[0], qdot, qddot, sign


def _compiled(kernel: str) -> bool:
    """Whether to run the compiled loop ``kernel`` of :mod:`._linkage_kernels` (numba;
    plain Python without it when ``mechcirc._jit.COMPILED`` is True) rather than the
    batched numpy path.  With COMPILED None (default) only once numba's disk cache holds
    it: until then numpy runs while a detached process compiles it
    (:func:`mechcirc._jit.warm_in_background`); False: numpy.  The one such loop is
    ``newton_path`` (the dyads have none: see :mod:`._linkage_kernels`)."""
    if _jit.COMPILED is False:
        return False
    from . import _linkage_kernels as K

    if not K.HAVE_NUMBA:
        return bool(_jit.COMPILED)
    return _jit.use(_WARM_STATEMENT, getattr(K, kernel))


# Compiles newton_path into numba's disk cache: a four-bar solved by Newton.
_WARM_STATEMENT = (
    "import numpy as np, mechcirc._jit as j; j.COMPILED = True\n"
    "from mechcirc.kinematics import parse_linkage\n"
    "lk = parse_linkage('[points]\\nA = [0.0, 0.0]\\nB = [1.0, 0.0]\\nC = [3.0, 2.0]\\n"
    "D = [4.0, 0.0]\\n[ground]\\npoints = [\"A\", \"D\"]\\n[links]\\ncrank = [\"A\", \"B\"]\\n"
    "coupler = [\"B\", \"C\"]\\nrocker = [\"D\", \"C\"]\\n[[cranks]]\\nlink = \"crank\"\\n"
    "omega = 10.0\\n')\n"
    "lk.motion(np.linspace(0.0, 1.0, 5), method='newton')\n")


def _solve_newton_compiled(lk, pl, t, dt_max, q0, t0):
    """The continuation as one compiled loop (:mod:`._linkage_kernels`), from q0 at time t0."""
    from . import _linkage_kernels as K

    N, n, nc = len(t), 3 * pl.nb, len(pl.crank_idx)
    Q, QD, QDD = np.empty((N, n)), np.empty((N, n)), np.empty((N, n))
    parts, info = np.empty((N, n, nc)), np.zeros(2)
    w1 = lk.cranks[0].omega
    vec = np.zeros((6, n))          # the kernel's scratch: it allocates nothing
    vec[0] = q0
    work = (np.empty(pl.nb), np.empty(pl.nb), np.empty((len(pl.ia), 4)), np.empty((len(pl.ga), 8)))
    status = K.newton_path(float(t0), np.ascontiguousarray(t, dtype=float), pl.ia, pl.ib, pl.sa,
                           pl.sb, pl.crank_idx, pl.omega, 1e-12 * pl.scale, float(dt_max),
                           float(np.max(np.abs(pl.omega))), Q, QD, QDD, parts, info,
                           pl.ga, pl.gb, pl.gs, pl.gu, pl.bs, work, np.empty((n, n)),
                           np.empty(n, np.int64), vec, np.zeros((n, nc)))
    if status == K.SINGULAR_POSE:
        raise _singular_pose(lk)
    if status == K.LOCK:
        raise _lock(lk, info[0] * w1)
    if status == K.BRANCH_JUMP:
        raise _branch_jump(lk, info[0] * w1, info[1] * w1)
    return Q, QD, QDD, parts


def _solve_newton(lk, pl, t, dt_max, start=None):
    """Newton's continuation from ``start`` ((q, time); default the pose) through times
    ``t``: the compiled loop when it is loaded, else in numpy."""
    q0, t0 = (pl.q0, 0.0) if start is None else start
    if _compiled("newton_path"):
        return _solve_newton_compiled(lk, pl, t, dt_max, q0, t0)
    nw = Newton(pl)
    nodes, at = _path(t, dt_max, t0)
    first = nw.step(q0, pl.omega * t0)
    if first is None:
        raise _singular_pose(lk)
    # The sequential continuation visits only the nodes it needs (consecutive
    # kept nodes at most dt_max apart along the path); every other node is
    # solved afterwards in one batch from the kept node before it.
    arc = np.concatenate(([0.0], np.cumsum(np.abs(np.diff(nodes)))))
    keep = [0]
    for k in range(1, len(nodes)):
        if k == len(nodes) - 1 or arc[k + 1] - arc[keep[-1]] > dt_max * (1 + 1e-12):
            keep.append(k)
    keep = np.array(keep)
    kept = _kept_nodes(lk, nw, nodes[keep], first, dt_max)
    return _targets(lk, nw, t, nodes, keep, at, kept, first[3], dt_max)


def _kept_nodes(lk, nw, T_keep, first, dt_max):
    """The continuation through the kept nodes at times ``T_keep`` (the first the pose).

    Returns (q, q̇, q̈, parts, exact) per node; ``exact``: solved in a block,
    polished, with batched derivatives (a target on one is taken as it is).
    """
    pl = nw.pl
    q, qdot, qddot, sign = first
    Qk, Qdk, Qddk = (np.empty((len(T_keep), nw.n)) for _ in range(3))
    Qk[0], Qdk[0], Qddk[0] = q, qdot, qddot
    # nodes solved by a block are final (polished, with batched derivatives):
    # a target on one is taken as it is
    exact = np.zeros(len(T_keep), dtype=bool)
    Pk = np.empty((len(T_keep), nw.n, len(pl.crank_idx)))
    t_now = T_keep[0]
    j, block = 1, 16
    while j < len(T_keep):
        if block > 1:
            # Blocks of nodes together: Taylor predictors from the last solved
            # node, batched Newton and derivatives, accepted only if every node
            # keeps the sign of det J and sits within 1 % of the size of the
            # Taylor step from the node before it (another assembly is a size
            # away); otherwise the block shrinks down to single steps.
            jj = min(len(T_keep), j + block)
            T = T_keep[j:jj]
            if (got := _block(nw, q, qdot, qddot, t_now, T, sign, pl)) is not None:
                Qk[j:jj], Qdk[j:jj], Qddk[j:jj], Pk[j:jj] = got
                exact[j:jj] = True
                q, qdot, qddot, t_now = got[0][-1], got[1][-1], got[2][-1], T[-1]
                j, block = jj, min(2 * block, 64)
                continue
            block //= 2
            continue
        q, qdot, qddot, t_now = _steps_to(lk, nw, q, qdot, qddot, t_now, T_keep[j], sign,
                                          dt_max)
        Qk[j], Qdk[j], Qddk[j] = q, qdot, qddot
        j, block = j + 1, 2
    return Qk, Qdk, Qddk, Pk, exact


def _steps_to(lk, nw, q, qdot, qddot, t_now, t_target, sign, dt_max):
    """Single Newton steps of at most ``dt_max`` from the node (q, q̇, q̈) at ``t_now`` to
    ``t_target``, each from a Taylor predictor, halved until it assembles; the node there
    and ``t_target``.  Raises where the linkage locks or changes branch (``sign`` of det J)."""
    pl, w1 = nw.pl, lk.cranks[0].omega
    wmax = float(np.max(np.abs(pl.omega)))
    while t_now != t_target:
        dt = max(-dt_max, min(dt_max, t_target - t_now))
        while True:
            guess = q + qdot * dt + 0.5 * qddot * dt * dt
            res = nw.step(guess, pl.omega * (t_now + dt))
            if res is not None:
                break
            dt *= 0.5
            if abs(dt) * wmax < 1e-9:
                raise _lock(lk, (t_now + 2 * dt) * w1)
        if res[3] != sign:
            raise _branch_jump(lk, t_now * w1, (t_now + dt) * w1)
        q, qdot, qddot, _ = res
        t_now = t_now + dt
    return q, qdot, qddot, t_now


def _targets(lk, nw, t, nodes, keep, at, kept, sign, dt_max):
    """Every target from the kept nodes around it; see the comment below."""
    pl, w1 = nw.pl, lk.cranks[0].omega
    Qk, Qdk, Qddk, Pk, exact = kept
    # Every target lies between two kept nodes (or is one): quintic Hermite
    # interpolation from their q, q̇, q̈ (error ~ h⁶ q⁽⁶⁾/720, about 1e-12 of
    # the size at the default spacing), then batched Newton — usually one
    # polishing step — and two batched solves for q̇, q̈.
    src = np.searchsorted(keep, at, side="right") - 1
    done = exact[src] & (keep[src] == at)
    if np.all(done):
        return Qk[src], Qdk[src], Qddk[src], Pk[src]
    final = (Qk[src[done]], Qdk[src[done]], Qddk[src[done]], Pk[src[done]])
    rest = np.flatnonzero(~done)
    src, at, t = src[rest], at[rest], t[rest]
    nxt = np.minimum(src + 1, len(keep) - 1)
    t0, t1 = nodes[keep[src]], nodes[keep[nxt]]
    h = np.where(t1 != t0, t1 - t0, 1.0)       # past the last node: u = 0, at its values
    u = np.where(t1 != t0, (nodes[at] - t0) / h, 0.0)
    guess = _quintic(u, h, (Qk[src], Qdk[src], Qddk[src]), (Qk[nxt], Qdk[nxt], Qddk[nxt]))
    angles = pl.omega[None, :] * t[:, None]
    start = np.max(np.abs(nw.residual(guess, angles)), axis=1)
    Q, ok = nw.newton(guess, angles)
    for i in np.flatnonzero(~ok):              # rare: redo from the node, sequentially
        Q[i] = _steps_to(lk, nw, Qk[src[i]], Qdk[src[i]], Qddk[src[i]], nodes[keep[src[i]]],
                         t[i], sign, dt_max)[0]
    J, qd, qdd, parts = nw.derivatives(Q)
    bad = ~np.all(np.isfinite(qd), axis=1) | ~np.all(np.isfinite(qdd), axis=1)
    if np.any(bad):
        th = math.degrees(t[int(np.argmax(bad))] * w1)
        raise GeometryError(f"{lk.source}: singular position at θ = {th:.6g}° (constraint "
                            f"Jacobian not invertible)")
    # a target whose interpolated start was not already close could have
    # converged elsewhere: check its det J sign (the nodes were checked)
    far = np.flatnonzero(~(start < 1e-6 * pl.scale) | ~ok)
    if far.size:
        sgn = np.sign(np.linalg.det(J[far]))
        if np.any(sgn != sign):
            raise _branch_jump(lk, t[far[int(np.argmax(sgn != sign))]] * w1)
    out = []
    for a, b in zip(final, (Q, qd, qdd, parts)):
        full = np.empty((len(done),) + a.shape[1:])
        full[done], full[rest] = a, b
        out.append(full)
    return tuple(out)


def _quintic(u, h, a, b, k=0):
    """The k-th time derivative, at u = (t − t0)/h (N,), of the quintic through the
    (y, y', y'') of ``a`` at t0 and of ``b`` at t0 + h (h (N,), each y (N, n))."""
    c = quintic(h[:, None], a, b)
    tau = np.asarray(u)[:, None] * h[:, None]
    return sum(math.perm(p, k) * c[p] * tau ** (p - k) for p in range(k, 6))


def _block(nw, q, qdot, qddot, t_now, T, sign, pl):
    """Solve the nodes at times ``T`` together from (q, q̇, q̈) at ``t_now``; None if unsafe."""
    d = (T - t_now)[:, None]
    guess = q + qdot * d + 0.5 * qddot * d * d
    Q, ok = nw.newton(guess, pl.omega[None, :] * T[:, None])
    if not ok.all():
        return None
    J, qd, qdd, parts = nw.derivatives(Q)
    if not (np.all(np.isfinite(qd)) and np.all(np.isfinite(qdd))):
        return None
    with np.errstate(all="ignore"):
        if not np.all(np.sign(np.linalg.det(J)) == sign):
            return None
    prev_q, prev_d, prev_dd = (np.vstack([x[None], y[:-1]]) for x, y in
                               ((q, Q), (qdot, qd), (qddot, qdd)))
    h = np.diff(np.concatenate(([t_now], T)))[:, None]
    pred = prev_q + prev_d * h + 0.5 * prev_dd * h * h
    return (Q, qd, qdd, parts) if np.max(np.abs(pred - Q)) <= 1e-2 * pl.scale else None
