"""Planar linkages (revolute and prismatic joints) with any number of driving cranks (Koshel & Koshel 2014).

File format (TOML, lengths in any consistent unit, angular velocities in rad/s)::

    name = "four-bar"                    # optional
    [points]                             # every joint in one assembled pose
    A = [0.0, 0.0]
    B = [29.0, 0.0]
    C = [...]
    D = [189.0, 0.0]

    [ground]
    points = ["A", "D"]                  # pivots fixed to the frame

    [links]                              # rigid moving links as point sets
    crank = ["A", "B"]                   # binary link
    coupler = ["B", "C"]
    rocker = ["C", "D"]                  # (a ternary link lists three points)

    [[cranks]]                           # one table per driving crank
    link = "crank"
    omega = 100.0                        # [rad/s], constant

Each link's shape is read from the pose, so the pose is an exact assembly.
A point shared by k bodies (links, and the ground if it is a pivot) is a
revolute joint contributing k − 1 pairs.  The mobility is Grübler's
W = 3·n − 2·p (n moving links, p revolute pairs) and must equal the number of
cranks.  A crank must be a link with a ground pivot; its angle is driven.

State and equations.  Each moving link i carries a frame with origin r_i at
its first listed point and angle φ_i (0 in the pose); a point with pose
offset s from that origin sits at ``r_i + R(φ_i) s``.  Constraints Φ(q, t) = 0:
coincident points of the bodies meeting at each joint (2 rows per pair) and
``φ_c − ω_c t = 0`` for each crank c.  Then

* position: Newton on Φ = 0, continued from the previous position in crank
  steps of at most ``max_step_deg`` (branch continuity); the sign of det J is
  tracked, and a change (the linkage passed a singular position onto another
  branch) is an error;
* velocity: J q̇ = [0 … 0, ω_1 … ω_k];
* acceleration: J q̈ = γ with γ = Σ (R(φ_i) s_i φ̇_i² − R(φ_j) s_j φ̇_j²) for
  each joint row (constant crank speeds);
* "conditional stop" (Koshel & Koshel 2014, eq. (6)–(8)): the contribution of crank c
  is J⁻¹ ω_c e_c, the velocity with every other crank stopped; the velocity is
  their sum, exactly, because J q̇ is linear in (ω_1 … ω_k).

The drive parameter θ is the rotation of the first crank from the pose
[rad]; time is t = θ/ω_1.

Prismatic joints (sliders).  A ``[[sliders]]`` table makes ``link`` slide
without turning along a straight guide fixed to ``guide`` (``"ground"`` or a
moving link)::

    [[sliders]]
    link = "block"                       # the sliding link (one point is enough)
    guide = "ground"                     # or the link it slides on
    line = ["G1", "G2"]                  # two points of the guide (ground points here)
    point = "C"                          # the block's point on that line (default:
                                         # the block's only point)

The guide line G1→G2 is fixed in the guide's frame; in the pose ``point``
must lie on it (else "off its guide", with the distance).  An optional
``stroke = [min, max]`` bounds ``point`` along the line from its first point;
a position beyond it is a located error.  A prismatic pair counts as one pair in
Grübler's formula, W = 3·n − 2·(p_revolute + p_prismatic), and gives two
constraint rows: the block's point on the line, u_g × (P − G) = 0, and no
relative turning, φ_block − φ_guide = 0.
"""

from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .._memo import Memos
from ..errors import GeometryError, InputError, NetlistError, unknown_name
from .linkage_solver import MAX_CONTINUATION_STEPS  # noqa: F401
from .linkage_solver import LinkageMotion, LinkageState, Newton, motion, plan

__all__ = ["Crank", "Slider", "AssurGroup", "Linkage", "LinkageState", "LinkageMotion",
           "parse_linkage",
           "load_linkage"]


@dataclass(frozen=True)
class Crank:
    """A driving crank: ``link`` turns about its ground ``pivot`` at ``omega`` [rad/s]."""

    link: str
    pivot: str
    omega: float


