"""A scene linearised at a crank angle: its mechanical circuit (issue 7 §2).

Method (frozen-coefficient linearisation about the rigid motion, as the seed
does by hand in DIGEST §1 and :mod:`mechcirc.sley.linear` for the sley):

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
as in the seed's and the sley's linearisations.  Units: a link drive makes the
circuit rotational (ξ in rad/s, forces in N·m, K in rad/(N·m·s)); a point
drive translational (m/s, N, m/(N·s)).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..circuit import Circuit, Drive, Element, Lever
from ..errors import GeometryError, InputError
from .files import Scene

__all__ = ["SceneCircuit", "build", "build_needed", "ZERO_RATIO"]

#: A velocity ratio below this fraction of the scene's largest one counts as zero.
ZERO_RATIO = 1e-9
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_PERP = np.array([[0.0, -1.0], [1.0, 0.0]])


@dataclass(frozen=True, eq=False)
class SceneCircuit:
    """The mechanical circuit of a scene at one crank angle.

    Attributes
    ----------
    theta : float
        Crank rotation from the pose [rad].
    circuit : Circuit
        The circuit, parsed from ``netlist``.
    netlist : str
        Its ``.mcir`` text (every ratio written out in comments).
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

    theta: float
    circuit: Circuit
    netlist: str
    ratios: dict
    parts: dict
    dropped: tuple
    drive_ratio: float
    rotational: bool

    @property
    def drive_node(self) -> str:
        return next(iter(self.parts))


