"""A scene linearised at a crank angle: its mechanical circuit.

Method (frozen-coefficient linearisation about the rigid motion, as Grigoriev et al. (2002)
do by hand and :mod:`mechcirc.sley.linear` for the sley):

1. Solve the rigid linkage (every elastic element rigid) at crank rotation θ
   (:meth:`Linkage.solve`); divide every velocity by the crank speed Ω and by
   the drive's own ratio r₀ (ω_link/Ω for a link drive, |v_P|/Ω for a point
   drive).  This gives each point's and body's *velocity ratio to the drive*.
2. Release the elastic elements: the moving bodies fall into rigid parts, each
   with one degree of freedom (checked when the scene is read, and here
   numerically: the part's constraint Jacobian must have a one-dimensional
   null space at θ).  Each part is one circuit node whose velocity ξ is its
   motion expressed in drive units: in the rigid motion every ξ equals the
   drive velocity.  Because an elastic element does not deform in the rigid
   motion, its elongation rate is c·(ξ_b − ξ_a) with *one* coefficient c (the
   ratio of its elongation rate to the drive velocity with one side held);
   an element to the frame has c·ξ.
3. Kinetic energy ½ Σ m_i |v_i|² + ½ Σ J_j ω_j² gives each mass or inertia a
   mass element from its part's node to the frame, reflected through its
   ratio r: ``eta = r²`` (``reflect="eta"``), or an ideal ``lever`` of ratio
   |r| in front of it (``reflect="lever"``).  Springs and dampers get
   ``eta = c²`` or a lever of ratio |c| at each end.

Dropped: the velocity-squared (ν) terms and pre-load (geometric) stiffness,
as in the paper's and the sley's linearisations.  Units: a link drive makes the
circuit rotational (ξ in rad/s, forces in N·m, K in rad/(N·m·s)); a point
drive translational (m/s, N, m/(N·s)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..circuit import Circuit, Drive, Element, Lever
from ..errors import GeometryError, InputError, MechcircError, OutOfReach
from ..sources import is_name, real_number, summary_repr
from .files import Scene, gear_meshes

#: How a lever is reflected into the circuit (see :func:`build`).
ReflectMode = Literal["eta", "lever"]

__all__ = ["SceneCircuit", "build", "build_needed", "ZERO_RATIO"]

#: A velocity ratio below this fraction of the scene's largest one counts as zero.
ZERO_RATIO = 1e-9


@dataclass(frozen=True, eq=False)
class SceneCircuit:
    """The mechanical circuit of a scene at one crank angle.

    Attributes
    ----------
    theta : float
        Crank rotation from the pose [rad].
    circuit : Circuit
        The circuit, built from Element/Lever/Drive objects.
    netlist : str
        Its ``.mcir`` text (:func:`mechcirc.netlist_writer.write`; every ratio
        written out in comments), which parses back to ``circuit``.
    ratios : dict[str, float]
        Element name → velocity ratio to the drive [1, m/rad or 1/m]: the speed
        of a mass's point, a link's ω, or a spring's elongation rate, per unit
        drive velocity; signed where a sign exists.
    parts : dict[str, tuple of str]
        Node → the bodies of its rigid part; the drive's node first.
    dropped : tuple of (str, str)
        Elements left out at this θ and why (a mass at rest, a spring that does
        not deform).
    drive_ratio : float
        Drive velocity per unit crank speed r₀ [1 for a link, m/rad for a point].
    rotational : bool
        True for a link drive (rad/s, N·m), False for a point drive (m/s, N).
    """

    __repr__ = summary_repr

    theta: float
    circuit: Circuit
    netlist: str
    ratios: dict
    parts: dict
    dropped: tuple
    drive_ratio: float
    rotational: bool


def build(scene: Scene, theta: float, *, reflect: ReflectMode = "eta",
          state=None) -> SceneCircuit:
    """The mechanical circuit of ``scene`` linearised at crank rotation ``theta`` [rad].

    Parameters
    ----------
    scene : Scene
        From :func:`~mechcirc.scene.load_scene` or :func:`~mechcirc.scene.parse_scene`.
    theta : float
        Rotation of the crank from the pose [rad].
    reflect : {"eta", "lever"}
        Reflect masses and springs through ``eta = ratio²`` (one node per rigid
        part; series–parallel for a chain) or through explicit ideal levers
        of ratio |ratio| (one extra node per element end; nodal analysis).
    state : LinkageState, optional
        The rigid linkage already solved at ``theta`` (saves a solve in loops).

    Returns
    -------
    SceneCircuit

    Raises
    ------
    GeometryError
        The linkage cannot be assembled at θ or its crank is at a position
        where the velocity ratios are infinite; the drive or a rigid part is
        at rest (a dead centre: its ratio to the crank is 0, named in the
        message); a rigid part is at a singular position of its own.
    """
    if reflect not in ("eta", "lever"):
        raise ValueError(f"reflect must be 'eta' or 'lever', got {reflect!r}")
    if not (real_number(theta) and math.isfinite(theta)):
        raise InputError(f"theta must be a finite angle [rad], got {theta!r}")
    theta = float(theta)
    m = _motion(scene, theta, state)
    r0, r0_text = _drive_ratio(scene, m)
    node_of_part, parts = _part_nodes(scene, m)
    b = _Builder(scene, m, r0, node_of_part, reflect)
    b.masses()
    kept_edges = b.springs()
    _check_connected(scene, node_of_part, kept_edges, b.dropped, m.deg)
    d = scene.drive
    drive = Drive(d.name, node_of_part[0], "0", d.kind, float(d.amplitude),
                  rotational=d.link is not None)
    if not b.elements:
        raise GeometryError(f"{scene.source}: at θ = {m.deg:.6g}° no mass, spring or damper of "
                            f"the scene moves with the drive; the circuit would be empty")
    stem = scene.source.rsplit("/", 1)[-1].rsplit(".", 1)[0] if scene.source != "<string>" \
        else "scene"
    circuit = Circuit(tuple(b.elements), drive, tuple(b.levers), name=f"{stem}@{m.deg:.6g}deg",
                      source=scene.source)
    text = _netlist(scene, circuit, m.deg, r0, r0_text, parts, b)
    return SceneCircuit(theta, circuit, text, b.ratios, parts, tuple(b.dropped), float(r0),
                        d.link is not None)


@dataclass(frozen=True)
class _Motion:
    """The rigid motion in SI, per unit crank speed, and the scale of "at rest": at one
    angle (vectors (2,), rates scalars) or n at once ((n, 2), (n,)), for build and the
    cycle map alike (the formulas below broadcast)."""

    deg: object      # crank rotation [deg]
    pos: dict        # point -> position [m]
    vel: dict        # point -> velocity per unit crank speed [m/rad]
    ang: dict        # link or torsion body -> angular velocity per unit crank speed [1]
    Lc: float        # the linkage's length scale [m]
    tiny: np.floating | np.ndarray  # a velocity ratio at most this is zero (ZERO_RATIO × the largest)
    crank: str


def scaled_motion(scene: Scene, deg, points: dict, velocities: dict, angular: dict) -> _Motion:
    """The rigid motion of ``scene`` scaled to SI and per unit crank speed.

    ``points``, ``velocities`` (point → vector [length], [length/s]) and
    ``angular`` (link → ω [rad/s]) at one crank angle ``deg`` or at an array
    of them (vectors (n, 2), rates (n,)).  A torsion rod's body turns with
    its link.
    """
    lk = scene.linkage
    L, omega = scene.length_scale, lk.cranks[0].omega
    pos = {p: np.asarray(x, float) * L for p, x in points.items()}
    vel = {p: np.asarray(v, float) * L / omega for p, v in velocities.items()}
    ang = {l: w / omega for l, w in angular.items()}
    for t in scene.torsions:
        ang[t.body] = ang[t.link]
    Lc = lk.length_scale() * L
    S_all = np.maximum(np.max([_norm(v) for v in vel.values()], axis=0),
                       np.max([np.abs(w) for w in ang.values()], axis=0) * Lc)
    crank = "cam" if getattr(lk, "cam", None) is not None else lk.cranks[0].link
    return _Motion(deg, pos, vel, ang, Lc, ZERO_RATIO * S_all, crank)


def _norm(v):
    """|v| over the last axis (of length 2)."""
    return np.hypot(v[..., 0], v[..., 1])


def _unit(v):
    return v / _norm(v)[..., None]


def _dot(u, v):
    """u·v over the last axis, as ``u @ v`` rounds it (one angle or many alike)."""
    return (u[..., None, :] @ v[..., :, None])[..., 0, 0]


def _perp(v):
    """v turned by +90°."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def _motion(scene: Scene, theta: float, state) -> _Motion:
    """Solve the rigid linkage at θ (unless ``state`` is given) and scale it."""
    lk, deg = scene.linkage, math.degrees(theta)
    if state is None:
        try:
            state = lk.solve(theta)
        except OutOfReach:
            raise                   # the step limit, not the linkage: its own message
        except GeometryError as exc:
            raise GeometryError(
                f"{scene.source}: at crank rotation θ = {deg:.6g}° the rigid mechanism "
                f"cannot be linearised: the linkage cannot be assembled there or passes a "
                f"position where its velocity ratios to the crank are infinite ({exc})") from None
    m = scaled_motion(scene, deg, state.points, state.velocities, state.angular_velocities)
    ang = m.ang
    for t in scene.torsions:          # rods sharing a body: a redundant, consistent loop only
        if abs(ang[t.link] - ang[t.body]) > 1e-9 * max(abs(ang[t.body]), 1e-300) \
                and abs(ang[t.link] - ang[t.body]) > 1e-12:
            link = [u.link for u in scene.torsions if u.body == t.body][-1]
            raise GeometryError(
                f"{scene.source}: at θ = {deg:.6g}° the links {t.link!r} and "
                f"{link!r} of the rods on body {t.body!r} turn at different "
                f"rates ({ang[t.link]:.6g} and {ang[t.body]:.6g} per unit crank speed): the "
                f"rigid mechanism's redundant constraint is not consistent")
    return m