@dataclass(frozen=True)
class Slider:
    """A prismatic pair: ``link`` slides along a line fixed to ``guide`` ("ground" or a link).

    The line passes through the pose of ``point`` (a point of ``link``) along
    the unit vector ``direction`` (pose coordinates), from the guide's points ``line``.
    ``stroke`` bounds ``point``'s place along it, measured from ``line[0]``
    towards ``line[1]``; :meth:`Linkage.motion` refuses a position beyond it.
    """

    link: str
    guide: str
    point: str
    direction: tuple
    line: tuple = ()
    stroke: tuple = ()        # (min, max) along line[0] → line[1] from line[0]; () = any
    stroke_at: tuple[int, int] = (0, 0)  # (line, col) of ``stroke`` in the file, for its errors

    @property
    def pair(self) -> str:
        """The pair's name in :meth:`Linkage.assur_groups` (``"slider:LINK"``)."""
        return f"slider:{self.link}"


@dataclass(frozen=True)
class AssurGroup:
    """A structural (Assur) group: links with zero mobility once their outer pairs are fixed.

    Attributes
    ----------
    links : tuple of str
        The group's links.
    internal_pairs : tuple of str
        Joints inside the group.
    external_pairs : tuple of str
        Joints attaching it to the ground, the cranks or earlier groups; their
        number is the group's order.
    group_class : int
        Artobolevsky's class: 2 for a dyad; 3 for a triad (a ternary base link
        carrying three binary links, each ending in an external pair); 0 when
        a larger group is not classified here.
    base : str or None
        The ternary base link of a class-III group.
    """

    links: tuple
    internal_pairs: tuple
    external_pairs: tuple
    group_class: int
    base: str | None = None

    @property
    def order(self) -> int:
        """Number of external pairs."""
        return len(self.external_pairs)


def _next_group(joints, known, remaining):
    """The smallest set S of the ``remaining`` links with 3·|S| = 2·(pairs among S and the
    ``known`` bodies), as (links, inner pairs, outer pairs); None if there is none."""
    for size in range(2, len(remaining) + 1, 2):
        for combo in itertools.combinations(remaining, size):
            S, pairs = set(combo), 0
            outer_pairs: list[str] = []
            inner_pairs: list[str] = []
            for p, members in joints.items():
                inside = [m for m in members if m in S]
                outside = [m for m in members if m in known]
                if not inside:
                    continue
                m = len(inside) + len(outside)
                if m >= 2:
                    pairs += m - 1
                    (outer_pairs if outside else inner_pairs).append(p)
            if 3 * size == 2 * pairs:
                return combo, tuple(inner_pairs), tuple(outer_pairs)
    return None


def _rot(phi):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s], [s, c]])



