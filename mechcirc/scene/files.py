"""Scene files: a linkage (docs/kinematics.md) with lumped masses, elastic elements and a drive.

A scene file is a linkage TOML file with ``units`` (required) and five more
tables::

    units = "mm"                 # length unit of [points]: "m", "cm" or "mm"

    [[masses]]                   # a lumped mass at a point [kg] ...
    name = "m2"
    point = "A"
    mass = 1.5
    [[masses]]                   # ... or a link's rotary inertia [kg·m²]
    name = "J1"
    link = "lever1"
    inertia = 0.02

    [[elastic]]                  # a binary link of [links] made elastic (axial spring)
    name = "k4"                  # default: the link's name
    link = "rodCD"
    stiffness = 2.0e6            # [N/m]
    damping = 40.0               # optional [N·s/m]

    [[torsion]]                  # a torsion rod at a ground pivot between a link
    name = "C2"                  # and a new body that turns with it in the cycle
    link = "crank"
    body = "shaft"
    pivot = "A"                  # optional when the link has one ground pivot
    stiffness = 1.0e5            # [N·m/rad]
    damping = 7.0                # optional [N·m·s/rad]

    [[loads]]                    # a spring and/or damper from a point to the frame
    name = "warp"
    point = "M"
    anchor = "W"                 # a ground point, or direction = [dx, dy]
    stiffness = 4.0e4            # [N/m]
    damping = 0.0                # optional [N·s/m]

    [drive]
    link = "shaft"               # a link or torsion body (rotational: rad/s, N·m) ...
    # point = "T"                # ... or a point (its speed along its path: m/s, N)
    velocity = 0.1               # kinematic excitation amplitude, or force = F0

    [analysis]                   # optional: what the scene asks for
    theta_deg = 40.0             # the moment of the cycle [deg from the pose]
    output = "kEF"               # force in this circuit element (default K at the drive)
    band = [30.0, 480.0]         # [rad/s], with tol: model only what the band needs
    tol = 0.01

The linkage part is read by :func:`mechcirc.kinematics.linkage.parse_linkage`
(the scene tables are hidden from it, line numbers kept), so its errors and
checks are the linkage's.  Masses, stiffnesses and dampings are SI; lengths
are converted from ``units`` to metres.  One crank, or several on one shaft (the
same ``omega``), or cranks geared to the first (``[[gears]]``: crank, ratio =
ω_crank/ω_first, optional mesh stiffness and damping: a torsion rod between the
crank and its gear's body); the time-domain tables ``[[moments]]``,
``[simulate]`` and ``[shaft]`` are read by :mod:`.simfile`; ``[cam]`` (a disc cam
moving an oscillating follower, the only crank, or a translating one, a block on a
fixed guide, by a motion law) by :mod:`.cam`.

Structure.  Releasing the elastic links and torsion rods splits the moving
bodies into *rigid parts* (bodies joined through joints other than ground
pivots).  Each part must have one degree of freedom (Grübler 3n − 2p = 1
counting its ground pivots); an elastic link pinned to the frame, whose
release leaves a two-degree-of-freedom part, is refused.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Literal, TypeGuard

from ..errors import GeometryError, MechcircError, NetlistError, did_you_mean
from ..kinematics.linkage import TABLES as LINKAGE_TABLES
from ..kinematics.linkage import Linkage, parse_linkage
from ..sources import (Table, brief, check_keys, checked_number, finite_number, load_toml,
                       split_lines)
from ..sources import TOML_HEADER, is_name, located, read_source, summary_repr
from ..units import in_si, is_bare_number, parse_quantity
from .simfile import (Moment, SimulateSettings, override_moment, override_run, parse_moments,
                      parse_shaft, parse_simulate)

__all__ = ["Scene", "Analysis", "Gear", "SceneMass", "ElasticLink", "Torsion", "Load", "SceneDrive",
           "parse_scene", "load_scene", "apply_overrides", "LENGTH_UNITS", "SCENE_TABLES"]

#: Length units accepted for ``units`` and their size [m].
LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
#: Tables a scene adds to the linkage format.
SCENE_TABLES = ("masses", "elastic", "torsion", "loads", "drive", "analysis", "moments",
                "simulate", "gears", "shaft", "cam")
_CLEARANCE = {"clearance": "half-width of the gap [m or rad], 0 for none",
              "clearance_law": "\"elastobacklash\" or \"dead-zone\""}
#: The tables of a scene file, declared once (see :class:`mechcirc.sources.Table`);
#: [moments] and [simulate] keep their own key lists in :mod:`mechcirc.scene.simfile`.
TABLES = {
    None: Table(None, dict(sorted({**LINKAGE_TABLES[None].keys,
                                   **{t: f"[{t}] (a scene table)" for t in SCENE_TABLES}
                                   }.items()))),
    "elastic": Table("elastic", {"name": "element name (default: the link)",
                                 "link": "a binary link of [links]",
                                 "stiffness": "[N/m]", "damping": "[N·s/m], default 0",
                                 **_CLEARANCE}, array=True),
    "torsion": Table("torsion", {"name": "element name (default C_BODY)",
                                 "link": "a rigid link", "body": "the new body beyond the rod",
                                 "pivot": "a ground pivot of the link",
                                 "stiffness": "[N·m/rad]", "damping": "[N·m·s/rad], default 0",
                                 **_CLEARANCE}, array=True),
    "masses": Table("masses", {"name": "element name (default m_POINT or J_LINK)",
                               "point": "a point of a rigid link", "link": "a rigid link or body",
                               "mass": "[kg], with point", "inertia": "[kg·m²], with link"},
                    array=True),
    "loads": Table("loads", {"name": "element name (default load_POINT)",
                             "point": "the loaded point", "anchor": "a ground point",
                             "direction": "[dx, dy]", "stiffness": "[N/m]",
                             "damping": "[N·s/m]"}, array=True),
    "drive": Table("drive", {"name": "element name (default V)", "link": "a rigid link or body",
                             "point": "a point of a rigid link", "velocity": "amplitude V0",
                             "force": "amplitude F0"}),
    "gears": Table("gears", {"crank": "a crank of [[cranks]] other than the first",
                             "ratio": "ω_crank/ω_first_crank, a ratio of whole numbers, not 0",
                             "body": "the gear's body (default gear_CRANK), with stiffness",
                             "stiffness": "mesh stiffness at the crank [N·m/rad], optional",
                             "damping": "[N·m·s/rad], default 0"}, array=True),
    "analysis": Table("analysis", {"theta_deg": "crank angle [deg]",
                                   "output": "an element of the circuit",
                                   "band": "[W1, W2] [rad/s]", "tol": "relative tolerance"}),
}
#: Clearance laws of an elastic link or torsion rod (docs/scenes.md, "In the time domain").
CLEARANCE_LAWS = ("elastobacklash", "dead-zone")


@dataclass(frozen=True)
class SceneMass:
    """A lumped mass at ``point`` [kg] (``kind="mass"``) or a link's inertia [kg·m²]."""

    name: str
    kind: str
    value: float
    point: str | None = None
    link: str | None = None