def drive_ratio(scene: Scene, m: _Motion):
    """(r₀, its size as a speed, its name): the drive's velocity per unit crank speed."""
    d = scene.drive
    if d.link is not None:
        return m.ang[d.link], np.abs(m.ang[d.link]) * m.Lc, f"ω_{d.link}/ω_{m.crank}"
    r0 = _norm(m.vel[d.point])
    return r0, r0, f"|v_{d.point}|/ω_{m.crank}"


def element_ratios(scene: Scene, m: _Motion, r0) -> dict:
    """Element name → (velocity ratio to the drive, its size as a speed [m/rad]).

    A mass's point speed or a link's ω; an elastic link's elongation rate
    along it (its moving end); a torsion rod's twist rate; a load's point
    along its line; each per unit drive velocity ``r0``.  Masses at ground
    points are not listed.  NaN for a load whose point meets its anchor.
    """
    lk, out = scene.linkage, {}
    with np.errstate(invalid="ignore", divide="ignore"):
        for ms in scene.masses:
            if ms.kind != "mass":
                out[ms.name] = (m.ang[ms.link] / r0, np.abs(m.ang[ms.link]) * m.Lc)
            elif ms.point not in lk.ground:
                size = _norm(m.vel[ms.point])
                out[ms.name] = (size / np.abs(r0), size)
        for e in scene.elastic:
            a, b = lk.links[e.link]
            c = _dot(_unit(m.pos[b] - m.pos[a]), m.vel[a if b in lk.ground else b]) / r0
            out[e.name] = (c, np.abs(c * r0))
        for t in scene.torsions:
            out[t.name] = (m.ang[t.link] / r0, np.abs(m.ang[t.link]) * m.Lc)
        for ld in scene.loads:
            u = m.pos[ld.anchor] - m.pos[ld.point] if ld.anchor is not None \
                else np.array(ld.direction, float)
            c = _dot(_unit(u), m.vel[ld.point]) / r0
            out[ld.name] = (c, np.abs(c * r0))
    return out