@dataclass(frozen=True, eq=False)
class Linkage(Memos):
    """A parsed planar linkage; see the module docstring for the file format.

    Use :func:`load_linkage` or :func:`parse_linkage` to build one.

    Attributes
    ----------
    name : str
        The file's ``name`` (default: the file's stem).
    pose : dict[str, ndarray (2,)]
        Every point in the assembled pose.
    ground : tuple of str
        Ground pivots.
    links : dict[str, tuple of str]
        Moving links as point lists (first point = the link frame's origin).
    cranks : tuple of Crank
        The driven links, the first being the main crank.
    source : str
        File name, for messages.
    units : str
        The file's ``units`` (the length unit of the pose, e.g. ``"mm"``), or ``""``.
    sliders : tuple of Slider
        Prismatic pairs.
    """

    name: str
    pose: dict
    ground: tuple
    links: dict
    cranks: tuple
    source: str = "<string>"
    units: str = ""
    sliders: tuple = ()

    # ------------------------------------------------------------ structure
    @property
    def link_names(self) -> tuple[str, ...]:
        return tuple(self.links)

    def joints(self) -> dict[str, tuple[str, ...]]:
        """Point → bodies meeting there (``"ground"`` first when it is a pivot), for shared points."""
        out = {}
        for p in self.pose:
            members = (["ground"] if p in self.ground else []) + \
                [l for l, pts in self.links.items() if p in pts]
            if len(members) >= 2:
                out[p] = tuple(members)
        return out

    @property
    def revolute_pairs(self) -> int:
        """Number of revolute pairs p (a joint of k bodies counts k − 1)."""
        return sum(len(m) - 1 for m in self.joints().values())

    @property
    def mobility(self) -> int:
        """Grübler's W = 3n − 2p (p: revolute and prismatic pairs)."""
        return 3 * len(self.links) - 2 * (self.revolute_pairs + len(self.sliders))

    def pairs(self) -> dict[str, tuple[str, ...]]:
        """Every pair → its bodies: the revolute :meth:`joints`, then each slider's pair."""
        out = self.joints()
        for s in self.sliders:
            out[s.pair] = (s.guide, s.link)
        return out

    def assur_groups(self) -> tuple[AssurGroup, ...]:
        """Decompose the linkage into Assur groups, in the order they can be solved.

        Starting from the ground and the cranks, repeatedly take the smallest
        set S of remaining links with 3·|S| = 2·(pairs among S and the known
        bodies); S is the next group.  Exhaustive over subsets, fine for the
        handful of links of a loom mechanism.

        Raises
        ------
        GeometryError
            Some links form no group (the structure does not decompose).
        """
        joints = self.pairs()
        known = {"ground"} | {c.link for c in self.cranks}
        remaining = [l for l in self.links if l not in known]
        groups = []
        while remaining:
            found = _next_group(joints, known, remaining)
            if not found:
                raise GeometryError(f"{self.source}: links {', '.join(remaining)} form no Assur "
                                    f"group on the ground and cranks")
            combo, inner, ext = found
            cls, base = (2 if len(combo) == 2 else 0), None
            if len(combo) == 4:
                degree = {l: sum(1 for p in inner + ext if l in joints[p]) for l in combo}
                ternary = [l for l in combo if degree[l] == 3]
                if (len(ternary) == 1 and len(ext) == 3
                        and all(degree[l] == 2 for l in combo if l != ternary[0])):
                    cls, base = 3, ternary[0]
            groups.append(AssurGroup(tuple(combo), inner, ext, cls, base))
            known |= set(combo)
            remaining = [l for l in remaining if l not in combo]
        return tuple(groups)

    def link_index(self) -> dict[str, int]:
        """link → its index i in the coordinates q (its x, y, φ are q[3i:3i + 3])."""
        return {n: i for i, n in enumerate(self.link_names)}

    def local_offsets(self) -> dict[str, dict[str, NDArray[np.float64]]]:
        """link → {point: pose offset from the link's first point} [m]."""
        return {l: {p: self.pose[p] - self.pose[pts[0]] for p in pts}
                for l, pts in self.links.items()}

    def constraint_rows(self) -> list[tuple[str, str, str]]:
        """Constraint rows: list of (point, body_a, body_b) with body_a possibly 'ground'."""
        return [(p, members[0], other) for p, members in self.joints().items()
                for other in members[1:]]

    # ----------------------------------------------------------- kinematics
    def q0(self) -> NDArray[np.float64]:
        """Generalised coordinates of the pose."""
        q = np.zeros(3 * len(self.links))
        for i, pts in enumerate(self.links.values()):
            q[3 * i:3 * i + 2] = self.pose[pts[0]]
        return q

    def length_scale(self) -> float:
        """The larger side of the pose's bounding box [m] (1 if all points coincide)."""
        pts = np.array(list(self.pose.values()))
        return float(np.max(np.ptp(pts, axis=0))) or 1.0


    @cached_property
    def _plan(self):
        return plan(self)

    @property
    def solver(self) -> str:
        """``"dyads"`` (closed form per RRR, RRP or RPR dyad) or ``"newton"``: how
        :meth:`motion` solves."""
        return self._plan.method

    def motion(self, theta: float | NDArray, *, max_step_deg: float = 2.0,
               method: str = "auto"):
        """Kinematics at first-crank rotations ``theta`` [rad] as arrays (a :class:`LinkageMotion`).

        The fast path: no per-position objects.  A linkage made of dyads only
        (RRR: a four-bar, a Watt or Stephenson six-bar; RRP, RPR: a
        slider-crank, a quick return) is solved in closed form, vectorised; any other by warm-started, batched Newton with the
        analytic Jacobian (see :mod:`.linkage_solver`).

        Parameters
        ----------
        theta : float or array_like
            Rotation of the first crank from the pose [rad]; an array is a path
            traversed in order from the pose (branch continuity; at a change
            point, where an RRR or RRP dyad lines up as its two assembly modes
            cross, the branch whose velocity is continuous).
        max_step_deg : float
            Largest rotation of any crank between two continuation nodes [deg];
            the dyad path checks the assembly at the same spacing.
        method : {"auto", "dyads", "newton"}
            ``"auto"``: closed form when the linkage is made of dyads, else Newton.

        Raises
        ------
        GeometryError
            The linkage locks (no assembly, or a singular Jacobian) — the
            message gives the first θ where it does — or the continuation
            jumped to another branch.
        NetlistError
            A slider passes its ``stroke`` at one of the positions (located
            at the ``stroke`` key in the file).
        """
        return motion(self, self._plan, theta, max_step_deg=max_step_deg, method=method)

    def solve(self, theta: float | NDArray, *, max_step_deg: float = 2.0,
              method: str = "auto"):
        """Positions, velocities and accelerations at first-crank rotation(s) ``theta`` [rad].

        Parameters
        ----------
        theta : float or array_like
            Rotation of the first crank from the pose [rad].  An array is
            traversed in order, each position continued from the previous one.
        max_step_deg : float
            Largest rotation of any crank in one continuation step [deg].
        method : {"auto", "dyads", "newton"}
            See :meth:`motion`, which this wraps.

        Returns
        -------
        LinkageState, or a list of them for an array.

        Raises
        ------
        GeometryError, NetlistError
            As :meth:`motion`, which this wraps.
        """
        out = self.motion(theta, max_step_deg=max_step_deg, method=method).states()
        return out[0] if np.ndim(theta) == 0 else out

    def assemble(self, crank_angles: dict, near: NDArray | None = None) -> dict:
        """Point positions with each crank turned by ``crank_angles[link]`` [rad] from the pose.

        One Newton solve from ``near`` (generalised coordinates, default the
        pose), with no continuation: cranks may be set independently (e.g. one
        stopped), which :meth:`solve` cannot do.

        Raises
        ------
        GeometryError
            Newton does not converge (no assembly near ``near``).
        UnknownNameError, InputError
            A key of ``crank_angles`` is no crank's link, a crank's link has no angle, or
            an angle is no finite number.
        """
        links = [c.link for c in self.cranks]
        stray = [k for k in crank_angles if k not in links]
        if stray:
            raise unknown_name(stray[0], links, "crank link")
        missing = [k for k in links if k not in crank_angles]
        if missing:
            raise InputError(f"crank_angles has no angle for crank link {missing[0]!r}: give "
                             f"one for each of {', '.join(map(repr, links))} [rad]")
        q = self.q0() if near is None else np.array(near, dtype=float)
        angles = real_values([crank_angles[k] for k in links], "crank_angles", "rad")[None]
        (q,), (ok,) = Newton(self._plan).newton(q[None], angles)
        if not ok:
            raise GeometryError(f"{self.source}: no assembly for crank angles {crank_angles} "
                                "near the given coordinates (the links cannot close there); "
                                "give angles the linkage reaches, or near= closer to one")
        # each point on its owner's frame (the plan's: its first link), or on the ground
        pts = {p: x.copy() if o == len(self.links) else q[3 * o:3 * o + 2] + _rot(q[3 * o + 2]) @ s
               for (p, x), o, s in zip(self.pose.items(), self._plan.owner, self._plan.offsets)}
        return {"q": q, "points": pts}