@dataclass(frozen=True)
class _Spring:
    """An elastic element of a scene: ``stiffness`` ∥ ``damping`` on ``link``.

    ``clearance`` is the half-width of a gap in it and ``clearance_law`` how
    the gap acts (one of CLEARANCE_LAWS); the time domain only.
    """

    name: str
    link: str
    stiffness: float
    damping: float = 0.0
    clearance: float = 0.0
    clearance_law: str = "elastobacklash"


@dataclass(frozen=True)
class ElasticLink(_Spring):
    """A binary link that is an axial spring ``stiffness`` [N/m] ∥ ``damping`` [N·s/m]."""


@dataclass(frozen=True)
class Torsion(_Spring):
    """A torsion rod at ground pivot ``pivot`` between ``link`` and the new ``body``.

    ``stiffness`` [N·m/rad], ``damping`` [N·m·s/rad].  In the rigid motion the
    body turns with the link.  ``body`` and ``pivot`` are keyword arguments.
    """

    body: str = field(kw_only=True)
    pivot: str = field(kw_only=True)


@dataclass(frozen=True)
class Gear:
    """A crank geared to the first crank (the main shaft): ω_crank = ``ratio`` · ω_1.

    ``ratio`` is ``p/q`` in lowest terms (``fraction``); ``body`` is None for a
    rigid mesh, else the gear's body, geared rigidly to the main shaft and
    joined to the crank by the torsion rod ``mesh`` (the mesh stiffness).
    """

    crank: str
    ratio: float
    fraction: tuple
    body: str | None = None


@dataclass(frozen=True)
class Load:
    """A spring ``stiffness`` [N/m] ∥ damper ``damping`` [N·s/m] from ``point`` to the frame.

    It acts along the line to the ground point ``anchor`` or along ``direction``.
    """

    name: str
    point: str
    stiffness: float
    damping: float
    anchor: str | None = None
    direction: tuple[float, float] | None = None


@dataclass(frozen=True)
class SceneDrive:
    """The excitation: on a ``link`` (rotational) or at a ``point`` (along its path).

    ``kind`` is ``"velocity"`` [rad/s or m/s] or ``"force"`` [N·m or N].
    """

    name: str
    kind: Literal["velocity", "force"]
    amplitude: float
    link: str | None = None
    point: str | None = None


@dataclass(frozen=True)
class Analysis:
    """What the scene asks for (the optional ``[analysis]`` table); None where not given.

    ``theta_deg`` the crank rotation [deg], ``output`` the circuit element whose
    force is the output (None: K at the drive), ``band`` (W1, W2) [rad/s] and
    ``tol`` [1] for :func:`mechcirc.simplify`.
    """

    theta_deg: float | None = None
    output: str | None = None
    band: tuple | None = None
    tol: float | None = None


@dataclass(frozen=True, eq=False)
class Scene:
    """A parsed scene; see the module docstring for the file format.

    Attributes
    ----------
    name : str
        The scene's name (the file's ``name``, else the linkage's).
    linkage : Linkage
        The rigid mechanism (every elastic element rigid).
    units : str
        Length unit of the points; ``length_scale`` is its size [m].
    length_scale : float
        The size of ``units`` [m].
    masses, elastic, torsions, loads : tuple
        Its [[masses]], [[elastic]], [[torsion]] and [[loads]] entries, parsed.
    drive : SceneDrive
        The [drive] table, parsed.
    parts : tuple of tuple of str
        The rigid parts left when the elastic elements are released (bodies:
        links and torsion bodies); the part holding the drive comes first.
        Built from the rest when given as ``()`` (raises GeometryError when
        a part does not have one degree of freedom).
    source : str
        Where the scene came from (a file name) for messages.
    """

    __repr__ = summary_repr

    name: str
    linkage: Linkage
    units: str
    length_scale: float
    masses: tuple
    elastic: tuple
    torsions: tuple
    loads: tuple
    drive: SceneDrive
    parts: tuple
    source: str = "<string>"
    analysis: Analysis = Analysis()
    moments: tuple = ()
    simulate: object = None
    gears: tuple = ()
    shaft: object = None

    def __post_init__(self):
        if not self.parts:       # the rigid parts follow from the rest (checks each has 1 DOF)
            object.__setattr__(self, "parts", _parts(self))

    @property
    def cycle_revolutions(self) -> int:
        """Revolutions of the first crank in one cycle of the mechanism (1 without gears;
        the least common multiple of the gear ratios' denominators)."""
        return math.lcm(*(g.fraction[1] for g in self.gears))

    @property
    def cycle(self) -> float:
        """The mechanism's cycle in first-crank rotation [rad]: 2π · cycle_revolutions."""
        return 2.0 * math.pi * self.cycle_revolutions

    @property
    def omega_shaft(self) -> float:
        """The crank's angular speed Ω [rad/s] (harmonics are multiples of it)."""
        return self.linkage.cranks[0].omega

    @property
    def bodies(self) -> dict:
        """Rigid body → its points: links that are not elastic, and torsion bodies."""
        el = {e.link for e in self.elastic}
        return {**{l: pts for l, pts in self.linkage.links.items() if l not in el},
                **{t.body: (t.pivot,) for t in self.torsions}}

    def part_of_body(self) -> dict:
        """Body → index of its rigid part."""
        return {b: i for i, part in enumerate(self.parts) for b in part}

    def part_of_point(self, point: str) -> int | None:
        """Index of the rigid part a point moves with, None for a ground point."""
        if point in self.linkage.ground:
            return None
        torsion_bodies = {t.body for t in self.torsions}
        return next((self.part_of_body()[b] for b, pts in self.bodies.items()
                     if point in pts and b not in torsion_bodies), None)