def _drive_ratio(scene: Scene, m: _Motion) -> tuple[float, str]:
    """r₀, the drive's velocity per unit crank speed, and its name; refused at rest."""
    r0, r0_size, r0_text = drive_ratio(scene, m)
    r0 = float(r0)
    from .cam import CamLinkage

    if r0_size <= m.tiny and isinstance(scene.linkage, CamLinkage):
        raise GeometryError(f"{scene.source}: at θ = {m.deg:.6g}° the cam dwells: the follower "
                            f"{scene.linkage.follower!r} is at rest (x'(θ) = 0), so the "
                            f"drive on it does not move the mechanism; choose a cam angle in a "
                            f"rise or a return")
    if r0_size <= m.tiny:
        raise GeometryError(
            f"{scene.source}: at θ = {m.deg:.6g}° the drive is at a dead centre: the velocity "
            f"ratio {r0_text} is {r0:.3g}, so the drive does not move the mechanism and every "
            f"ratio to it is infinite; choose another crank angle")
    return r0, r0_text


def _part_nodes(scene: Scene, m: _Motion) -> tuple[list[str], dict]:
    """One node a rigid part (named after its first body), each checked to move with one DOF."""
    node_of_part, parts = [], {}
    used = {"0"}
    for i, part in enumerate(scene.parts):
        name = part[0] if is_name(part[0]) else f"part{i}"
        while name in used:
            name = f"{name}_{i}"
        used.add(name)
        node_of_part.append(name)
        parts[name] = part
        _check_part(scene, part, m)
    return node_of_part, parts