# ------------------------------------------------------------------ parsing
# The located-TOML helpers are shared with the scene and study readers.
from ..sources import (Table, brief, check_keys, did_you_mean, finite_number,  # noqa: E402
                       load_toml, locate, located, read_source, real_values)
from ..units import in_si  # noqa: E402

#: The tables of a linkage file, declared once (see :class:`mechcirc.sources.Table`);
#: ``[points]`` and ``[links]`` map names of the user's choice.
TABLES = {
    None: Table(None, {"cranks": "[[cranks]]: the driving cranks", "description": "free text",
                       "sliders": "[[sliders]]: prismatic pairs",
                       "ground": "[ground]: points = [ground pivots]",
                       "links": "[links]: NAME = [two or more points]",
                       "name": "the linkage's name (default: the file's stem)",
                       "points": "[points]: NAME = [x, y]",
                       "units": "the length unit of [points], e.g. \"mm\""}),
    "ground": Table("ground", {"points": "the ground pivots' names"}),
    "cranks": Table("cranks", {"link": "the driven link", "pivot": "its ground pivot",
                               "omega": "its angular velocity [rad/s], nonzero"}, array=True),
    "sliders": Table("sliders", {"link": "the sliding link",
                                 "guide": "\"ground\" or the link it slides on",
                                 "line": "[two points of the guide] along the guide",
                                 "point": "the sliding link's point on the line",
                                 "stroke": "[min, max]: where the point may be along the "
                                           "line, from its first point"}, array=True),
}