def _hide_scene_tables(text: str) -> str:
    """The text with the scene tables blanked (line numbers kept), for the linkage parser."""
    key = re.compile(r'^\s*"?([A-Za-z0-9_-]+)"?\s*=')
    out, hiding, top = [], False, True
    for line in split_lines(text):
        if m := TOML_HEADER.match(line):
            top = False
            hiding = m.group(1).split(".")[0].strip('"') in SCENE_TABLES
        elif top:
            hiding = (k := key.match(line)) is not None and k.group(1) in SCENE_TABLES
        out.append("" if hiding else line)
    return "\n".join(out) + "\n"


#: The unit in brackets of a value's description -> its role in the unit grammar: a point
#: mass takes kg only, a link's inertia kg·m² only, an axial rod N/m, a torsion rod
#: N·m/rad (a point mass given 2.5 kg·m² was read as 2.5 kg: session 28).
_ROLE_OF = {"[N/m]": "axial spring", "[N·m/rad]": "rotary spring", "[N·s/m]": "axial damper",
            "[N·m·s/rad]": "rotary damper", "[kg]": "point mass", "[kg·m²]": "rotary inertia",
            "[deg]": "angle"}


def _named(value, names) -> TypeGuard[str]:
    """``value`` is a string among ``names`` (a list or a number in the file is no name)."""
    return isinstance(value, str) and value in names


def _number(text, source, value, what, table, key, n, *, positive=True, allow_zero=False):
    role = next((r for u, r in _ROLE_OF.items() if what.endswith(u)), None)
    converted = in_si(text, source, value, role, table, key, n, what,   # "2 kN/mm", "30 deg"
                      unit="deg" if role == "angle" else "")
    return checked_number(text, source, converted, what, table, key, n, positive=positive,
                          allow_zero=allow_zero)


def parse_scene(text: str, source: str = "<string>") -> Scene:
    """Parse the TOML text of a scene (see the module docstring).

    Parameters
    ----------
    text, source : str
        As for :func:`~mechcirc.kinematics.linkage.parse_linkage`.

    Returns
    -------
    Scene
        The scene (plain data).

    Raises
    ------
    NetlistError
        Anything wrong in the file (TOML syntax, an unknown point, link or
        key, a bad value), at file:line:col.
    GeometryError
        The linkage's own geometry checks, or a rigid part that does not have
        exactly one degree of freedom once the elastic elements are released.
    """
    doc = load_toml(text, source)
    check_keys(text, source, TABLES[None], doc)
    linkage = parse_linkage(_hide_scene_tables(text), source)
    units = _length_unit(text, source, doc)
    if "cam" in doc:                  # a cam swings the first crank (scene/cam.py)
        from .cam import parse_cam

        linkage = parse_cam(text, source, doc["cam"], linkage)
    if (w := linkage.cranks[0].omega) < 0:  # (the scene's tables turn it with θ increasing)
        raise located(text, source, f"the first crank turns at omega = {w:g} rad/s; a scene's "
                      "first crank turns the positive way", "cranks", "omega", expected=(
                          "omega > 0; for a clockwise crank mirror the points (y -> -y)"))
    r = _SceneReader(text, source, doc, linkage)
    elastic = r.elastic()
    elastic_links = {x.link for x in elastic}
    torsions = r.torsions(elastic_links)
    gears, links = r.gears(torsions), linkage.links
    bodies = {l for l in links if l not in elastic_links} | {t.body for t in torsions}
    rigid_points = set().union(*(set(links[l]) for l in links if l not in elastic_links))
    masses = r.masses(bodies, rigid_points, elastic_links)
    loads = r.loads()
    drive = r.drive(bodies, rigid_points)
    circuit_names = r.circuit_names(masses, elastic, torsions, loads, drive)
    analysis = _analysis(text, source, doc.get("analysis"), circuit_names)
    scene = Scene(str(doc.get("name", linkage.name)), linkage, units, LENGTH_UNITS[units],
                  tuple(masses), tuple(elastic), tuple(torsions), tuple(loads), drive, (),
                  source, analysis, gears=tuple(gears))
    if "cam" in doc:
        from .cam import check_follower_part

        spring = check_follower_part(scene, text)     # a contact that can open: its spring
        if spring:
            object.__setattr__(scene, "loads", (*scene.loads, Load(**spring)))
    _read_dynamics(scene, text, source, doc)
    return scene


def _length_unit(text: str, source: str, doc: dict) -> str:
    """The scene's ``units``, the length unit of [points] (refused unless m, cm or mm)."""
    units = doc.get("units")
    if not _named(units, LENGTH_UNITS):
        raise located(text, source, f"a scene needs units = \"m\", \"cm\" or \"mm\" (the length "
                   f"unit of [points]), got {units!r}", None, "units",
                   expected="units = \"mm\" (masses and stiffnesses are SI)")
    return units


