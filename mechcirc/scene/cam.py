"""A disc cam on the main shaft driving a follower in a scene (``[cam]``).

Oscillating follower (a roller on the arm, or ``oscillating_flat``: a flat face
through the arm's pivot): the follower is the linkage's crank (its arm pivoted to
the frame); the cam replaces its uniform turning by the law x(θ) of a
:class:`~mechcirc.motion_laws.Motion`: at cam angle θ = Ω t the arm is turned
by α = x(θ) − x(0) from the pose (either face; the face changes the cam's
profile, checked by :func:`~mechcirc.kinematics.cam.cam_profile`, not the arm's
motion).

Translating follower (roller or flat face): the follower is a block sliding on
a fixed guide, lifted by s(θ) = x(θ) − x(0) along it; the linkage's crank is a
link pinned to the frame in the follower's rigid part, and α(θ) is the crank
rotation that puts the block at that lift: τ(α) = s, τ the block's travel
along its guide, solved by Newton with the solver's exact τ′ = u·v/Ω (to
round-off), and by the chain rule α′ = x′/τ′, α″ = (x″ − τ″ α′²)/τ′.

The linkage is solved at α with the crank turning at Ω, and the rates are
rescaled by the chain rule, exactly: with q̇ₛ = J Ω and q̈ₛ = J′ Ω² the
solver's rates,

    q̇ = q̇ₛ α′(θ),      q̈ = q̈ₛ α′(θ)² + q̇ₛ Ω α″(θ).

A rate x′ below :data:`DWELL` of the peak is the round-off of a dwell and is
set to 0.  Everything that calls :meth:`Linkage.motion` or :meth:`Linkage.solve`
(the circuit at θ, the cycle map, the time-domain tables) then follows the cam.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import GeometryError, InputError, MechcircWarning, warn
from ..kinematics.linkage import Linkage, Slider
from ..sources import Table, brief, check_keys, checked_number, did_you_mean, located
from ..units import in_si

if TYPE_CHECKING:
    from ..motion_laws import Motion

__all__ = ["CamLinkage", "parse_cam", "check_follower_part", "aligned_points", "DWELL",
           "contact_geometry", "open_contact_rows", "SPRING"]

#: |x′(θ)| at most this fraction of its peak is the round-off of a dwell's 0: the
#: follower is at rest there (a law's x′ is exact to ~1e-16 of its peak).
DWELL = 1e-13


@dataclass(frozen=True, eq=False)
class CamLinkage(Linkage):
    """A :class:`Linkage` whose first crank follows a cam (see the module).

    Attributes
    ----------
    cam : Motion
        The follower's motion x(θ) over one turn of the cam shaft: the arm's
        rotation [rad], or a translating follower's lift [the pose's units].
    x0 : float
        x(0): the pose is the follower at cam angle 0.
    key : tuple
        What identifies the cam, for the scene's memoised tables.
    follower : str
        The follower's link ("" for the first crank).
    slider : Slider or None
        A translating follower's prismatic pair on the frame; None: oscillating.
    contact : str
        The ``[[elastic]]`` element that is the cam's contact when it can open
        ("" : the follower is kinematic); ``spring`` [N/m] and ``preload`` [N]
        are then the follower spring's (see "The contact that can open").
    """

    cam: Motion = field(kw_only=True)
    x0: float = 0.0
    key: tuple = ()
    follower: str = ""
    slider: Slider | None = None
    contact: str = ""
    spring: float = 0.0
    preload: float = 0.0

    @cached_property
    def peak_rate(self) -> float:
        """max |x′(θ)| over the turn (on 4096 angles) [per rad]."""
        return float(np.max(np.abs(self.cam.evaluate(np.linspace(0, 2 * np.pi, 4097))[1])))

    def motion(self, theta, *, max_step_deg: float = 2.0, method: str = "auto"):
        """Kinematics at cam angles ``theta`` [rad] (the crank at α(θ)); see the module."""
        th = np.asarray(theta, dtype=float).reshape(-1)
        x, x1, x2 = self.cam.evaluate(th)
        x1 = np.where(np.abs(x1) <= DWELL * self.peak_rate, 0.0, x1)    # a dwell: at rest
        kw: dict[str, Any] = {"max_step_deg": max_step_deg, "method": method}
        if self.slider is None:
            a1, a2 = x1, x2
            m = Linkage.motion(self, x - self.x0, **kw)
        else:
            m, a1, a2 = self._lifted(th, x - self.x0, x1, x2, kw)
        w = self.cranks[0].omega
        qd = m.qdot * a1[:, None]
        qdd = m.qddot * (a1 * a1)[:, None] + m.qdot * (w * a2)[:, None]
        return dataclasses.replace(m, theta=th, t=th / w, qdot=qd, qddot=qdd,
                                   parts=m.parts * a1[:, None, None])

    def _lifted(self, th, s, x1, x2, kw):
        """The motion at the crank rotations α that lift the follower by ``s``, and α′, α″."""
        sl, w = self.slider, self.cranks[0].omega
        u, p0 = np.array(sl.direction, dtype=float), self.pose[sl.point]

        def travel(alpha):
            # a trial past the lock (where the dyads' determinant is 0) gives NaN rates,
            # which the search below rejects: numpy's divide warnings would only be noise
            with np.errstate(divide="ignore", invalid="ignore"):
                m = Linkage.motion(self, alpha, **kw)
                i = m.point_names.index(sl.point)
                return m, (m.points[:, i] - p0) @ u, (m.velocities[:, i] @ u) / w, i

        alpha = np.zeros_like(s)
        m, tau, slope, i = travel(alpha)
        slope0, tol, crank = slope[0], 1e-13 * self.length_scale(), self.cranks[0].link
        if not abs(slope0) > tol:
            raise GeometryError(f"{self.source}: [cam] in the pose the crank {crank!r} does not "
                                f"move the follower {self.follower!r} along its guide (a dead "
                                "centre)")
        polish = 2                       # two more steps once converged: round-off level
        for _ in range(60):
            r = tau - s
            polish -= bool(np.max(np.abs(r)) <= tol)
            if polish < 0:
                break
            step, trial, why = -r / slope, None, ""
            for _ in range(40):          # damped: halve the step until the linkage assembles
                try:
                    trial = travel(alpha + step)
                except GeometryError as exc:
                    trial, why = None, str(exc)
                else:
                    if np.all(trial[2] * slope0 > 0):
                        break
                    trial, why = None, "its travel along the guide turns back: a dead centre"
                step = 0.5 * step
            if trial is None:
                k = int(np.argmax(np.abs(r)))
                raise GeometryError(
                    f"{self.source}: [cam] no rotation of the crank {crank!r} lifts the "
                    f"follower {self.follower!r} by {s[k]:.6g} {self.units or 'units'} (cam "
                    f"angle {math.degrees(th[k]):.6g}°): the linkage locks or passes a dead "
                    f"centre before ({why})")
            alpha = alpha + step
            m, tau, slope, i = trial
        else:
            k = int(np.argmax(np.abs(tau - s)))
            raise GeometryError(
                f"{self.source}: [cam] no rotation of the crank {crank!r} was found that lifts "
                f"the follower {self.follower!r} by {s[k]:.6g} {self.units or 'units'} (cam "
                f"angle {math.degrees(th[k]):.6g}°; the nearest lifts it by {tau[k]:.6g}): the "
                "lift is beyond what the linkage can reach")
        a1 = x1 / slope
        curv = (m.accelerations[:, i] @ u) / (w * w)
        return m, a1, (x2 - curv * a1 * a1) / slope


def check_follower_part(scene, text: str) -> dict | None:
    """A translating follower must be in the rigid part of the crank it drives.

    With a contact that can open, the contact is checked too, and the follower
    spring is returned as the keywords of a :class:`~mechcirc.scene.files.Load`
    (the scene adds it to its loads); else None.

    Parameters
    ----------
    scene : Scene
    text : str
        The scene file's text, to locate the error.

    Returns
    -------
    dict or None
        The follower spring's :class:`~mechcirc.scene.files.Load` keywords, or None.

    Raises
    ------
    NetlistError
        The follower and the crank are in different rigid parts (an elastic
        element between them), located at ``[cam] follower``.
    """
    lk = scene.linkage
    crank = lk.cranks[0].link
    if getattr(lk, "slider", None) is not None and not any(
            crank in p and lk.follower in p for p in scene.parts):
        raise located(text, scene.source, f"[cam] the translating follower {lk.follower!r} "
                      f"and the crank {crank!r} are in different rigid parts: the cam lifts "
                      "the follower and the crank's part moves with it, so they must be joined "
                      "by rigid links", "cam", "follower", value=lk.follower,
                      expected="rigid links between the follower and the crank")
    return _open_contact(scene, text) if getattr(lk, "contact", "") else None


#: The follower spring's element name when the contact can open (a [[loads]]-like spring).
SPRING = "follower_spring"


def contact_geometry(scene):
    """The geometry of a scene's cam contact that can open (see :func:`open_contact_rows`).

    Parameters
    ----------
    scene : Scene
        A cam scene with ``[cam] contact``.

    Returns
    -------
    tuple
        (contact element, follower point, unit vector cam block → follower,
        pose distance [m], half-gap [m]).
    """
    lk, L = scene.linkage, scene.length_scale
    el = next(e for e in scene.elastic if e.name == lk.contact)
    a, b = lk.links[el.link]
    cam_part = scene.part_of_body()[lk.cranks[0].link]
    if scene.part_of_point(a) != cam_part:
        a, b = b, a
    d = (lk.pose[b] - lk.pose[a]) * L
    dist = float(np.hypot(*d))
    s = lk.cam.evaluate(np.linspace(0.0, 2 * np.pi, 4097))[0] - lk.x0
    return el, b, d / dist, dist, float(np.abs(s).max()) * L + lk.preload / lk.spring


def _open_contact(scene, text) -> dict:
    """Check the contact that can open; the follower spring's Load keywords.

    The contact is an ``[[elastic]]`` link from a point of the cam's part (the block
    the cam lifts) to a point P of another part, P on a block sliding on a guide fixed
    to the frame along the contact's line; the spring acts at P along that line.
    """
    lk = scene.linkage

    def err(msg, expected):
        return located(text, scene.source, f"[cam] contact {lk.contact!r} {msg}",
                       "cam", "contact", value=lk.contact, expected=expected)

    el = next((e for e in scene.elastic if e.name == lk.contact), None)
    if el is None:
        raise err("is not an [[elastic]] element", "one of " + (", ".join(
            e.name for e in scene.elastic) or "(no [[elastic]] element)"))
    if el.clearance:
        raise err("has a clearance: the contact's gap is set by the cam (it pushes only)",
                  "no clearance on the contact's [[elastic]] entry")
    a, b = lk.links[el.link]
    cam_part = scene.part_of_body()[lk.cranks[0].link]
    parts = {scene.part_of_point(a), scene.part_of_point(b)}
    if cam_part not in parts or None in parts or len(parts) != 2:
        raise err("must join the cam's block (the part the cam drives) to the follower, a "
                  "part of its own", "an [[elastic]] link from the block the cam lifts to "
                  "the follower's block")
    _, p, u, _, _ = contact_geometry(scene)
    guide = [x for x in lk.sliders if x.guide == "ground" and p in lk.links[x.link]]
    g = np.asarray(guide[0].direction, float) if guide else None
    if g is None or abs(float(g[0] * u[1] - g[1] * u[0])) > 1e-9:
        raise err(f"must be along the guide of the follower's point {p!r} (a block sliding "
                  "on a guide fixed to the frame)", "the follower on a guide along the "
                  "contact's line")
    if any(x.name == SPRING for x in (*scene.masses, *scene.elastic, *scene.torsions,
                                       *scene.loads)):
        raise err(f"needs the element name {SPRING!r} for its spring", f"no element named "
                  f"{SPRING!r}")
    return {"name": SPRING, "point": p, "stiffness": lk.spring, "damping": 0.0,
            "direction": (float(u[0]), float(u[1]))}


def open_contact_rows(scene, EI, EF, enames, point_fns) -> None:
    """The kernel rows of the contact that can open, in place (see the module).

    The contact's row gets the one-sided law: ElastoBacklash with half-gap G/2 =
    max lift + F₀/k and a free length that leaves it pushing F₀ in the pose, so its
    far flank is G away; the spring's row (a load along the rigid motion) becomes an
    absolute spring from an anchor on the line, pushing F₀ + k y.

    Parameters
    ----------
    scene : Scene
        A cam scene with ``[cam] contact``.
    EI, EF : list
        The kernel's integer and float rows of the scene's elements (changed in place).
    enames : list of str
        The elements' names, in the rows' order.
    point_fns : callable
        ``point_fns(point)`` → (x function, y function, part) of a point's motion.
    """
    lk, L = scene.linkage, scene.length_scale
    el, p, u, dist, half = contact_geometry(scene)
    i = enames.index(el.name)
    EI[i][1] = 1                                        # ElastoBacklash
    EF[i][2], EF[i][3] = half, dist + half + lk.preload / el.stiffness
    j = enames.index(SPRING)
    fx, fy, part = point_fns(p)
    anchor = lk.pose[p] * L + u                         # 1 m beyond P along the line
    EI[j] = [1, 0, -1, -1, fx, fy, 0, part]
    EF[j] = [lk.spring, 0.0, 0.0, 1.0 + lk.preload / lk.spring, float(anchor[0]),
             float(anchor[1]), 0.0, 0.0, 0.0, 0.0]


def aligned_points(cam, n: int) -> int:
    """The fewest intervals per turn, from ``n`` to 4n, that put a node on every joint of the
    ``cam``'s pieces (where a derivative of x jumps; a quintic Hermite table across one
    is ~60 times less accurate), else ``n``.

    Parameters
    ----------
    cam : Motion
        The follower's law.
    n : int

    Returns
    -------
    int
    """
    u = np.asarray(cam.start, dtype=float) / (2 * np.pi)
    return next((k for k in range(n, 4 * n + 1)
                 if np.all(np.abs(u * k - np.round(u * k)) <= 1e-9)), n)


#: The ``[cam]`` table's keys (see docs/scenes.md, "A cam drives the scene").
CAM_KEYS = {"follower": "oscillating: the first crank of [[cranks]]; roller or flat: a block "
                        "sliding on a fixed guide",
            "follower_type": "oscillating (default: a roller on the arm) | oscillating_flat "
                             "(a flat face on the arm) | roller | flat",
            "law": "a motion law of mechcirc.motion_laws.LAWS", "rise": "[deg]",
            "dwell": "[deg], default 0", "return": "[deg]", "return_law": "default: law",
            "stroke_deg": "the arm's swing [deg], nonzero (oscillating)",
            "stroke": "the lift [units], nonzero (roller, flat)",
            "table": "CSV angle_deg,displacement: the arm's angle [deg] or the lift [units] "
                     "(instead of a law)",
            "base_radius": "r_b [units], for the pressure-angle and undercut checks",
            "roller_radius": "r_f [units], default 0", "arm": "L [units] (oscillating)",
            "pivot": "D, arm pivot to cam centre [units] (oscillating, oscillating_flat)",
            "offset": "e, the follower's axis from the cam's centre [units] (roller), default 0",
            "pressure_limit_deg": "default 45 (oscillating), 30 (roller, flat)",
            "contact": "an [[elastic]] link from the cam's block to the follower: it pushes "
                       "only, so the follower can leave the cam (roller, flat)",
            "spring": "the follower spring [N/m] > 0, with contact",
            "preload": "the follower spring's force at the bottom of the lift [N] >= 0"}
#: The keys that belong to some kinds of follower only: (what they are for, those kinds).
_ONLY = {"stroke_deg": ("oscillating", ("oscillating", "oscillating_flat")),
         "arm": ("oscillating roller", ("oscillating",)),
         "pivot": ("oscillating", ("oscillating", "oscillating_flat")),
         "stroke": ("translating", ("roller", "flat")), "offset": ("roller", ("roller",)),
         "roller_radius": ("roller", ("oscillating", "roller", "flat"))}
#: The role and unit of each key with no bare-degree reading ("": the scene's ``units``);
#: the others (rise, dwell, return, stroke_deg, pressure_limit_deg) are angles in degrees.
_UNIT_OF = {**dict.fromkeys(("stroke", "base_radius", "roller_radius", "arm", "pivot", "offset"),
                            ("length", "")), "spring": ("spring", "N/m"), "preload": ("force", "N")}
#: The follower types of a scene's [cam].
KINDS = ("oscillating", "oscillating_flat", "roller", "flat")


class _CamReader:
    """Reads one ``[cam]`` table, each value located at its key on error."""

    def __init__(self, text, source, raw, linkage):
        self.text, self.source, self.raw, self.lk = text, source, raw, linkage

    def err(self, message, key, expected=None, value=None):
        return located(self.text, self.source, message, "cam", key, value=value,
                       expected=expected)

    def num(self, key, default=None, positive=True, allow_zero=False):
        role, unit = _UNIT_OF.get(key, ("angle", "deg"))
        value = in_si(self.text, self.source, self.raw.get(key, default), role, "cam", key,
                      what=f"[cam] {key}", unit=unit or self.lk.units)   # "20 mm", "2 rad"
        return checked_number(self.text, self.source, value, f"[cam] {key}",
                              "cam", key if key in self.raw else "follower", positive=positive,
                              allow_zero=allow_zero, expected=f"{key} = {CAM_KEYS[key]}")

    def kind(self) -> str:
        """``follower_type``, and the keys of the other kinds refused."""
        kind = self.raw.get("follower_type", "oscillating")
        if kind not in KINDS:
            raise self.err(f"[cam] follower_type {brief(kind)} is not a follower type"
                           + did_you_mean(str(kind), KINDS),
                           "follower_type", expected=" | ".join(KINDS),
                           value=kind)
        for key, (what, kinds) in _ONLY.items():
            if key in self.raw and kind not in kinds:
                raise self.err(f"[cam] {key} is for a{'n' if what[0] == 'o' else ''} {what} "
                               f"follower, not {kind}", key, expected=f"{key}: "
                               f"{CAM_KEYS[key]}; follower_type = \"{kind}\" takes " + (", ".join(
                                   k for k, (_, ks) in _ONLY.items() if kind in ks) or "none"))
        return kind

    def follower(self, kind):
        """The follower's name and, for a translating one, its slider on the frame."""
        cranks, f, raw = self.lk.cranks, self.raw.get("follower"), self.raw
        at = "follower" if "follower" in raw else next(iter(raw), "follower")
        if kind.startswith("oscillating"):
            slider = None
            if len(cranks) != 1 or f != cranks[0].link:
                raise self.err(f"[cam] follower {brief(f)} must be the linkage's only crank "
                               f"(the arm the cam swings; its omega is the cam shaft's "
                               f"speed)", at, value=f, expected=f'follower = '
                               f'"{cranks[0].link}" with one [[cranks]] entry')
        else:
            slider = next((x for x in self.lk.sliders if x.link == f and x.guide == "ground"),
                          None)
            if slider is None or len(cranks) != 1:
                raise self.err(f"[cam] follower {brief(f)} must be a block sliding on a guide "
                               "fixed to the frame ([[sliders]] guide = \"ground\"), with one "
                               "[[cranks]] entry: a link pinned to the frame that the follower "
                               "moves", at, value=f, expected="follower = one of " + (", ".join(
                                   x.link for x in self.lk.sliders if x.guide == "ground")
                                   or "(no block on a fixed guide)"))
        if not cranks[0].omega > 0:
            raise self.err(f"[cam] the cam shaft turns at omega = {cranks[0].omega:g} rad/s "
                           f"(the [[cranks]] omega of {cranks[0].link!r}); a cam needs "
                           f"omega > 0", at, expected="omega > 0 in [[cranks]]", value=f)
        return f, slider

    def motion(self, kind):
        """The follower's Motion (arm angle [rad] or lift [units]) and its memo key."""
        from ..motion_laws import LAWS, cam_cycle, read_motion_table

        raw = self.raw
        if ("table" in raw) == ("law" in raw):
            raise self.err("[cam] needs exactly one of law = … (with rise, dwell, return, "
                           "stroke) or table = \"FILE.csv\"",
                           "law" if "law" in raw else "follower",
                           expected='law = "cycloidal" or table = "lift.csv"')
        if "table" in raw:
            path = raw["table"]
            if not isinstance(path, str):
                raise self.err(f"[cam] table must be a file name, got {brief(path)}", "table")
            if self.source != "<string>" and not os.path.isabs(path):
                path = os.path.join(os.path.dirname(self.source), path)
            motion = read_motion_table(path)
            if kind.startswith("oscillating"):
                motion = motion.scaled(math.pi / 180.0)
            return motion, ("table", os.path.abspath(path), motion.start, motion.poly,
                            motion.sine)
        for key in ("law", "return_law"):
            if key in raw and raw[key] not in LAWS:
                raise self.err(f"[cam] {key} {brief(raw[key])} is not a motion law"
                               + did_you_mean(str(raw[key]), LAWS), key,
                               expected=" | ".join(LAWS), value=raw[key])
        osc = kind.startswith("oscillating")
        skey = "stroke_deg" if osc else "stroke"
        rise, ret = self.num("rise"), self.num("return")
        dwell, stroke = self.num("dwell", 0.0, allow_zero=True), self.num(skey, positive=False)
        h = math.radians(stroke) if osc else stroke
        try:
            motion = cam_cycle(raw["law"], rise, dwell, ret, h, raw.get("return_law"))
        except ValueError as exc:
            key = skey if "stroke" in str(exc) else "rise"
            raise self.err(f"[cam] {exc}".replace(
                "stroke=", "stroke [rad] = " if osc else "stroke = "), key,
                expected=f"rise + dwell + return ≤ 360 degrees, {skey} ≠ 0") from None
        return motion, ("law", raw["law"], raw.get("return_law"), rise, dwell, ret, stroke)

    def contact(self, kind) -> dict:
        """``contact``, ``spring``, ``preload``: the contact that can open, if asked for."""
        raw = self.raw
        if "contact" not in raw:
            for key in ("spring", "preload"):
                if key in raw:
                    raise self.err(f"[cam] {key} is the follower spring's, for a contact that "
                                   "can open", key, expected='contact = "NAME" (an '
                                   "[[elastic]] link from the cam's block to the follower)")
            return {}
        c = raw["contact"]
        if kind.startswith("oscillating") or not isinstance(c, str):
            raise self.err(f"[cam] contact {brief(c)}: the contact that can open is an "
                           "[[elastic]] link's name, for a translating follower (roller or "
                           "flat)", "contact", expected='contact = "NAME" with follower_type '
                           '= "roller" or "flat"', value=c)
        return {"contact": c, "spring": self.num("spring"),
                "preload": self.num("preload", allow_zero=True)}

    def checks(self, kind, motion):
        """The cam's pressure-angle and undercut checks (warnings), when base_radius is given."""
        from ..kinematics.cam import cam_profile

        geo = ("roller_radius", "arm", "pivot", "offset", "pressure_limit_deg")
        if "base_radius" not in self.raw:
            if any(k in self.raw for k in geo):
                raise self.err("[cam] the geometry checks need base_radius", next(
                    k for k in geo if k in self.raw), expected="base_radius = r_b")
            return
        limit = self.num("pressure_limit_deg", 45.0 if kind.startswith("oscillating") else 30.0)
        rf = self.num("roller_radius", 0.0, allow_zero=True)
        if kind == "oscillating":
            extra = {"arm": self.num("arm"), "pivot": self.num("pivot")}
            at, hint = "base_radius", ("a base circle the arm's roller can reach "
                                       "(|D − L| < r_b + r_f < D + L)")
        elif kind == "oscillating_flat":
            extra = {"pivot": self.num("pivot")}
            at, hint = "pivot", "a pivot farther from the cam's centre than r_b (D > r_b)"
        else:
            extra = {"offset": self.num("offset", 0.0, positive=False)}
            at = "offset" if "offset" in self.raw else "base_radius"
            hint = "|offset| < r_b + r_f"
        try:
            prof = cam_profile(motion, self.num("base_radius"), kind, roller_radius=rf,
                               pressure_limit_deg=limit, **extra)
        except InputError as exc:
            raise self.err(f"[cam] the cam cannot be built: {exc}", at, expected=hint) from None
        for c in prof.checks:
            if not c.ok:
                what = (f"pressure angle {math.degrees(c.value):.4g}° beyond the limit "
                        f"{math.degrees(c.limit):.4g}°" if c.name == "pressure_angle" else
                        "undercut: the face stops turning against the cam (1 + dψ/dθ = 0), "
                        "its contact point runs off to infinity" if c.value == -math.inf else
                        f"undercut: smallest convex radius of the profile {c.value:.4g} "
                        f"{self.lk.units or 'units'} ≤ 0")
                warn(f"{self.source}: [cam] {what} at cam angle {math.degrees(c.theta):.4g}°",
                     MechcircWarning)


def parse_cam(text: str, source: str, raw, linkage: Linkage) -> CamLinkage:
    """The ``[cam]`` table: the follower's law, the linkage made to follow it, the cam's checks.

    Parameters
    ----------
    text : str
    source : str
        File name, for errors.
    raw : dict
        The ``[cam]`` table.
    linkage : Linkage

    Returns
    -------
    CamLinkage

    Raises
    ------
    NetlistError
        A bad key or value, an unknown follower type, a follower that is not the
        only crank (oscillating) or not a block on a fixed guide (translating),
        a law whose angles do not fit a turn, a cam geometry that cannot be
        built — at the key.
    """
    if not isinstance(raw, dict):
        raise located(text, source, "cam must be a table [cam]", None, "cam")
    check_keys(text, source, Table("cam", CAM_KEYS), raw)
    r = _CamReader(text, source, raw, linkage)
    kind = r.kind()
    follower, slider = r.follower(kind)
    motion, key = r.motion(kind)
    r.checks(kind, motion)
    fields = {f.name: getattr(linkage, f.name) for f in dataclasses.fields(Linkage)}
    return CamLinkage(**fields, cam=motion, x0=float(motion.evaluate(0.0)[0]), key=key,
                      follower=follower, slider=slider, **r.contact(kind))