def parse_linkage(text: str, source: str = "<string>") -> Linkage:
    """Parse the TOML text of a linkage (see the module docstring).

    Parameters
    ----------
    text : str
        The TOML text.
    source : str
        Name of the text in error messages (a file name).

    Returns
    -------
    Linkage
        The linkage, ready to :meth:`Linkage.solve` at any crank angle.

    Raises
    ------
    NetlistError
        TOML syntax, a missing table, an unknown point or link, a bad value —
        located at file:line:col.
    GeometryError
        The mobility differs from the number of cranks (says W), or a link's
        points coincide.
    """
    doc = load_toml(text, source)
    _check_tables(doc, text, source)
    pose = _read_points(doc["points"], text, source)
    ground_pts = _read_ground(doc["ground"], pose, text, source)
    raw_sliders = doc.get("sliders", [])
    if not isinstance(raw_sliders, list) or not all(isinstance(x, dict) for x in raw_sliders):
        raise located(text, source, f"'sliders' must be a [[sliders]] table, got "
                      f"{brief(raw_sliders)}", None, "sliders", expected="[[sliders]]")
    slider_links = {x.get("link") for x in raw_sliders if isinstance(x.get("link"), str)}
    links = _read_links(doc["links"], pose, text, source, slider_links)
    _check_every_point_used(pose, ground_pts, links, text, source)
    cranks = _read_cranks(doc["cranks"], links, ground_pts, text, source)
    sliders = _read_sliders(raw_sliders, pose, links, ground_pts, text, source)
    units = _read_units(doc, text, source)
    lk = Linkage(str(doc.get("name", Path(source).stem)), pose, tuple(ground_pts), links,
                 tuple(cranks), source, units, tuple(sliders))
    if lk.mobility != len(cranks):
        pairs = f"({lk.revolute_pairs} + {len(sliders)})" if sliders else lk.revolute_pairs
        raise GeometryError(
            f"{source}: mobility W = 3·{len(links)} − 2·{pairs} = "
            f"{lk.mobility}, but {len(cranks)} crank(s) are driven; W must equal the number "
            f"of cranks")
    return lk


def _check_tables(doc: dict, text: str, source: str) -> None:
    """The four tables are there with the right shape, and no unknown top-level key."""
    for table in ("points", "ground", "links", "cranks"):
        header = "[[cranks]]" if table == "cranks" else f"[{table}]"
        if table not in doc:
            raise NetlistError(f"missing {header} table", source, 0, 0,
                               "points, ground, links and cranks")
        kind = list if table == "cranks" else dict
        if not isinstance(doc[table], kind) or (
                table == "cranks" and not all(isinstance(c, dict) for c in doc[table])):
            raise located(text, source, f"{table!r} must be a {header} table, got "
                          f"{brief(doc[table])}", None, table, expected=header)
    check_keys(text, source, TABLES[None], doc)


def _read_points(table: dict, text: str, source: str) -> dict[str, NDArray[np.float64]]:
    """[points]: name → [x, y] of two finite numbers."""
    pose = {}
    for name, xy in table.items():
        ok = isinstance(xy, list) and len(xy) == 2 and all(map(finite_number, xy))
        if not ok:
            raise located(text, source, f"point {name!r} must be [x, y], got {brief(xy)}",
                       "points", name, expected="two finite numbers")
        pose[name] = np.array(xy, dtype=float)
    return pose


def _read_ground(table: dict, pose: dict, text: str, source: str) -> list[str]:
    """[ground] points: a nonempty list of known point names."""
    check_keys(text, source, TABLES["ground"], table)
    ground_pts = table.get("points")
    if not isinstance(ground_pts, list) or not ground_pts:
        raise located(text, source, "[ground] needs points = [\"…\", …]", "ground", "points",
                   expected="a list of ground pivot names")
    for p in ground_pts:
        if not isinstance(p, str) or p not in pose:
            raise located(text, source, f"unknown point {p!r} in [ground]", "ground", "points",
                       value=p, choices=pose)
    return ground_pts