def _read_dynamics(scene: Scene, text: str, source: str, doc: dict) -> None:
    """The tables of the time domain into ``scene``: [[moments]], [simulate], [shaft]."""
    object.__setattr__(scene, "moments", parse_moments(text, source, doc.get("moments"), scene))
    object.__setattr__(scene, "simulate", parse_simulate(text, source, doc.get("simulate"),
                                                         scene))
    if "shaft" in doc:
        object.__setattr__(scene, "shaft", parse_shaft(text, source, doc["shaft"], scene))


class _SceneReader:
    """Reads the scene's element tables, one method a table, keeping the names used."""

    def __init__(self, text: str, source: str, doc: dict, linkage: Linkage):
        self.text, self.source, self.doc, self.linkage = text, source, doc, linkage
        self.names: dict[str, str] = {}            # element name -> its table

    def err(self, message, table, key, **kw) -> NetlistError:
        return located(self.text, self.source, message, table, key, **kw)

    def new_name(self, entry, table, key, n, default) -> str:
        """A valid element name not used before: ``entry``'s ``name``, or ``default``
        (an error then points at ``key``)."""
        name = entry.get("name", default)
        key = "name" if "name" in entry else key
        if not is_name(name):
            raise self.err(f"[[{table}]] #{n + 1}: name {name!r} is not a valid "
                           f"element name", table, key, occurrence=n,
                           expected="letters, digits and '_', not starting with a digit")
        if name in self.names:
            raise self.err(f"element name {name!r} is already used in "
                           f"[[{self.names[name]}]]", table, key, occurrence=n,
                           expected="a unique name")
        self.names[name] = table
        return name

    def entries(self, table):
        """``(n, entry)`` of ``[[table]]``, each checked for undeclared keys when reached."""
        raw = self.doc.get(table, [])
        if not isinstance(raw, list) or not all(isinstance(e, dict) for e in raw):
            raise self.err(f"{table} must be an array of tables [[{table}]]", None, table)
        for n, entry in enumerate(raw):
            check_keys(self.text, self.source, TABLES[table], entry, n)
            yield n, entry

    def point_ref(self, entry, table, n, key="point"):
        p = entry.get(key)
        if not _named(p, self.linkage.pose):
            raise self.err(f"[[{table}]] #{n + 1}: {key} {p!r} does not exist in [points]", table,
                           key, value=p, occurrence=n, choices=self.linkage.pose)
        return p

    def number(self, value, what, table, key, n, **kw) -> float:
        return _number(self.text, self.source, value, what, table, key, n, **kw)

    def elastic(self) -> list[ElasticLink]:
        """[[elastic]]: binary rigid links of the linkage made axial springs."""
        links, cranks = self.linkage.links, self.linkage.cranks
        elastic: list[ElasticLink] = []
        for n, e in self.entries("elastic"):
            lname = e.get("link")
            if not _named(lname, links):
                raise self.err(f"elastic link {lname!r} is not in the linkage's [links]",
                               "elastic", "link", value=lname, occurrence=n, choices=links)
            if len(links[lname]) != 2:
                raise self.err(f"elastic link {lname!r} has {len(links[lname])} points; "
                               "only a binary link can be an axial spring", "elastic", "link",
                               value=lname, occurrence=n, expected="a link of two points")
            if any(x.link == lname for x in elastic):
                raise self.err(f"link {lname!r} is declared elastic twice", "elastic",
                               "link", value=lname, occurrence=n)
            if any(c.link == lname for c in cranks):
                raise self.err(f"the crank {lname!r} cannot be an axial spring",
                               "elastic", "link", value=lname, occurrence=n)
            name = self.new_name(e, "elastic", "link", n, lname)
            elastic.append(ElasticLink(name, lname, **self.spring(e, "elastic", n, name, "m",
                                                                  "N")))
        return elastic

    def torsions(self, elastic_links: set) -> list:
        """[[torsion]]: rods at a ground pivot between a rigid link and a new body."""
        links, ground = self.linkage.links, self.linkage.ground
        torsions = []
        for n, t in self.entries("torsion"):
            lname = t.get("link")
            if not _named(lname, links) or lname in elastic_links:
                raise self.err(
                    f"torsion rod #{n + 1}: link {lname!r} is not a rigid link of [links]",
                    "torsion", "link", value=lname, occurrence=n,
                    choices=[lk for lk in links if lk not in elastic_links])
            pivots = [p for p in links[lname] if p in ground]
            pivot = t.get("pivot", pivots[0] if len(pivots) == 1 else None)
            if pivot not in pivots:
                raise self.err(f"torsion rod #{n + 1} must sit at a ground pivot of link "
                               f"{lname!r} (its ground pivots: {pivots or 'none'})", "torsion",
                               "pivot" if "pivot" in t else "link", occurrence=n,
                               expected="pivot = one of the link's ground pivots")
            body = t.get("body")
            if not is_name(body) or body in links or body == "ground":
                raise self.err(f"torsion rod #{n + 1}: body {body!r} must be a new name "
                               "(not a link or 'ground'; several rods may share one body)",
                               "torsion", "body" if "body" in t else "link", occurrence=n,
                               expected="an identifier for the body beyond the rod")
            name = self.new_name(t, "torsion", "body", n, f"C_{body}")
            torsions.append(Torsion(name, lname, body=body, pivot=pivot,
                                    **self.spring(t, "torsion", n, name, "rad", "N·m")))
        return torsions

    def spring(self, entry, table, n, name, gap, load) -> dict:
        """stiffness [load/gap], damping [load·s/gap] and clearance of an [[elastic]],
        [[torsion]] or [[gears]] (its mesh) entry ``n`` named ``name``: the keyword arguments
        of a :class:`_Spring`."""
        k = self.number(entry.get("stiffness"), f"stiffness of {name!r} [{load}/{gap}]",
                        table, "stiffness" if "stiffness" in entry else "link" if "link" in entry
                        else "crank", n)      # a gear's mesh is on its crank
        c = self.number(entry.get("damping", 0.0), f"damping of {name!r} [{load}·s/{gap}]",
                        table, "damping", n, allow_zero=True)
        b = self.number(entry.get("clearance", 0.0),
                        f"clearance of {name!r} (half-width of the gap) [{gap}]", table,
                        "clearance", n, allow_zero=True)
        law = entry.get("clearance_law", "elastobacklash")        # the time domain only
        if law not in CLEARANCE_LAWS:
            raise self.err(f"[[{table}]] #{n + 1}: clearance_law {law!r} is unknown", table,
                           "clearance_law", occurrence=n,
                           expected=" or ".join(f'"{x}"' for x in CLEARANCE_LAWS))
        return {"stiffness": k, "damping": c, "clearance": b, "clearance_law": law}

    def gears(self, torsions: list) -> list:
        """[[gears]]: cranks geared to the first; a crank turning at another speed needs one.

        A gear with ``stiffness`` adds its mesh as a torsion rod (to ``torsions``)
        between the crank and the gear's body.
        """
        cranks = self.linkage.cranks
        w1, names = cranks[0].omega, [c.link for c in cranks]
        gears = {}
        for n, g in self.entries("gears"):
            c = g.get("crank")
            if not _named(c, names[1:]) or c in gears:
                raise self.err(f"[[gears]] #{n + 1}: crank {c!r} is not a crank after the first "
                               "(the main shaft) or is geared twice", "gears",
                               "crank" if "crank" in g else next(iter(g), "crank"),
                               value=c, occurrence=n, choices=names[1:],
                               expected=None if names[1:] else "one of (none: one crank)")
            ratio, frac = self.gear_ratio(n, g, c, w1, names[0])
            body = self.gear_mesh(n, g, c, torsions)
            gears[c] = Gear(c, float(ratio), (frac.numerator, frac.denominator), body)
        for n, cr in enumerate(cranks[1:], start=1):
            if cr.link not in gears and cr.omega != w1:
                raise self.err(f"crank {cr.link!r} turns at {cr.omega:g} rad/s and the first "
                               f"crank {names[0]!r} at {w1:g}: cranks on one shaft need the "
                               "same omega, a crank at another speed needs a [[gears]] entry",
                               "cranks", "omega", occurrence=n,
                               expected=f'[[gears]] crank = "{cr.link}", ratio = '
                                        f"{cr.omega / w1:g}")
        return list(gears.values())

    def gear_ratio(self, n: int, g: dict, c: str, w1: float, main: str) -> tuple:
        """Gear #n's ratio ω_c/ω_main (``w1``, the crank ``main``'s), a ratio of tooth counts
        that agrees with the cranks' omegas, and that ratio as a fraction."""
        from fractions import Fraction

        ratio = self.number(g.get("ratio"), f"gear ratio of {c!r} (ω_{c}/ω_{main})",
                            "gears", "ratio" if "ratio" in g else "crank", n,
                            positive=False)
        if ratio == 0:
            raise self.err(f"[[gears]] #{n + 1}: gear ratio 0 would stop crank {c!r}",
                           "gears", "ratio", occurrence=n,
                           expected="ratio = ω_crank/ω_main, e.g. -1.5 for 3:2 reversed")
        frac = Fraction(ratio).limit_denominator(1000)
        if abs(float(frac) - ratio) > 1e-12 * abs(ratio):
            raise self.err(f"[[gears]] #{n + 1}: gear ratio {ratio!r} is not a ratio of "
                           "whole numbers (tooth counts) with a denominator ≤ 1000, so the "
                           "mechanism would never repeat its cycle", "gears", "ratio",
                           occurrence=n, expected="e.g. ratio = -1.5 (z1/z2 = 30/20)")
        w = next(x.omega for x in self.linkage.cranks if x.link == c)
        if abs(w - ratio * w1) > 1e-12 * abs(w):
            raise self.err(f"[[gears]] #{n + 1}: crank {c!r} has omega = {w:g} rad/s in "
                           f"[[cranks]] but the gear ratio {ratio:g} makes it "
                           f"{ratio * w1:g} rad/s", "gears", "ratio", occurrence=n,
                           expected=f"ratio = {w / w1:g}, or omega = {ratio * w1:g}")
        return ratio, frac

    def gear_mesh(self, n: int, g: dict, c: str, torsions: list) -> str | None:
        """Gear #n's body, with its mesh (stiffness, damping) added to ``torsions`` as a
        rod from crank ``c``; None for a rigid gear."""
        if not ("stiffness" in g or "body" in g or "damping" in g):
            return None
        body = g.get("body", f"gear_{c}")
        if not is_name(body) \
                or body in self.linkage.links or body == "ground" \
                or body in {t.body for t in torsions}:
            raise self.err(f"[[gears]] #{n + 1}: body {body!r} must be a new name",
                           "gears", "body" if "body" in g else "crank", occurrence=n,
                           expected="an identifier for the gear on the crank's shaft")
        name = self.new_name({}, "gears", "crank", n, f"mesh_{c}")
        piv = next(x.pivot for x in self.linkage.cranks if x.link == c)
        torsions.append(Torsion(name, c, body=body, pivot=piv,     # the rules of a torsion rod
                                **self.spring(g, "gears", n, name, "rad", "N·m")))
        return body

    def masses(self, bodies: set, rigid_points: set, elastic_links: set) -> list:
        """[[masses]]: a mass at a point of a rigid link, or the inertia of a body."""
        masses = []
        for n, m in self.entries("masses"):
            if ("point" in m) == ("link" in m):
                raise self.err(f"[[masses]] #{n + 1} needs exactly one of point or link",
                               "masses", next(iter(m), "name"), occurrence=n,
                               expected='point = "P" with mass = …, or link = "L" with '
                                        'inertia = …')
            masses.append(self._point_mass(m, n, rigid_points) if "point" in m
                          else self._link_inertia(m, n, bodies, elastic_links))
        return masses

    def _point_mass(self, m, n, rigid_points):
        p = self.point_ref(m, "masses", n)
        if p not in rigid_points and p not in self.linkage.ground:
            raise self.err(f"mass at point {p!r}: the point is on elastic links "
                           "only, so it belongs to no rigid part", "masses", "point", value=p,
                           occurrence=n, expected="a point of a rigid link")
        if "inertia" in m or "mass" not in m:
            raise self.err(f"[[masses]] #{n + 1} at a point takes mass = … [kg]"
                           + (", not inertia" if "inertia" in m else ""), "masses",
                           "inertia" if "inertia" in m else "point", occurrence=n)
        name = self.new_name(m, "masses", "point", n, f"m_{p}")
        return SceneMass(name, "mass", self.mass(m, n, name), point=p)

    def _link_inertia(self, m, n, bodies, elastic_links):
        lname = m.get("link")
        if not _named(lname, bodies):
            hint = (" (an elastic link has no inertia of its own here: lump its mass at "
                    "its end points)") if _named(lname, elastic_links) else ""
            raise self.err(f"[[masses]] #{n + 1}: link {lname!r} is not a rigid "
                           f"link or torsion body{hint}", "masses", "link",
                           value=lname, occurrence=n, choices=sorted(bodies))
        if "mass" in m or "inertia" not in m:
            raise self.err(f"[[masses]] #{n + 1} on a link takes inertia = … "
                           "[kg·m²]", "masses", "link", occurrence=n)
        name = self.new_name(m, "masses", "link", n, f"J_{lname}")
        return SceneMass(name, "inertia", self.mass(m, n, name), link=lname)

    def mass(self, m, n, name) -> float:
        """``mass`` [kg] or ``inertia`` [kg·m²] of [[masses]] entry ``n`` named ``name``."""
        key, unit = ("mass", "kg") if "mass" in m else ("inertia", "kg·m²")
        return self.number(m[key], f"{key} {name!r} [{unit}]", "masses", key, n)

    def loads(self) -> list:
        """[[loads]]: a spring/damper from a point to a ground anchor or along a direction."""
        loads = []
        for n, ld in self.entries("loads"):
            p = self.point_ref(ld, "loads", n)
            if ("anchor" in ld) == ("direction" in ld):
                raise self.err(f"load #{n + 1} needs exactly one of anchor or direction",
                               "loads", "point", occurrence=n,
                               expected='anchor = "GROUND_POINT" or direction = [dx, dy]')
            anchor, direction = self._load_line(ld, n)
            name = self.new_name(ld, "loads", "point", n, f"load_{p}")
            loads.append(Load(name, p, *self.load_values(ld, n, name), anchor, direction))
        return loads

    def load_values(self, ld, n, name) -> tuple[float, float]:
        """stiffness [N/m] and damping [N·s/m] of [[loads]] entry ``n`` named ``name``."""
        k = self.number(ld.get("stiffness", 0.0), f"stiffness of {name!r} [N/m]",
                        "loads", "stiffness", n, allow_zero=True)
        c = self.number(ld.get("damping", 0.0), f"damping of {name!r} [N·s/m]",
                        "loads", "damping", n, allow_zero=True)
        if k == 0 and c == 0:
            raise self.err(f"load {name!r} needs stiffness > 0 or damping > 0",
                           "loads", "point", occurrence=n)
        return k, c

    def _load_line(self, ld, n):
        """(anchor, direction) of a load: one of them, the other None."""
        if "anchor" in ld:
            anchor = ld["anchor"]
            if not _named(anchor, self.linkage.ground):
                raise self.err(f"load #{n + 1}: anchor {anchor!r} is not a ground "
                               "point", "loads", "anchor", occurrence=n, value=anchor,
                               choices=self.linkage.ground)
            return anchor, None
        d = ld["direction"]
        if not (isinstance(d, list) and len(d) == 2 and all(finite_number(x) for x in d)
                and any(x != 0 for x in d)):
            raise self.err(f"load #{n + 1}: direction must be [dx, dy], not zero, "
                           f"got {brief(d)}", "loads", "direction", occurrence=n)
        return None, (float(d[0]), float(d[1]))

    def drive(self, bodies: set, rigid_points: set) -> "SceneDrive":
        """[drive]: a velocity or force on a rigid link or a point of one."""
        dr = self.doc.get("drive")
        if not isinstance(dr, dict):
            raise NetlistError("a scene needs a [drive] table", self.source, 0, 0,
                               '[drive] with link = "…" (or point = "…") and velocity = V0')
        check_keys(self.text, self.source, TABLES["drive"], dr)
        if ("link" in dr) == ("point" in dr):
            raise self.err("[drive] needs exactly one of link or point", "drive",
                           next(iter(dr), "link"), expected='link = "…" or point = "…"')
        if "link" in dr and not _named(dr["link"], bodies):
            raise self.err(f"[drive] link {dr['link']!r} is not a rigid link or torsion "
                           "body", "drive", "link", value=dr["link"], choices=sorted(bodies))
        if "point" in dr:
            if not _named(dr["point"], self.linkage.pose):
                raise self.err(f"[drive] point {dr['point']!r} does not exist in [points]",
                               "drive", "point", value=dr["point"], choices=self.linkage.pose)
            if dr["point"] not in rigid_points:
                raise self.err(f"[drive] point {dr['point']!r} is on no rigid link",
                               "drive", "point")
        if ("velocity" in dr) == ("force" in dr):
            raise self.err("[drive] needs exactly one of velocity = V0 or force = F0",
                           "drive", "force" if "force" in dr else next(iter(dr), "link"))
        kind: Literal["velocity", "force"] = "velocity" if "velocity" in dr else "force"
        amp = self.number(dr[kind], f"drive {kind} amplitude", "drive", kind, 0,
                          positive=False)
        dname = dr.get("name", "V")
        if not is_name(dname) or dname in self.names:
            raise self.err(f"[drive] name {dname!r} is not a valid unused element name",
                           "drive", "name")
        return SceneDrive(dname, kind, amp, link=dr.get("link"), point=dr.get("point"))

    def circuit_names(self, masses, elastic, torsions, loads, drive) -> set:
        """The circuit's element names: a damper in parallel with a spring is NAME_d."""
        names = {m.name for m in masses} | {drive.name}
        for el in (*elastic, *torsions, *loads):
            names.add(el.name)
            if el.damping > 0 and el.stiffness > 0:
                taken = el.name + "_d"
                if taken in self.names:
                    where = next(((n, ln.index(f'"{taken}"') + 1) for n, ln in
                                  enumerate(split_lines(self.text), start=1)
                                  if f'"{taken}"' in ln), (0, 0))
                    raise NetlistError(f"{el.name!r} has a damper, named {taken!r} in the "
                                       "circuit, but that name is taken", self.source, *where,
                                       "another name")
                names.add(taken)
        return names