class _Builder:
    """The circuit's elements and levers, built as objects, with each one's ratio."""

    def __init__(self, scene: Scene, m: _Motion, r0: float, node_of_part: list,
                 reflect: ReflectMode):
        self.scene, self.m, self.r0, self.node_of_part = scene, m, r0, node_of_part
        self.reflect = reflect
        self.part_of_body = scene.part_of_body()
        self.elements: list[Element] = []
        self.levers: list[Lever] = []
        self.ratios: dict[str, float] = {}
        self.dropped: list[tuple[str, str]] = []
        self.notes: dict[str, str] = {}      # element -> "what = ratio", for the text
        self.found = element_ratios(scene, m, r0)     # name -> (ratio, size)
        self.names_used = {"0", *node_of_part}
        self.element_names = {x.name for x in scene.masses} | {scene.drive.name} | {
            x.name + suffix for x in (*scene.elastic, *scene.torsions, *scene.loads)
            for suffix in ("", "_d")}

    def node_of_point(self, p) -> str:
        i = self.scene.part_of_point(p)
        return "0" if i is None else self.node_of_part[i]

    def port(self, name, node, r) -> tuple[str, float]:
        """Reflection through ``r``: (node, η = r²), or a lever of ratio |r| to a new node."""
        if self.reflect == "eta":
            return node, r * r
        port_node = f"{name}_v"
        while port_node in self.names_used:
            port_node += "_"
        self.names_used.add(port_node)
        lever = f"L_{name}"
        while lever in self.element_names:
            lever = "L" + lever
        self.element_names.add(lever)
        self.levers.append(Lever(lever, node, "0", port_node, "0", abs(r)))
        return port_node, 1.0

    def masses(self) -> None:
        """A mass element a moving mass or inertia (kinetic energy, reflected to the drive)."""
        m, ground = self.m, self.scene.linkage.ground
        for ms in self.scene.masses:
            if ms.kind == "mass":
                if ms.point in ground:
                    self.dropped.append((ms.name, f"at ground point {ms.point!r}: it does "
                                                  "not move"))
                    continue
                node, what = self.node_of_point(ms.point), f"|v_{ms.point}|/v_drive"
            else:
                node = self.node_of_part[self.part_of_body[ms.link]]
                what = f"ω_{ms.link}/v_drive"
            r, size = (float(x) for x in self.found[ms.name])
            self.ratios[ms.name] = r
            if size <= m.tiny:
                self.dropped.append((ms.name, f"at rest at this θ ({what} = {r:.3g})"))
                continue
            n, eta = self.port(ms.name, node, r)
            self.elements.append(Element("mass", ms.name, n, "0", ms.value, eta))
            self.notes[ms.name] = f"{what} = {r!r}"

    def _elastic(self) -> list:
        """(element, node a, node b, ratio c, size, what) of every spring, rod and load."""
        scene, m = self.scene, self.m
        lk, out = scene.linkage, []
        for e in scene.elastic:
            a, b = lk.links[e.link]
            out.append((e, self.node_of_point(a), self.node_of_point(b),
                        f"elongation rate of {e.link} / v_drive"))
        for t in scene.torsions:
            out.append((t, self.node_of_part[self.part_of_body[t.link]],
                        self.node_of_part[self.part_of_body[t.body]],
                        f"ω_{t.link}/v_drive (twist rate of the rod per unit drive velocity)"))
        for ld in scene.loads:
            if ld.anchor is not None and not np.any(m.pos[ld.anchor] != m.pos[ld.point]):
                raise GeometryError(
                    f"{scene.source}: at θ = {m.deg:.6g}° load {ld.name!r}'s point "
                    f"{ld.point!r} coincides with its anchor {ld.anchor!r}")
            out.append((ld, self.node_of_point(ld.point), "0",
                        f"velocity of {ld.point} along the load / v_drive"))
        return [(el, na, nb, *(float(x) for x in self.found[el.name]), what)
                for el, na, nb, what in out]

    def springs(self) -> list[tuple[str, str]]:
        """Springs and dampers of the elastic elements that deform; their node pairs."""
        kept_edges = []
        for el, na, nb, c, size, what in self._elastic():
            self.ratios[el.name] = c
            if size <= self.m.tiny:
                self.dropped.append((el.name, f"does not deform at this θ ({what} = {c:.3g})"))
                continue
            kept_edges.append((na, nb))
            ends = [node if node == "0" or self.reflect == "eta" else
                    self.port(f"{el.name}_{side}", node, c)[0]
                    for side, node in (("a", na), ("b", nb))]
            eta = c * c if self.reflect == "eta" else 1.0
            if el.stiffness > 0:
                self.elements.append(Element("spring", el.name, ends[0], ends[1], el.stiffness,
                                             eta))
                self.notes[el.name] = f"{what} = {c!r}"
            if el.damping > 0:
                dname = el.name + "_d" if el.stiffness > 0 else el.name
                self.elements.append(Element("damper", dname, ends[0], ends[1], el.damping, eta))
                if el.stiffness == 0:
                    self.notes[dname] = f"{what} = {c!r}"
        return kept_edges