def _read_links(table: dict, pose: dict, text: str, source: str,
                sliders=frozenset()) -> dict[str, tuple[str, ...]]:
    """[links]: name → two or more distinct known points, not all at one place (a slider's
    link may have one point)."""
    links = {}
    for lname, pts in table.items():
        least = 1 if lname in sliders else 2
        if not isinstance(pts, list) or len(pts) < least or \
                not all(isinstance(p, str) for p in pts):
            stray = sorted(s for s in sliders if s not in table)   # a slider's misspelt link
            why = (f"; [[sliders]] names {stray[0]!r}, which is no link"
                   f"{did_you_mean(stray[0], table)}") if stray and least == 2 else ""
            raise located(text, source, f"link {lname!r} must list at least two point names "
                          f"(one for a slider's link){why}",
                       "links", lname, expected='["P1", "P2", …]')
        for p in pts:
            if p not in pose:
                raise located(text, source, f"unknown point {p!r} in link {lname!r}", "links",
                           lname, value=p, choices=pose)
        if len(set(pts)) != len(pts):
            raise located(text, source, f"link {lname!r} lists a point twice", "links", lname)
        if lname == "ground":
            raise located(text, source, "'ground' is reserved for the frame", "links", lname)
        xy = np.array([pose[p] for p in pts])
        if len(pts) > 1 and np.max(np.ptp(xy, axis=0)) == 0.0:
            raise located(text, source, f"link {lname!r} has all its points at the same place "
                          f"{xy[0].tolist()}", "links", lname, expected="points at two places")
        links[lname] = tuple(pts)
    return links


def _check_every_point_used(pose, ground_pts, links, text: str, source: str) -> None:
    """Every point is on a link or a ground pivot."""
    used = set(ground_pts).union(*map(set, links.values()))
    for p in pose:
        if p not in used:
            raise located(text, source, f"point {p!r} belongs to no link and is not a ground pivot",
                       "points", p)


def _unknown(key: str, entry: dict, where: str) -> str:
    """The message for a missing or unknown name under ``key`` of a table's ``entry``."""
    if key not in entry:
        return f"{where} has no {key}"
    return f"unknown {key} {entry[key]!r} in {where}"


def _read_cranks(raw_cranks: list, links, ground_pts, text: str, source: str) -> list[Crank]:
    """[[cranks]]: each a known link, driven once, about one ground pivot, at omega ≠ 0."""
    if not isinstance(raw_cranks, list) or not raw_cranks:
        raise NetlistError("no [[cranks]]: at least one driving crank is needed", source)
    cranks: list[Crank] = []
    for n, c in enumerate(raw_cranks):
        check_keys(text, source, TABLES["cranks"], c, n)
        lname = c.get("link")
        if not isinstance(lname, str) or lname not in links:
            raise located(text, source, _unknown("link", c, f"[[cranks]] #{n + 1}"), "cranks",
                       "link", value=lname, occurrence=n, choices=links)
        pivots = [p for p in links[lname] if p in ground_pts]
        pivot = c.get("pivot", pivots[0] if len(pivots) == 1 else None)
        if pivot not in pivots:
            raise located(text, source, f"crank {lname!r} needs exactly one ground pivot among its "
                       f"points (found {pivots or 'none'}); name it with pivot = \"…\"",
                       "cranks", "pivot" if "pivot" in c else "link", occurrence=n)
        omega = in_si(text, source, c.get("omega"), "omega", "cranks", "omega", n)
        if not finite_number(omega) or omega == 0:
            raise located(text, source, f"crank {lname!r}: omega must be a nonzero number "
                       f"[rad/s], got {brief(omega)}", "cranks", "omega" if "omega" in c else "link",
                       occurrence=n)
        if any(k.link == lname for k in cranks):
            raise located(text, source, f"link {lname!r} is driven twice", "cranks", "link",
                       value=lname, occurrence=n)
        cranks.append(Crank(lname, pivot, float(omega)))
    return cranks