def _analysis(text, source, table, circuit_names) -> Analysis:
    """The optional ``[analysis]`` table: theta_deg, output, band = [W1, W2], tol."""
    if table is None:
        return Analysis()
    if not isinstance(table, dict):
        raise located(text, source, "analysis must be a table [analysis]", None, "analysis")
    check_keys(text, source, TABLES["analysis"], table)
    theta = _number(text, source, table["theta_deg"], "theta_deg [deg]", "analysis",
                    "theta_deg", 0, positive=False) if "theta_deg" in table else None
    output = table.get("output")
    if output is not None and not _named(output, circuit_names):
        raise located(text, source, f"[analysis] output {output!r} is not an element of the "
                   "scene's circuit", "analysis", "output", value=output,
                   choices=sorted(circuit_names))
    band = None
    if "band" in table:
        from .._simplify import BandError, check_band

        raw = table["band"]
        try:
            if not (isinstance(raw, list) and len(raw) == 2 and all(map(finite_number, raw))):
                raise BandError(f"band must be [W1, W2] in rad/s, got {raw!r}")
            band = check_band(raw)
        except BandError as exc:
            raise located(text, source, f"[analysis] {exc}", "analysis", "band",
                       expected="band = [W1, W2] with 0 < W1 < W2 [rad/s]") from None
    tol = _number(text, source, table["tol"], "tol", "analysis", "tol", 0) \
        if "tol" in table else None
    if (band is None) != (tol is None):
        raise located(text, source, "[analysis] needs band and tol together", "analysis",
                   "band" if band is not None else "tol",
                   expected="band = [W1, W2] and tol = T")
    return Analysis(theta, output, band, tol)


