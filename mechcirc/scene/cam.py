"""A disc cam on the main shaft driving an oscillating follower in a scene (``[cam]``).

The follower is the linkage's crank (its arm pivoted to the frame); the cam
replaces its uniform turning by the law x(θ) of a
:class:`~mechcirc.motion_laws.Motion`: at cam angle θ = Ω t the arm is turned
by x(θ) − x(0) from the pose.  The linkage is solved at that arm angle with the
arm turning at Ω, and the rates are rescaled by the chain rule, exactly:
with q̇ₛ = J Ω and q̈ₛ = J′ Ω² the solver's rates,

    q̇ = q̇ₛ x′(θ),      q̈ = q̈ₛ x′(θ)² + q̇ₛ Ω x″(θ).

A rate below :data:`DWELL` of the peak is the round-off of a dwell and is set
to 0.  Everything that calls :meth:`Linkage.motion` or :meth:`Linkage.solve` (the
circuit at θ, the cycle map, the time-domain tables) then follows the cam.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..kinematics.linkage import Linkage

__all__ = ["CamLinkage", "parse_cam", "aligned_points", "DWELL"]

#: |x′(θ)| at most this fraction of its peak is the round-off of a dwell's 0: the
#: follower is at rest there (a law's x′ is exact to ~1e-16 of its peak).
DWELL = 1e-13


@dataclass(frozen=True, eq=False)
class CamLinkage(Linkage):
    """A :class:`Linkage` whose first crank (the follower's arm) follows a cam.

    Attributes
    ----------
    cam : Motion
        The arm's rotation x(θ) [rad] over one turn of the cam shaft.
    x0 : float
        x(0): the pose is the arm at cam angle 0.
    key : tuple
        What identifies the cam, for the scene's memoised tables.
    """

    cam: object = None
    x0: float = 0.0
    key: tuple = ()

    @cached_property
    def peak_rate(self) -> float:
        """max |x′(θ)| over the turn (on 4096 angles) [rad per rad]."""
        return float(np.max(np.abs(self.cam.evaluate(np.linspace(0, 2 * np.pi, 4097))[1])))

    def motion(self, theta, *, max_step_deg: float = 2.0, method: str = "auto"):
        """Kinematics at cam angles ``theta`` [rad] (the arm at x(θ) − x(0)); see the module."""
        th = np.asarray(theta, dtype=float).reshape(-1)
        x, x1, x2 = self.cam.evaluate(th)
        x1 = np.where(np.abs(x1) <= DWELL * self.peak_rate, 0.0, x1)    # a dwell: at rest
        m = Linkage.motion(self, x - self.x0, max_step_deg=max_step_deg, method=method)
        w = self.cranks[0].omega
        qd = m.qdot * x1[:, None]
        qdd = m.qddot * (x1 * x1)[:, None] + m.qdot * (w * x2)[:, None]
        return dataclasses.replace(m, theta=th, t=th / w, qdot=qd, qddot=qdd,
                                   parts=m.parts * x1[:, None, None])


def aligned_points(cam, n: int) -> int:
    """The fewest intervals per turn, from ``n`` to 4n, that put a node on every joint of the
    ``cam``'s pieces (where a derivative of x jumps; a quintic Hermite table across one
    is ~60 times less accurate), else ``n``."""
    u = np.asarray(cam.start, dtype=float) / (2 * np.pi)
    for k in range(n, 4 * n + 1):
        if np.all(np.abs(u * k - np.round(u * k)) <= 1e-9):
            return k
    return n


#: The ``[cam]`` table's keys (see docs/scenes.md, "A cam drives the scene").
CAM_KEYS = {"follower": "the follower's arm: the first crank of [[cranks]]",
            "law": "a motion law of mechcirc.motion_laws.LAWS", "rise": "[deg]",
            "dwell": "[deg], default 0", "return": "[deg]", "return_law": "default: law",
            "stroke_deg": "the arm's swing [deg], nonzero",
            "table": "CSV angle_deg,displacement: the arm's angle [deg] (instead of a law)",
            "base_radius": "r_b [units], for the pressure-angle and undercut checks",
            "roller_radius": "r_f [units], default 0", "arm": "L [units]",
            "pivot": "D, arm pivot to cam centre [units]",
            "pressure_limit_deg": "default 45"}


def parse_cam(text: str, source: str, raw, linkage: Linkage) -> CamLinkage:
    """The ``[cam]`` table: the arm's law, the linkage made to follow it, the cam's checks.

    Raises
    ------
    NetlistError
        A bad key or value, a follower that is not the only crank, a law whose
        angles do not fit a turn, a cam geometry that cannot be built — at the key.
    """
    import math
    import os

    from ..errors import InputError, MechcircWarning, warn
    from ..motion_laws import LAWS, cam_cycle, read_motion_table
    from ..sources import Table, brief, check_keys, finite_number, located

    def err(message, key, expected=None, value=None):
        return located(text, source, message, "cam", key, value=value, expected=expected)

    if not isinstance(raw, dict):
        raise located(text, source, "cam must be a table [cam]", None, "cam")
    check_keys(text, source, Table("cam", CAM_KEYS), raw)
    cranks = linkage.cranks
    f = raw.get("follower")
    if len(cranks) != 1 or f != cranks[0].link:
        raise err(f"[cam] follower {brief(f)} must be the linkage's only crank (the arm the "
                  f"cam swings; its omega is the cam shaft's speed)", "follower" if "follower"
                  in raw else next(iter(raw), "follower"),
                  expected=f'follower = "{cranks[0].link}" with one [[cranks]] entry',
                  value=f if isinstance(f, str) else None)
    if not cranks[0].omega > 0:
        raise err(f"[cam] the cam shaft turns at omega = {cranks[0].omega:g} rad/s (the "
                  f"[[cranks]] omega of {f!r}); a cam needs omega > 0", "follower",
                  expected="omega > 0 in [[cranks]]", value=f)

    def num(key, default=None, positive=True, allow_zero=False):
        v = raw.get(key, default)
        if not finite_number(v) or (positive and (v < 0 or (v == 0 and not allow_zero))):
            raise err(f"[cam] {key} must be a finite number{' > 0' if positive else ''}"
                      f"{' or 0' if allow_zero else ''}, got {brief(v)}",
                      key if key in raw else "follower", expected=f"{key} = {CAM_KEYS[key]}")
        return float(v)

    if ("table" in raw) == ("law" in raw):
        raise err("[cam] needs exactly one of law = … (with rise, dwell, return, stroke_deg) "
                  "or table = \"FILE.csv\"", "law" if "law" in raw else "follower",
                  expected='law = "cycloidal" or table = "lift.csv"')
    if "law" in raw:
        for key in ("law", "return_law"):
            if key in raw and raw[key] not in LAWS:
                raise err(f"[cam] {key} {brief(raw[key])} is not a motion law", key,
                          expected=" | ".join(LAWS), value=raw[key]
                          if isinstance(raw[key], str) else None)
        rise, ret = num("rise"), num("return")
        dwell, stroke = num("dwell", 0.0, allow_zero=True), num("stroke_deg", positive=False)
        try:
            motion = cam_cycle(raw["law"], rise, dwell, ret, math.radians(stroke),
                               raw.get("return_law"))
        except ValueError as exc:
            key = "stroke_deg" if "stroke" in str(exc) else "rise"
            raise err(f"[cam] {exc}".replace("stroke=", "stroke [rad] = "), key,
                      expected="rise + dwell + return ≤ 360 degrees, stroke_deg ≠ 0") from None
        key = ("law", raw["law"], raw.get("return_law"), rise, dwell, ret, stroke)
    else:
        path = raw["table"]
        if not isinstance(path, str):
            raise err(f"[cam] table must be a file name, got {brief(path)}", "table")
        if source != "<string>" and not os.path.isabs(path):
            path = os.path.join(os.path.dirname(source), path)
        motion = read_motion_table(path).scaled(math.pi / 180.0)
        key = ("table", os.path.abspath(path), motion.start, motion.poly, motion.sine)
    x0 = float(motion.evaluate(0.0)[0])
    if "base_radius" in raw:
        from ..kinematics.cam import cam_profile

        try:
            prof = cam_profile(motion, num("base_radius"), "oscillating",
                               roller_radius=num("roller_radius", 0.0, allow_zero=True),
                               arm=num("arm"), pivot=num("pivot"),
                               pressure_limit_deg=num("pressure_limit_deg", 45.0))
        except InputError as exc:
            raise err(f"[cam] the cam cannot be built: {exc}", "base_radius",
                      expected="a base circle the arm's roller can reach (|D − L| < r_b + "
                      "r_f < D + L)") from None
        for c in prof.checks:
            if not c.ok:
                what = (f"pressure angle {math.degrees(c.value):.4g}° beyond the limit "
                        f"{math.degrees(c.limit):.4g}°" if c.name == "pressure_angle" else
                        f"undercut: smallest convex radius of the profile {c.value:.4g} "
                        f"{linkage.units or 'units'} ≤ 0")
                warn(f"{source}: [cam] {what} at cam angle {math.degrees(c.theta):.4g}°",
                     MechcircWarning)
    elif any(k in raw for k in ("roller_radius", "arm", "pivot", "pressure_limit_deg")):
        raise err("[cam] the geometry checks need base_radius", next(
            k for k in ("roller_radius", "arm", "pivot", "pressure_limit_deg") if k in raw),
            expected="base_radius = r_b with arm and pivot")
    fields = {f.name: getattr(linkage, f.name) for f in dataclasses.fields(Linkage)}
    return CamLinkage(**fields, cam=motion, x0=x0, key=key)