def build(scene: Scene, theta: float, *, reflect: Literal["eta", "lever"] = "eta",
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
    theta = float(theta)
    if not math.isfinite(theta):
        raise InputError(f"theta must be finite, got {theta!r}")
    lk = scene.linkage
    deg = math.degrees(theta)
    if state is None:
        try:
            state = lk.solve(theta)
        except GeometryError as exc:
            raise GeometryError(
                f"{scene.source}: at crank rotation θ = {deg:.6g}° the rigid mechanism "
                f"cannot be linearised: the linkage cannot be assembled there or passes a "
                f"position where its velocity ratios to the crank are infinite ({exc})") from None
    L = scene.length_scale
    omega = lk.cranks[0].omega
    crank = lk.cranks[0].link
    tbody_link = {t.body: t.link for t in scene.torsions}
    pos = {p: np.asarray(x, float) * L for p, x in state.points.items()}
    vel = {p: np.asarray(v, float) * L / omega for p, v in state.velocities.items()}
    ang = {l: w / omega for l, w in state.angular_velocities.items()}
    for body, link in tbody_link.items():
        ang[body] = ang[link]
    for t in scene.torsions:          # rods sharing a body: a redundant, consistent loop only
        if abs(ang[t.link] - ang[t.body]) > 1e-9 * max(abs(ang[t.body]), 1e-300) \
                and abs(ang[t.link] - ang[t.body]) > 1e-12:
            raise GeometryError(
                f"{scene.source}: at θ = {deg:.6g}° the links {t.link!r} and "
                f"{tbody_link[t.body]!r} of the rods on body {t.body!r} turn at different "
                f"rates ({ang[t.link]:.6g} and {ang[t.body]:.6g} per unit crank speed): the "
                f"rigid mechanism's redundant constraint is not consistent")
    Lc = lk.length_scale() * L
    S_all = max(max(np.hypot(*v) for v in vel.values()),
                max(abs(w) for w in ang.values()) * Lc)
    tiny = ZERO_RATIO * S_all

    d = scene.drive
    if d.link is not None:
        r0, r0_size = ang[d.link], abs(ang[d.link]) * Lc
        r0_text = f"ω_{d.link}/ω_{crank}"
    else:
        r0 = float(np.hypot(*vel[d.point]))
        r0_size, r0_text = r0, f"|v_{d.point}|/ω_{crank}"
    if r0_size <= tiny:
        raise GeometryError(
            f"{scene.source}: at θ = {deg:.6g}° the drive is at a dead centre: the velocity "
            f"ratio {r0_text} is {r0:.3g}, so the drive does not move the mechanism and every "
            f"ratio to it is infinite; choose another crank angle")

    # ---- the rigid parts: one node each, checked to move and to have one DOF
    node_of_part, parts = [], {}
    used = {"0"}
    for i, part in enumerate(scene.parts):
        name = part[0] if _IDENT.fullmatch(part[0]) else f"part{i}"
        while name in used:
            name = f"{name}_{i}"
        used.add(name)
        node_of_part.append(name)
        parts[name] = part
        _check_part(scene, part, pos, vel, ang, Lc, tiny, deg, crank)
    part_of_body = scene.part_of_body()

    def node_of_point(p):
        i = scene.part_of_point(p)
        return "0" if i is None else node_of_part[i]

    lines, ratios, dropped = [], {}, []
    elements, levers = [], []          # the circuit, built as objects beside its text
    names_used = set(used)
    element_names = {m.name for m in scene.masses} | {d.name} | {
        x.name + suffix for x in (*scene.elastic, *scene.torsions, *scene.loads)
        for suffix in ("", "_d")}

    def port(name, node, r):
        """Reflection through ``r``: (node, eta string) or a lever to a new node."""
        if reflect == "eta":
            return node, f" eta={r * r!r}"
        port_node = f"{name}_v"
        while port_node in names_used:
            port_node += "_"
        names_used.add(port_node)
        lever = f"L_{name}"
        while lever in element_names:
            lever = "L" + lever
        element_names.add(lever)
        lines.append(f"lever {lever} {node} 0 {port_node} 0 ratio={abs(r)!r}")
        levers.append(Lever(lever, node, "0", port_node, "0", abs(r)))
        return port_node, ""

    lines.append("# masses and inertias (kinetic energy, reflected to the drive)")
    for m in scene.masses:
        if m.kind == "mass":
            if m.point in lk.ground:
                dropped.append((m.name, f"at ground point {m.point!r}: it does not move"))
                continue
            r = float(np.hypot(*vel[m.point])) / abs(r0)
            size, node = r * abs(r0), node_of_point(m.point)
            what = f"|v_{m.point}|/v_drive"
        else:
            r = ang[m.link] / r0
            size, node = abs(ang[m.link]) * Lc, node_of_part[part_of_body[m.link]]
            what = f"ω_{m.link}/v_drive"
        ratios[m.name] = r
        if size <= tiny:
            dropped.append((m.name, f"at rest at this θ ({what} = {r:.3g})"))
            continue
        n, eta = port(m.name, node, r)
        lines.append(f"mass {m.name} {n} 0 {m.value!r}{eta}   ; {what} = {r!r}")
        elements.append(Element("mass", m.name, n, "0", m.value, r * r if eta else 1.0))

    lines.append("# elastic elements (elongation rate = ratio × velocity difference of the nodes)")
    springs = []           # (name, node_a, node_b, c, size)
    for e in scene.elastic:
        a, b = lk.links[e.link]
        u = pos[b] - pos[a]
        u = u / np.hypot(*u)
        ca, cb = float(u @ vel[a]), float(u @ vel[b])
        c = (cb if b not in lk.ground else ca) / r0
        springs.append((e, node_of_point(a), node_of_point(b), c, abs(c * r0),
                        f"elongation rate of {e.link} / v_drive"))
    for t in scene.torsions:
        c = ang[t.link] / r0
        springs.append((t, node_of_part[part_of_body[t.link]],
                        node_of_part[part_of_body[t.body]], c, abs(ang[t.link]) * Lc,
                        f"ω_{t.link}/v_drive (twist rate of the rod per unit drive velocity)"))
    for ld in scene.loads:
        if ld.anchor is not None:
            u = pos[ld.anchor] - pos[ld.point]
            if np.hypot(*u) == 0:
                raise GeometryError(f"{scene.source}: at θ = {deg:.6g}° load {ld.name!r}'s point "
                                    f"{ld.point!r} coincides with its anchor {ld.anchor!r}")
        else:
            u = np.array(ld.direction, float)
        u = u / np.hypot(*u)
        c = float(u @ vel[ld.point]) / r0
        springs.append((ld, node_of_point(ld.point), "0", c, abs(c * r0),
                        f"velocity of {ld.point} along the load / v_drive"))

    kept_edges = []
    for el, na, nb, c, size, what in springs:
        ratios[el.name] = c
        if size <= tiny:
            dropped.append((el.name, f"does not deform at this θ ({what} = {c:.3g})"))
            continue
        kept_edges.append((na, nb))
        ends = []
        for side, node in (("a", na), ("b", nb)):
            if node == "0":
                ends.append("0")
            elif reflect == "eta":
                ends.append(node)
            else:
                ends.append(port(f"{el.name}_{side}", node, c)[0])
        eta = f" eta={c * c!r}" if reflect == "eta" else ""
        eta_value = c * c if reflect == "eta" else 1.0
        if el.stiffness > 0:
            lines.append(f"spring {el.name} {ends[0]} {ends[1]} {el.stiffness!r}{eta}"
                         f"   ; {what} = {c!r}")
            elements.append(Element("spring", el.name, ends[0], ends[1], el.stiffness,
                                    eta_value))
        if el.damping > 0:
            dname = el.name + "_d" if el.stiffness > 0 else el.name
            lines.append(f"damper {dname} {ends[0]} {ends[1]} {el.damping!r}{eta}")
            elements.append(Element("damper", dname, ends[0], ends[1], el.damping, eta_value))
    _check_connected(scene, node_of_part, kept_edges, dropped, deg)

    unit = "rad/s" if d.link is not None else "m/s"
    head = [f"# scene {scene.name!r} ({scene.source}) linearised by mechcirc.scene.build",
            f"# at crank rotation theta = {deg!r} deg from the pose; drive on "
            + (f"link {d.link} (rotational: v in rad/s, Q in N·m)" if d.link is not None
               else f"point {d.point} along its path (translational: v in m/s, Q in N)"),
            f"# drive ratio r0 = {r0_text} = {r0!r}",
            "# nodes (rigid parts between elastic elements):"]
    head += [f"#   {n}: {', '.join(p)}" for n, p in parts.items()]
    for name, why in dropped:
        head.append(f"# left out: {name}: {why}")
    head.append(f"drive {d.name} {node_of_part[0]} 0 {d.kind}={d.amplitude!r}   ; [{unit}]"
                if d.kind == "velocity" else
                f"drive {d.name} {node_of_part[0]} 0 force={d.amplitude!r}")
    text = "\n".join(head + lines) + "\n"
    if not any(ln.split(None, 1)[0] in ("mass", "spring", "damper") for ln in lines
               if not ln.startswith("#")):
        raise GeometryError(f"{scene.source}: at θ = {deg:.6g}° no mass, spring or damper of "
                            f"the scene moves with the drive; the circuit would be empty")
    stem = scene.source.rsplit("/", 1)[-1].rsplit(".", 1)[0] if scene.source != "<string>" \
        else "scene"
    drive = Drive(d.name, node_of_part[0], "0", d.kind, float(d.amplitude))
    # built as objects (issue 15 §3); ``text`` is the same circuit as a netlist (tested)
    circuit = Circuit(tuple(elements), drive, tuple(levers), name=f"{stem}@{deg:.6g}deg",
                      source=scene.source)
    return SceneCircuit(theta, circuit, text, ratios, parts, tuple(dropped), float(r0),
                        d.link is not None)


def _check_part(scene, part, pos, vel, ang, Lc, tiny, deg, crank):
    """Refuse a part at rest (dead centre) or at a singular position of its own."""
    lk = scene.linkage
    bodies = scene.bodies
    tbodies = {t.body for t in scene.torsions}
    sizes = {f"ω_{b}/ω_{crank}": (abs(ang[b]) * Lc, ang[b]) for b in part}
    for b in part:
        if b in tbodies:
            continue
        for p in bodies[b]:
            sizes[f"|v_{p}|/ω_{crank}"] = (float(np.hypot(*vel[p])), float(np.hypot(*vel[p])))
    key = max(sizes, key=lambda k: sizes[k][0])
    if sizes[key][0] <= tiny:
        raise GeometryError(
            f"{scene.source}: at θ = {deg:.6g}° the rigid part {{{', '.join(part)}}} is at rest "
            f"in the rigid motion (a dead centre: its largest velocity ratio {key} is "
            f"{sizes[key][1]:.3g}), so it is decoupled from the drive and the linearised "
            f"circuit is singular; choose another crank angle")
    # Numerical degrees of freedom of the part at θ: null space of its joint constraints.
    cols = {b: 3 * i for i, b in enumerate(part)}
    origin = {b: pos[bodies[b][0]] for b in part}
    rows = []
    for p in {p for b in part for p in bodies[b]}:
        on = [b for b in part if p in bodies[b]]
        members = (["ground"] if p in lk.ground else []) + on
        for other in members[1:]:
            for axis in range(2):
                row = np.zeros(3 * len(part))
                for body, sign in ((members[0], 1.0), (other, -1.0)):
                    if body == "ground":
                        continue
                    j = cols[body]
                    row[j + axis] += sign
                    arm = (pos[p] - origin[body]) / Lc
                    row[j + 2] += sign * (_PERP @ arm)[axis]
                rows.append(row)
    if rows:
        s = np.linalg.svd(np.array(rows), compute_uv=False)
        rank = int(np.sum(s > 1e-9 * s.max()))
    else:
        rank = 0
    nullity = 3 * len(part) - rank
    if nullity != 1:
        raise GeometryError(
            f"{scene.source}: at θ = {deg:.6g}° the rigid part {{{', '.join(part)}}} is at a "
            f"singular position of its own ({nullity} independent velocity fields instead of "
            f"1), so its velocity ratios are not unique; choose another crank angle")


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
                 reflect: Literal["eta", "lever"] = "eta"):
    """The model the scene asks for: built at θ and, with a band, reduced to what it needs.

    Parameters
    ----------
    scene : Scene
    theta : float, optional
        Crank rotation from the pose [rad]; default the file's
        ``[analysis] theta_deg``.
    reflect : {"eta", "lever"}

    Returns
    -------
    (SceneCircuit, Simplified or None)
        The full model at θ, and its reduction for ``[analysis] output`` over
        ``band`` to ``tol`` (:func:`mechcirc.simplify.simplify`), or None
        when the file gives no band.

    Raises
    ------
    MechcircError
        No θ given here or in the file; the output element is left out at θ.
    GeometryError
        As :func:`build`.
    """
    from ..errors import MechcircError
    from ..simplify import simplify

    a = scene.analysis
    if theta is None:
        if a.theta_deg is None:
            raise MechcircError(f"{scene.source}: no crank angle: give one, or theta_deg in "
                                "[analysis]")
        theta = math.radians(a.theta_deg)
    model = build(scene, theta, reflect=reflect)
    if a.band is None:
        return model, None
    if a.output is not None and a.output not in {e.name for e in model.circuit.elements}:
        why = dict(model.dropped).get(a.output.removesuffix("_d"), "not in the circuit")
        raise MechcircError(f"{scene.source}: the output element {a.output!r} is left out at "
                            f"θ = {math.degrees(theta):.6g}° ({why})")
    return model, simplify(model.circuit, a.band, a.tol, output=a.output)