def _parts(scene: Scene) -> tuple:
    """Rigid parts after releasing the elastic elements; checks each has one DOF."""
    lk, bodies = scene.linkage, scene.bodies
    tbodies = {t.body for t in scene.torsions}
    meshes = gear_meshes(scene)
    parts = _rigid_parts(lk, bodies, tbodies, meshes)
    for part in parts:
        n = len(part)
        pairs = sum(max(sum(p in bodies[b] for b in part) + (p in lk.ground) - 1, 0)
                    for p in {p for b in part for p in bodies[b]})
        # a slider in the part on a guide in the part or the frame
        pairs += sum(1 for x in lk.sliders if x.link in part and (x.guide in part
                                                                   or x.guide == "ground"))
        g = sum(1 for a, b, _ in meshes if a in part)     # a rigid mesh: one constraint
        w = 3 * n - 2 * pairs - g
        if w != 1:
            near = [e.name for e in scene.elastic
                    if any(p in bodies[b] for b in part for p in lk.links[e.link])]
            raise GeometryError(
                f"{scene.source}: once the elastic elements are released, the rigid part "
                f"{{{', '.join(part)}}} has W = 3·{n} − 2·{pairs}{f' − {g}' if g else ''} = {w} "
                f"degrees of freedom{' (a rigid gear mesh counts 1)' if g else ''}; "
                f"each rigid part between elastic elements must have exactly one (elastic "
                f"elements next to it: {', '.join(near) or 'none'}; " + (
                    "an elastic gear mesh inside a loop through both cranks is not supported: "
                    "make the mesh rigid)" if any(gb.body in part for gb in scene.gears) else
                    "an elastic link pinned to the frame is not supported: model it as a "
                    "torsion rod or a load)"))
    part_of = {b: i for i, part in enumerate(parts) for b in part}
    for e in scene.elastic:
        ends = []
        for p in lk.links[e.link]:
            on = [b for b, pts in bodies.items() if p in pts and b not in tbodies]
            if not on and p not in lk.ground:
                raise GeometryError(f"{scene.source}: elastic link {e.link!r} ends at point "
                                    f"{p!r}, which is on no rigid link and not a ground pivot")
            ends.append(part_of[on[0]] if on else None)
        if ends[0] is not None and ends[0] == ends[1]:
            raise GeometryError(
                f"{scene.source}: elastic link {e.link!r} joins the rigid part "
                f"{{{', '.join(parts[ends[0]])}}} to itself (it is redundant in a rigid "
                f"loop); only links between different rigid parts or to the frame are supported")
    d = scene.drive
    first = d.link if d.link is not None else \
        next(b for b, pts in bodies.items() if d.point in pts and b not in tbodies)
    parts.sort(key=lambda part: first not in part)
    return tuple(parts)