def _netlist(scene, circuit, deg, r0, r0_text, parts, b: _Builder) -> str:
    """The circuit's text (the one netlist writer), every ratio and choice in a comment."""
    from ..netlist_writer import write

    d = scene.drive
    head = [f"scene {scene.name!r} ({scene.source}) linearised by mechcirc.scene.build",
            f"at crank rotation theta = {deg!r} deg from the pose; drive on "
            + (f"link {d.link} (rotational: v in rad/s, Q in N·m)" if d.link is not None
               else f"point {d.point} along its path (translational: v in m/s, Q in N)"),
            f"drive ratio r0 = {r0_text} = {r0!r}",
            "nodes (rigid parts between elastic elements):"]
    head += [f"  {n}: {', '.join(p)}" for n, p in parts.items()]
    head += [f"left out: {name}: {why}" for name, why in b.dropped]
    notes = dict(b.notes)
    if d.kind == "velocity":
        notes[d.name] = "[rad/s]" if d.link is not None else "[m/s]"
    return write(circuit, head, comments=notes)


def _check_part(scene, part, m: _Motion):
    """Refuse a part at rest (dead centre) or at a singular position of its own."""
    sizes = part_speeds(scene, part, m)
    key = max(sizes, key=lambda k: sizes[k][0])
    if sizes[key][0] <= m.tiny:
        raise GeometryError(
            f"{scene.source}: at θ = {m.deg:.6g}° the rigid part {{{', '.join(part)}}} is at "
            f"rest in the rigid motion (a dead centre: its largest velocity ratio {key} is "
            f"{float(sizes[key][1]):.3g}), so it is decoupled from the drive and the "
            f"linearised circuit is singular; choose another crank angle")
    s = part_singular_values(scene, part, m)
    nullity = 3 * len(part) - int(np.sum(s > RANK_TOL * s.max(initial=0.0)))
    if nullity != 1:
        raise GeometryError(
            f"{scene.source}: at θ = {m.deg:.6g}° the rigid part {{{', '.join(part)}}} is at a "
            f"singular position of its own ({nullity} independent velocity fields instead of "
            f"1), so its velocity ratios are not unique; choose another crank angle")


def part_speeds(scene: Scene, part, m: _Motion) -> dict:
    """A rigid part's velocity ratios to the crank: name → (size as a speed, value)."""
    bodies, tbodies = scene.bodies, {t.body for t in scene.torsions}
    sizes = {f"ω_{b}/ω_{m.crank}": (np.abs(m.ang[b]) * m.Lc, m.ang[b]) for b in part}
    sizes.update((f"|v_{p}|/ω_{m.crank}", (_norm(m.vel[p]),) * 2)
                 for b in part if b not in tbodies for p in bodies[b])
    return sizes


#: A part's joint constraints lose rank where a singular value is below this
#: fraction of the largest.
RANK_TOL = 1e-9