def _read_sliders(raw: list, pose, links, ground_pts, text: str, source: str) -> list[Slider]:
    """[[sliders]]: a link sliding once, on ground or another link, along two of the guide's
    points, with its point on that line in the pose."""
    out: list[Slider] = []
    scale = float(np.max(np.ptp(np.array(list(pose.values())), axis=0))) or 1.0
    for n, x in enumerate(raw):
        check_keys(text, source, TABLES["sliders"], x, n)
        lname, guide = x.get("link"), x.get("guide")
        if not isinstance(lname, str) or lname not in links:
            raise located(text, source, _unknown("link", x, f"[[sliders]] #{n + 1}"),
                          "sliders", "link", value=lname, occurrence=n, choices=links)
        if any(s.link == lname for s in out):
            raise located(text, source, f"link {lname!r} slides twice", "sliders", "link",
                          value=lname, occurrence=n)
        if guide != "ground" and (not isinstance(guide, str) or guide not in links
                                  or guide == lname):
            raise located(text, source, _unknown("guide", x, f"[[sliders]] #{n + 1}"),
                          "sliders", "guide" if "guide" in x else "link", occurrence=n,
                          expected="\"ground\" or another link: "
                                   f"{', '.join(k for k in links if k != lname)}")
        on_guide = ground_pts if guide == "ground" else links[guide]
        line = x.get("line")
        if not (isinstance(line, list) and len(line) == 2
                and all(isinstance(p, str) and p in on_guide for p in line)):
            raise located(text, source, f"slider {lname!r}: line must name two points of its "
                          f"guide {guide!r}, got {brief(line)}", "sliders",
                          "line" if "line" in x else "link", occurrence=n,
                          expected=f"two of {', '.join(on_guide)}")
        u = pose[line[1]] - pose[line[0]]
        size = float(np.hypot(*u))
        if size == 0.0:
            raise located(text, source, f"slider {lname!r}: the line's points {line[0]!r} and "
                          f"{line[1]!r} coincide", "sliders", "line", occurrence=n)
        own = links[lname]
        point = x.get("point", own[0] if len(own) == 1 else None)
        if point not in own:
            raise located(text, source, f"slider {lname!r}: point must be one of its points "
                          f"(got {brief(point)})", "sliders", "point" if "point" in x else
                          "link", occurrence=n, value=point, choices=own)
        u = u / size
        d = pose[point] - pose[line[0]]                # the point from the line's first point
        off = float(u[0] * d[1] - u[1] * d[0])
        if abs(off) > 1e-9 * scale:
            raise located(text, source, f"slider {lname!r} is off its guide: point {point!r} is "
                          f"{abs(off):.6g} from the line {line[0]}–{line[1]} in the pose",
                          "sliders", "point" if "point" in x else "line", occurrence=n,
                          expected=f"{point!r} on the line through {line[0]!r} and {line[1]!r}")
        stroke, at = _read_stroke(x, n, float(u @ d), lname, text, source)
        out.append(Slider(lname, guide, point, (float(u[0]), float(u[1])), tuple(line),
                          stroke, at))
    return out


def _read_stroke(x: dict, n: int, s0: float, lname: str, text: str, source: str):
    """A slider's ``stroke = [min, max]`` (min < max, the pose's place s0 inside) and its
    (line, col); ``((), (0, 0))`` without one."""
    if "stroke" not in x:
        return (), (0, 0)
    raw = x["stroke"]
    if not (isinstance(raw, list) and len(raw) == 2 and all(finite_number(v) for v in raw)
            and raw[0] < raw[1]):
        raise located(text, source, f"slider {lname!r}: stroke must be [min, max] with "
                      f"min < max, got {brief(raw)}", "sliders", "stroke", occurrence=n,
                      expected="two finite numbers, the lower first")
    lo, hi = float(raw[0]), float(raw[1])
    if not lo <= s0 <= hi:
        raise located(text, source, f"slider {lname!r} starts off its stroke: its point is at "
                      f"{s0:.6g} along the line in the pose, outside [{lo:g}, {hi:g}]",
                      "sliders", "stroke", occurrence=n, expected=f"a stroke containing {s0:.6g}")
    return (lo, hi), locate(text, "sliders", "stroke", occurrence=n)


def _read_units(doc: dict, text: str, source: str) -> str:
    """units: a short length unit name (free text, no spaces or brackets)."""
    units = doc.get("units", "")
    if not isinstance(units, str) or len(units) > 20 or any(ch.isspace() or ch in "[]"
                                                            for ch in units):
        raise located(text, source, f"units must be a short length unit such as \"mm\", got "
                   f"{brief(units)}", None, "units", expected='"mm", "m", "in", …')
    return units


def load_linkage(path: str | Path) -> Linkage:
    """Read a linkage TOML file: :func:`parse_linkage` of its text, its errors naming the file.

    Parameters
    ----------
    path : str or Path
        The linkage file: TOML in UTF-8, its lengths in its ``units``.

    Returns
    -------
    Linkage

    Raises
    ------
    NetlistError
        The file is missing or unreadable, or has an error (at file:line:col).
    GeometryError
        As :func:`parse_linkage`.
    """
    return parse_linkage(read_source(path, "a linkage .toml"), os.fspath(path))