def gear_meshes(scene: Scene) -> list[tuple]:
    """Rigid gear meshes as (body, first crank, ratio): the body turns at ratio × the first
    crank (the geared crank itself, or the gear beyond its mesh stiffness)."""
    return [(g.body or g.crank, scene.linkage.cranks[0].link, g.ratio) for g in scene.gears]


def _rigid_parts(lk, bodies: dict, tbodies: set, meshes=()) -> list[tuple]:
    """Bodies joined by a moving pin (not through a torsion body) or a rigid gear mesh, as
    connected components.

    Each part lists its bodies in the order of ``bodies``; the parts are in the
    order of their first body.
    """
    import networkx as nx

    g = nx.Graph()
    g.add_nodes_from(bodies)
    for p in (p for p in lk.pose if p not in lk.ground):
        on = [b for b, pts in bodies.items() if p in pts and b not in tbodies]
        g.add_edges_from((on[0], b) for b in on[1:])
    g.add_edges_from((x.guide, x.link) for x in lk.sliders if x.guide in bodies)
    g.add_edges_from((a, b) for a, b, _ in meshes)
    order = {b: i for i, b in enumerate(bodies)}
    parts = [tuple(sorted(c, key=order.__getitem__)) for c in nx.connected_components(g)]
    return sorted(parts, key=lambda part: order[part[0]])