def part_singular_values(scene: Scene, part, m: _Motion):
    """Singular values of a rigid part's joint constraints (pins, sliders, rigid gear
    meshes) on its bodies' velocities (x', y', φ'·Lc each), shape (..., k): rank
    3·len(part) − 1 means one velocity field (one degree of freedom)."""
    lk, bodies, Lc = scene.linkage, scene.bodies, m.Lc
    cols = {b: 3 * i for i, b in enumerate(part)}
    shape = np.shape(next(iter(m.pos.values())))[:-1] + (3 * len(part),)
    origin = {b: m.pos[bodies[b][0]] for b in part}
    rows = []

    def row(*entries):        # (moving body, sign, x-y coefficients or None, φ coefficient)
        r = np.zeros(shape)
        for body, sign, xy, turn in entries:
            j = cols[body]
            if xy is not None:
                r[..., j:j + 2] += sign * xy
            r[..., j + 2] += sign * turn
        rows.append(r)

    for p in sorted({p for b in part for p in bodies[b]}):
        members = (["ground"] if p in lk.ground else []) + [b for b in part if p in bodies[b]]
        for other in members[1:]:
            arms = {b: _perp((m.pos[p] - origin[b]) / Lc) for b in (members[0], other)
                    if b != "ground"}
            for axis in range(2):
                e = np.eye(2)[axis]
                row(*((b, sign, e, arms[b][..., axis]) for b, sign in
                      ((members[0], 1.0), (other, -1.0)) if b != "ground"))
    for x in lk.sliders:               # a slider: no relative turning, no motion across the guide
        if x.link not in part or not (x.guide in cols or x.guide == "ground"):
            continue
        u = m.pos[x.line[1]] - m.pos[x.line[0]] if x.guide != "ground" \
            else np.array(x.direction, float)
        n = _perp(_unit(u))
        pair = [(b, sign) for b, sign in ((x.link, 1.0), (x.guide, -1.0)) if b != "ground"]
        row(*((b, sign, None, 1.0) for b, sign in pair))
        row(*((b, sign, n, _dot(n, _perp((m.pos[x.point] - origin[b]) / Lc)))
              for b, sign in pair))
    for a, b, ratio in gear_meshes(scene):       # a rigid mesh: ω_a − ratio · ω_b = 0
        if a in cols:
            row((a, 1.0, None, 1.0), (b, -ratio, None, 1.0))
    if not rows:
        return np.zeros(shape[:-1] + (0,))
    return np.linalg.svd(np.stack(rows, axis=-2), compute_uv=False)


def _check_connected(scene, node_of_part, edges, dropped, deg):
    """Refuse parts that no kept element couples to the drive's part (not through the frame)."""
    import networkx as nx

    g = nx.Graph()
    g.add_nodes_from(node_of_part)
    g.add_edges_from((a, b) for a, b in edges if "0" not in (a, b))
    reach = nx.node_connected_component(g, node_of_part[0])
    lost = [n for n in node_of_part if n not in reach]
    if lost:
        why = "; ".join(f"{n}: {w}" for n, w in dropped if "deform" in w)
        raise GeometryError(
            f"{scene.source}: at θ = {deg:.6g}° the parts {', '.join(lost)} are not coupled "
            f"to the drive: the elastic elements that would couple them do not deform in the "
            f"rigid motion ({why or 'no element joins them'}); a dead centre")


def build_needed(scene: Scene, theta: float | None = None, *,
                 reflect: ReflectMode = "eta"):
    """The model the scene asks for: built at θ and, with a band, reduced to what it needs.

    Parameters
    ----------
    scene : Scene
        The scene to model.
    theta : float, optional
        Crank rotation from the pose [rad]; default the file's
        ``[analysis] theta_deg``.
    reflect : {"eta", "lever"}
        As in :func:`build`.

    Returns
    -------
    (SceneCircuit, Simplified or None)
        The full model at θ, and its reduction for ``[analysis] output`` over
        ``band`` to ``tol`` (:func:`mechcirc.simplify`), or None
        when the file gives no band.

    Raises
    ------
    MechcircError
        No θ given here or in the file; the output element is left out at θ.
    GeometryError
        As :func:`build`.
    """
    from .._simplify import simplify

    a = scene.analysis
    if theta is None:
        if a.theta_deg is None:
            raise MechcircError(f"{scene.source}: no crank angle: give one, or theta_deg in "
                                "[analysis]")
        theta = math.radians(a.theta_deg)
    model = build(scene, theta, reflect=reflect)
    if a.band is None or a.tol is None:      # the file gives both or neither
        return model, None
    if a.output is not None and a.output not in {e.name for e in model.circuit.elements}:
        why = dict(model.dropped).get(a.output.removesuffix("_d"), "not in the circuit")
        raise MechcircError(f"{scene.source}: the output element {a.output!r} is left out at "
                            f"θ = {math.degrees(theta):.6g}° ({why})")
    return model, simplify(model.circuit, a.band, a.tol, output=a.output)