def load_scene(path: str | Path) -> Scene:
    """Read and parse a scene TOML file (see :func:`parse_scene`).

    Parameters
    ----------
    path : str or Path
        The scene file (TOML, UTF-8).

    Returns
    -------
    Scene
        As :func:`parse_scene`, with the file's name in its error messages.

    Raises
    ------
    NetlistError
        The file is missing or unreadable, or has an error.
    """
    return parse_scene(read_source(path, "a scene .toml"), os.fspath(path))


#: By the kind of element NAME is: the Scene field holding it, and what
#: ``--set NAME.FIELD`` may change in it.
_FIELDS: dict[type, tuple[str, tuple[str, ...]]] = {
    SceneMass: ("masses", ("mass", "inertia", "value")),
    ElasticLink: ("elastic", ("stiffness", "damping", "clearance")),
    Torsion: ("torsions", ("stiffness", "damping", "clearance")),
    Load: ("loads", ("stiffness", "damping")),
    Moment: ("moments", ("amplitude", "window_deg", "sigma_deg"))}


def apply_overrides(scene: Scene, overrides: dict) -> Scene:
    """A copy of ``scene`` with ``NAME.FIELD = value`` overrides (``--set``); also ``omega``.

    Fields: ``mass``/``inertia`` (or ``value``) of a mass; ``stiffness``,
    ``damping``, ``clearance`` of an elastic link or torsion rod, ``stiffness``,
    ``damping`` of a load; ``amplitude``, ``window_deg``, ``sigma_deg`` of a
    moment; ``omega`` (the crank speed of the run), ``omega_ripple.amplitude``,
    ``omega_ripple.harmonic``.  Each value is checked by the file reader's own
    rule for that key, so what the file refuses ``--set`` refuses, with the same
    message; a text (``"2 kN*m/rad"``) is read as the file reads it there (any
    unit where the file takes none: ``omega = "3000rpm"``).

    Parameters
    ----------
    scene : Scene
    overrides : dict[str, float or str]

    Returns
    -------
    Scene

    Raises
    ------
    NetlistError
        A value the scene file would refuse; its source is ``--set NAME.FIELD=VALUE``.
    MechcircError
        An unknown name or field.
    """
    found = {x.name: x for table, _ in _FIELDS.values() for x in getattr(scene, table)}
    sim = scene.simulate if isinstance(scene.simulate, SimulateSettings) else SimulateSettings()
    for key, value in overrides.items():
        source = f"--set {key}={value}"
        name, _, fld = key.partition(".")
        kind = type(found.get(name))
        # a bare number is read here, a text with a unit only for omega and the ripple (any
        # unit); the others go to their reader as typed (a moment's, as the file's
        # [[moments]], takes no unit and refuses one)
        if isinstance(value, str) and (name not in found or is_bare_number(value)):
            value = parse_quantity(value)
        if key in ("omega", "omega_ripple.amplitude", "omega_ripple.harmonic"):
            sim = override_run(source, sim, key, value)
        elif fld in _FIELDS.get(kind, ("", ()))[1]:
            found[name] = _override(_SceneReader("", source, {}, scene.linkage), found[name],
                                    fld, value)
        else:
            known = ["omega", "omega_ripple.amplitude/harmonic"] + [
                f"{n}.{'/'.join(_FIELDS[type(x)][1])}" for n, x in found.items()]
            every = ["omega", "omega_ripple.amplitude", "omega_ripple.harmonic"] + [
                f"{n}.{f}" for n, x in found.items() for f in _FIELDS[type(x)][1]]
            raise MechcircError(f"--set {key}: no such parameter{did_you_mean(key, every)} "
                                f"(known: {', '.join(known)})")
    # each table rebuilt from its own entries (a scene made in Python may repeat a name
    # across tables: one name, one entry of ``found``)
    tables: dict[str, Any] = {table: tuple(found[x.name] if type(found[x.name]) is kind else x
                                           for x in getattr(scene, table))
                              for kind, (table, _) in _FIELDS.items()}
    return replace(scene, simulate=sim, **tables)


def _override(reader: _SceneReader, old, fld: str, value):
    """The mass, spring, load or moment ``old`` with ``fld`` = ``value``, checked by the
    rule of the reader of its table (``reader``, whose source is the ``--set``)."""
    if isinstance(old, Moment):
        return override_moment(reader.source, old, fld, value)
    if isinstance(old, SceneMass):
        if fld not in ("value", old.kind):      # (a point mass's inertia, a link's mass)
            raise MechcircError(f"{reader.source}: {old.name!r} is a "
                                f"{'point mass' if old.kind == 'mass' else 'link inertia'}; "
                                f"set {old.name}.{old.kind}")
        return replace(old, value=reader.mass({old.kind: value}, 0, old.name))
    entry = asdict(old) | {fld: value}          # as the file would hold it, with the new value
    if isinstance(old, Load):
        k, c = reader.load_values(entry, 0, old.name)
        return replace(old, stiffness=k, damping=c)
    gap, load = ("m", "N") if isinstance(old, ElasticLink) else ("rad", "N·m")
    return replace(old, **reader.spring(entry, "elastic", 0, old.name, gap, load))
