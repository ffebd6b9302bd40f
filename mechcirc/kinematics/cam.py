"""Disc cams: profile, pressure angle, radius of curvature and undercut, in closed form.

A disc cam turns counter-clockwise about its centre O by the cam angle θ; the
follower's motion x(θ) is a :class:`~mechcirc.motion_laws.Motion` (a law cycle
from :func:`~mechcirc.motion_laws.cam_cycle` or a table), which gives x, dx/dθ
and d²x/dθ² exactly.  The lift s = x − min x is measured from the motion's
lowest point, where the follower touches the base circle r_b (the cam's
smallest circle): a negative stroke or a table of absolute positions needs no
shifting.  Three followers:

``roller``
    Translating roller of radius r_f on an axis parallel to y at x = e (the
    offset).  Its centre is B = (e, d + s) in the fixed frame, with
    d = √((r_b + r_f)² − e²) and s the lift: at s = 0 it touches the base
    circle r_b.
``flat``
    Translating flat face perpendicular to its axis, touching the base circle
    at s = 0 (the offset moves the stem, not the profile).
``oscillating``
    Roller of radius r_f at the end of an arm of length L pivoted at
    A = (D, 0) (D, the pivot distance, = |OA|).  The arm angle ψ (between A→O
    and A→B) is ψ₀ + s [rad], with r_b + r_f = |OB| at ψ₀; the roller centre
    is B = (D − L cos ψ, L sin ψ) and s > 0 moves it away from O.

In the cam's frame a fixed-frame point B(θ) is P = R(−θ)B, so with J the
quarter turn, P' = R(−θ)(B' − JB) and P'' = R(−θ)(B'' − 2JB' − B): the pitch
curve (the roller centre's path), its unit normal and its curvature follow in
closed form for both roller followers, and the profile is the envelope of the
roller circle, P − r_f n (n the outward normal).  The pressure angle φ is the
angle between n (the line of the contact force) and the velocity of the
roller centre; it reduces to

    translating roller:   tan φ = (s' − e) / (s + √((r_b + r_f)² − e²))
    oscillating roller:   tan φ = (L (1 + ψ') − D cos ψ) / (D sin ψ)

(primes: d/dθ; the cam turning counter-clockwise), the first the textbook
form (Norton, *Design of Machinery*, ch. 8, sizing the cam; Rothbart, *Cam
Design Handbook*), the second from the geometry above.  The radius of
curvature of the pitch curve is ρ = −|P'|³ / (P' × P'') (the pitch curve runs
clockwise in the cam's frame), signed + where it is convex
(for e = 0 it is Norton's (R² + s'²)^{3/2} / (R² + 2s'² − R s''), R = r_b + r_f
+ s), and the profile's is ρ − r_f.  A roller undercuts (the envelope loops)
where the pitch curve is convex with 0 < ρ < r_f.  The flat face touches the
cam at x = s' along the face (the fixed frame), so the profile is
R(−θ)(s', r_b + s), of radius of curvature r_b + s + s'', and undercuts where
that is ≤ 0; its pressure angle is 0.

``oscillating_flat``
    A flat face on an arm pivoted at A = (D, 0), the face's line through the
    pivot, at the angle ψ = ψ₀ + s from A→O (sin ψ₀ = r_b / D: at s = 0 it
    touches the base circle).  In the cam's frame the face is the line
    m·X = p with m at the angle φ = π/2 − ψ − θ and p = D sin ψ, the face's
    distance from O; the profile is its envelope, X = p m + (dp/dφ) m⊥, of
    radius of curvature ρ = p + d²p/dφ², with dφ/dθ = −(1 + s′):

        ρ = p + (p_θθ φ_θ − p_θ φ_θθ) / φ_θ³,   p_θ = D cos ψ s′,
        p_θθ = D (cos ψ s″ − sin ψ s′²),  φ_θ = −(1 + s′),  φ_θθ = −s″,

    an undercut where ρ ≤ 0 (or where 1 + s′ = 0, the face's normal turning
    back).  The contact point moves with the arm perpendicular to the face (the
    face passes through the pivot), so the pressure angle is 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..errors import InputError, unknown_name
from ..sources import did_you_mean, real_number, summary_repr

__all__ = [
    "FOLLOWERS",
    "CamCheck",
    "CamProfile",
    "cam_profile",
    "profile_csv",
    "profile_svg",
    "save_profile",
]

#: The follower kinds a scene's ``[cam]`` takes; :func:`cam_profile` also takes
#: ``"oscillating_flat"`` (a flat face on a pivoted arm).
FOLLOWERS = ("roller", "flat", "oscillating")
_FACES = ("flat", "oscillating_flat")
#: Default pressure-angle limits [deg]: translating, oscillating (Norton, ch. 8).
PRESSURE_LIMIT_DEG = {"roller": 30.0, "flat": 30.0, "oscillating": 45.0,
                      "oscillating_flat": 45.0}


@dataclass(frozen=True)
class CamCheck:
    """One design check: the worst value over the turn, where, against what limit.

    Attributes
    ----------
    name : str
        ``"pressure_angle"`` (value: max |φ| [rad]) or ``"undercut"`` (value:
        the smallest radius of curvature of the convex profile, ρ − r_f for a
        roller or r_b + s + s'' for a flat face; undercut where it is ≤ 0).
    ok : bool
        Whether the check passes.
    value, theta : float
        The worst value and the cam angle [rad] where it occurs.
    limit : float
        The largest admissible |φ| [rad], or 0 for the undercut check.
    """

    name: str
    ok: bool
    value: float
    theta: float
    limit: float


@dataclass(frozen=True)
class CamProfile:
    """A disc cam over one turn: pitch curve, profile, pressure angle, curvature, checks.

    Plain data (numpy arrays and floats): it pickles.  Coordinates are in the
    cam's frame (the frame turning with it), the cam angle increasing from 0
    to 2π over ``theta`` (first and last point the same).

    Attributes
    ----------
    follower : str
        One of :data:`FOLLOWERS`.
    base_radius, roller_radius, offset, arm, pivot : float
        r_b, r_f, e, L and D (the last two 0 for a translating follower).
    theta, lift, dlift, ddlift : ndarray
        Cam angle [rad]; the lift s = x − min x and its derivatives ds/dθ,
        d²s/dθ² (length, or rad for the oscillating arm).
    pitch_x, pitch_y : ndarray or None
        The roller centre's path (None for a flat face).
    x, y : ndarray
        The cam profile.
    pressure_angle : ndarray
        φ [rad], signed: + where s' > e (a translating follower's rise with e = 0).
    rho_pitch : ndarray or None
        Radius of curvature of the pitch curve (+ convex; ±inf where straight).
    rho : ndarray
        Radius of curvature of the profile (+ convex).
    checks : tuple of CamCheck
        ``pressure_angle`` and ``undercut``, over the whole turn (the extremes
        are refined between the grid points).
    """

    __repr__ = summary_repr

    follower: str
    base_radius: float
    roller_radius: float
    offset: float
    arm: float
    pivot: float
    theta: np.ndarray
    lift: np.ndarray
    dlift: np.ndarray
    ddlift: np.ndarray
    pitch_x: np.ndarray | None
    pitch_y: np.ndarray | None
    x: np.ndarray
    y: np.ndarray
    pressure_angle: np.ndarray
    rho_pitch: np.ndarray | None
    rho: np.ndarray
    checks: tuple

    def check(self, name: str) -> CamCheck:
        """The check called ``name`` (``"pressure_angle"`` or ``"undercut"``)."""
        for c in self.checks:
            if c.name == name:
                return c
        raise unknown_name(name, [c.name for c in self.checks], "check")


def _geometry(motion, theta, follower, rb, rf, e, arm, pivot, x0):
    """Everything at ``theta``: (s, s', s'', P or None, C, φ, κ_pitch or None, ρ_profile)."""
    x, ds, dds = motion.evaluate(theta)
    s = x - x0
    c, sn = np.cos(theta), np.sin(theta)

    def to_cam(u, v):                           # R(−θ)·(u, v)
        return np.array([u * c + v * sn, -u * sn + v * c])

    if follower == "flat":
        return s, ds, dds, None, to_cam(ds, rb + s), np.zeros_like(s), None, rb + s + dds
    if follower == "oscillating_flat":
        psi = math.asin(rb / pivot) + s
        p = pivot * np.sin(psi)
        p1, p2 = pivot * np.cos(psi) * ds, pivot * (np.cos(psi) * dds - np.sin(psi) * ds ** 2)
        f1, f2 = -(1.0 + ds), -dds
        with np.errstate(divide="ignore", invalid="ignore"):
            pf = p1 / f1
            rho = p + (p2 * f1 - p1 * f2) / f1 ** 3
        phi = 0.5 * math.pi - psi - theta
        m, t = np.array([np.cos(phi), np.sin(phi)]), np.array([-np.sin(phi), np.cos(phi)])
        return s, ds, dds, None, p * m + pf * t, np.zeros_like(s), None, rho
    if follower == "roller":
        d = math.sqrt((rb + rf) ** 2 - e * e)
        B, dB = np.array([np.full_like(s, e), d + s]), np.array([np.zeros_like(s), ds])
        ddB = np.array([np.zeros_like(s), dds])
        v = np.array([np.zeros_like(s), np.ones_like(s)])      # direction of the lift
    else:
        cos0 = (pivot ** 2 + arm ** 2 - (rb + rf) ** 2) / (2 * pivot * arm)
        psi = math.acos(cos0) + s
        v = np.array([np.sin(psi), np.cos(psi)])
        B = np.array([pivot - arm * v[1], arm * v[0]])
        dB, ddB = arm * ds * v, arm * dds * v + arm * ds ** 2 * np.array([v[1], -v[0]])
    T = np.array([dB[0] + B[1], dB[1] - B[0]])                  # B' − JB
    A = np.array([ddB[0] + 2 * dB[1] - B[0], ddB[1] - 2 * dB[0] - B[1]])   # B'' − 2JB' − B
    speed = np.hypot(T[0], T[1])
    kappa = -(T[0] * A[1] - T[1] * A[0]) / speed ** 3    # the pitch curve runs clockwise
    n = np.array([-T[1], T[0]]) / speed                    # outward normal, JT/|T|
    phi = np.arctan2(v[0] * n[1] - v[1] * n[0], v[0] * n[0] + v[1] * n[1])
    contact = B - rf * n
    with np.errstate(divide="ignore"):
        rho = 1.0 / kappa - rf
    return s, ds, dds, to_cam(B[0], B[1]), to_cam(contact[0], contact[1]), phi, kappa, rho


def _refine_max(f, theta, values):
    """The largest of f over the turn: the grid's best point, polished by bounded Brent."""
    from scipy.optimize import minimize_scalar

    i = int(np.argmax(values))
    best_t, best = float(theta[i]), float(values[i])
    lo, hi = theta[max(i - 1, 0)], theta[min(i + 1, theta.size - 1)]
    if hi > lo:
        r = minimize_scalar(lambda t: -f(t), bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-12})
        if -r.fun > best:
            best_t, best = float(r.x), float(-r.fun)
    return best_t, best


def cam_profile(motion, base_radius: float, follower: str = "roller", *,
                roller_radius: float = 0.0, offset: float = 0.0, arm: float = 0.0,
                pivot: float = 0.0, points: int = 721,
                pressure_limit_deg: float | None = None) -> CamProfile:
    """The profile of a disc cam driving ``follower`` with lift ``motion``, and its checks.

    Parameters
    ----------
    motion : Motion
        The follower's motion x(θ) [length; rad if ``oscillating``] of the cam angle θ (cam turning
        counter-clockwise); its lowest point on the grid of ``points`` touches the base circle.
    base_radius : float
        r_b > 0, the cam's smallest radius, where x is least.
    follower : {"roller", "flat", "oscillating", "oscillating_flat"}
        See the module text for the geometry of each.
    roller_radius : float
        r_f ≥ 0 (a knife edge at 0); ignored for the flat faces.
    offset : float
        e, the translating roller's axis from O (|e| < r_b + r_f).
    arm, pivot : float
        L and D of the oscillating follower, |D − L| < r_b + r_f < D + L; the
        oscillating flat face takes D > r_b only.
    points : int
        Number of cam angles from 0 to 360° inclusive (≥ 8).
    pressure_limit_deg : float, optional
        Largest admissible |φ| [deg]; default 30 (translating) or 45 (oscillating).

    Returns
    -------
    CamProfile

    Raises
    ------
    InputError
        A radius ≤ 0 (or r_f < 0), a geometry that cannot be assembled (the
        follower's axis missing the base circle, an arm that cannot reach it
        or a lift that swings it through the line AO), or ``points`` < 8.

    Examples
    --------
    >>> from mechcirc.motion_laws import cam_cycle
    >>> cam = cam_profile(cam_cycle("cycloidal", 120, 60, 120, 20.0), 40.0,
    ...                   roller_radius=10.0)
    >>> round(math.degrees(cam.check("pressure_angle").value), 4)
    17.8466
    """
    rb, rf, e, arm, pivot, pressure_limit = _inputs(motion, follower, base_radius, roller_radius,
                                                    offset, arm, pivot, points, pressure_limit_deg)
    theta = np.linspace(0.0, 2 * math.pi, int(points))
    geo = partial(_geometry, motion, follower=follower, rb=rb, rf=rf, e=e, arm=arm, pivot=pivot,
                  x0=float(np.min(motion.evaluate(theta)[0])))    # of the cam angle(s) t
    s, ds, dds, P, C, phi, kappa, rho = geo(theta)
    if follower.startswith("oscillating"):        # the flat face: r_f = L = 0 (_inputs)
        _check_swing(theta, s, rb + rf, arm, pivot)
    checks = _checks(geo, theta, follower, phi, kappa, rho, rf, pressure_limit)
    return CamProfile(follower, rb, rf, e, float(arm), float(pivot), theta, s, ds, dds,
                      None if P is None else P[0], None if P is None else P[1], C[0], C[1],
                      phi, None if follower in _FACES else rho + rf, rho, checks)


def _inputs(motion, follower, base_radius, roller_radius, offset, arm, pivot, points,
            pressure_limit_deg):
    """The checked (r_b, r_f, e, L, D, pressure limit [rad]) of :func:`cam_profile`."""
    known = FOLLOWERS + ("oscillating_flat",)
    if follower not in known:
        raise InputError(f"unknown follower {follower!r}; expected one of {', '.join(known)}"
                         f"{did_you_mean(str(follower), known)}")
    if getattr(motion, "period", None) != 2 * math.pi:
        raise InputError("the motion must be a Motion over one turn of the cam (period 2π; "
                         "build it with cam_cycle, motion_table or read_motion_table)")
    values = {"base radius": base_radius, "roller radius": roller_radius, "offset": offset,
              "arm": arm, "pivot": pivot}
    for name, val in values.items():
        if not (real_number(val) and math.isfinite(val)):
            raise InputError(f"the {name} must be a finite number, got {val!r}")
    rb, rf, e = float(base_radius), float(roller_radius), float(offset)
    if rb <= 0:
        raise InputError(f"the base radius must be > 0, got {rb:g}")
    if rf < 0:
        raise InputError(f"the roller radius must be ≥ 0, got {rf:g}")
    if int(points) < 8:
        raise InputError(f"points must be at least 8, got {points}")
    if follower in _FACES:
        rf = 0.0
    if follower == "oscillating_flat":
        arm = 0.0
        if not pivot > rb:
            raise InputError(f"the pivot distance D = {pivot:g} must be more than the base "
                             f"radius r_b = {rb:g} (the face through the pivot touches the "
                             "base circle at sin ψ₀ = r_b / D)")
    elif follower != "oscillating":
        arm = pivot = 0.0
    rp = rb + rf
    if follower == "roller" and abs(e) >= rp:
        raise InputError(f"the offset |e| = {abs(e):g} must be less than r_b + r_f = {rp:g} "
                         "(the follower's axis must cross the base circle of the roller centre)")
    if follower == "oscillating":
        if arm <= 0 or pivot <= 0:
            raise InputError(f"the arm and the pivot distance must be > 0, got arm={arm:g}, "
                             f"pivot={pivot:g}")
        if not abs(pivot - arm) < rp < pivot + arm:
            raise InputError(f"an arm of {arm:g} pivoted {pivot:g} from the cam's centre "
                             f"cannot put its roller centre at r_b + r_f = {rp:g} (needs "
                             f"{abs(pivot - arm):g} < r_b + r_f < {pivot + arm:g})")
    limit_deg = PRESSURE_LIMIT_DEG[follower] if pressure_limit_deg is None \
        else float(pressure_limit_deg)
    if not 0 < limit_deg < 90:
        raise InputError(f"the pressure-angle limit must be between 0 and 90 degrees, got "
                         f"{limit_deg:g}")
    return rb, rf, e, arm, pivot, math.radians(limit_deg)


def _check_swing(theta, s, rp, arm, pivot):
    """The oscillating arm stays on one side of the line from its pivot to the cam's centre
    (``arm`` 0: the flat face through the pivot, sin ψ₀ = r_b / D)."""
    psi0 = math.asin(rp / pivot) if arm == 0 else \
        math.acos((pivot ** 2 + arm ** 2 - rp * rp) / (2 * pivot * arm))
    psi = psi0 + s
    if np.any((psi <= 0) | (psi >= math.pi)):
        i = int(np.argmax(np.abs(psi - math.pi / 2)))
        raise InputError(f"the arm angle ψ = {math.degrees(psi[i]):.3f}° at θ = "
                         f"{math.degrees(theta[i]):.3f}° (ψ₀ = {math.degrees(psi0):.3f}° "
                         f"plus the lift) leaves (0°, 180°): the arm would swing through "
                         f"the line from its pivot to the cam's centre")


def _checks(geo, theta, follower, phi, kappa, rho, rf, pressure_limit) -> tuple:
    """The worst pressure angle and the smallest convex radius of the profile (the largest
    curvature), each refined between the grid points."""
    t_phi, phi_max = _refine_max(lambda t: abs(float(geo(np.array([t]))[5][0])), theta,
                                 np.abs(phi))
    checks = [CamCheck("pressure_angle", phi_max <= pressure_limit, phi_max, t_phi,
                       pressure_limit)]
    turn_back = _turns_back(geo, theta) if follower == "oscillating_flat" else None
    if turn_back is not None:           # ρ → ±∞ there: no least radius, the profile has none
        checks.append(CamCheck("undercut", False, -math.inf, turn_back, 0.0))
    elif follower in _FACES:
        t_rho, neg = _refine_max(lambda t: -float(geo(np.array([t]))[7][0]), theta, -rho)
        checks.append(CamCheck("undercut", -neg > 0, -neg, t_rho, 0.0))
    else:
        t_k, k_max = _refine_max(lambda t: float(geo(np.array([t]))[6][0]), theta, kappa)
        worst = 1.0 / k_max - rf if k_max > 0 else math.inf
        checks.append(CamCheck("undercut", worst > 0, worst, t_k, 0.0))
    return tuple(checks)


def _turns_back(geo, theta) -> float | None:
    """The first cam angle where the oscillating flat face stops turning against the cam,
    1 + s′ = 0 (its contact point runs off to infinity, ρ ~ 1/(1 + s′)³ changes sign),
    or None where 1 + s′ > 0 over the whole turn."""
    from scipy.optimize import brentq

    def turn(t):
        return 1.0 + float(geo(np.array([t]))[1][0])

    rate = 1.0 + geo(theta)[1]
    t_min, neg = _refine_max(lambda t: -turn(t), theta, -rate)
    if neg < 0:
        return None
    i = int(np.argmax(rate <= 0)) if np.any(rate <= 0) else int(np.searchsorted(theta, t_min))
    hi = float(theta[i]) if rate[i] <= 0 else t_min
    if i == 0 or turn(hi) == 0:
        return hi
    return float(brentq(turn, float(theta[i - 1]), hi, xtol=1e-15, rtol=4 * np.finfo(float).eps))


# ------------------------------------------------------------------ export
def _exportable(cam: CamProfile, files: str = "the profile") -> None:
    """Refuse to export a profile that does not exist: where an oscillating flat face turns
    back (1 + s′ = 0) its contact point is at infinity and the envelope is no cam."""
    cut = cam.check("undercut")
    if cut.value == -math.inf:
        raise InputError(
            f"{files} not written: the oscillating flat face turns back at θ = "
            f"{math.degrees(cut.theta):.3f}° (1 + dψ/dθ = 0), where its contact point runs off "
            "to infinity, so there is no cam profile to export (a longer return or rise, or "
            "a smaller swing, gives one)")


def profile_csv(cam: CamProfile) -> str:
    """The profile as CSV text: ``theta_deg,x,y,pressure_angle_deg,radius_of_curvature``.

    One row per cam angle (the last repeats the first, 360° on); the radius of
    curvature is the profile's (+ convex, ``inf`` where straight).  A ``#``
    line first says what cam it is.

    Parameters
    ----------
    cam : CamProfile
        Its angles, points, pressure angles and radii of curvature become the rows.

    Returns
    -------
    str
        The CSV text, each line ending in a newline.

    Raises
    ------
    InputError
        The profile does not exist: an oscillating flat face that turns back (the
        ``undercut`` check at −∞; the message gives the angle).
    """
    _exportable(cam)
    rows = [(f"# mechcirc cam: {cam.follower} follower, base radius {cam.base_radius!r}, roller "
            f"radius {cam.roller_radius!r}, offset {cam.offset!r}, arm {cam.arm!r}, pivot "
            f"{cam.pivot!r}; cam frame, cam turning counter-clockwise"),
            "theta_deg,x,y,pressure_angle_deg,radius_of_curvature"]
    cols = (np.degrees(cam.theta), cam.x, cam.y, np.degrees(cam.pressure_angle), cam.rho)
    rows += [",".join(repr(float(v)) for v in row) for row in zip(*cols)]
    return "\n".join(rows) + "\n"


def profile_svg(cam: CamProfile) -> str:
    """The profile as an SVG drawing in mm (lengths taken as mm), y up.

    A closed polyline of the profile, the base circle dashed and a cross at the
    cam's centre; the drawing's ``width``/``height`` are in mm, so it prints
    at scale 1:1.

    Parameters
    ----------
    cam : CamProfile
        Its points (taken as mm) and base circle are drawn.

    Returns
    -------
    str
        The SVG document.

    Raises
    ------
    InputError
        As :func:`profile_csv`.
    """
    _exportable(cam)
    r = max(float(np.max(np.hypot(cam.x, cam.y))), cam.base_radius)
    m = 0.05 * r
    w = 2 * (r + m)
    sw = f"{r / 200:.6g}"
    pts = " ".join(f"{x:.6f},{-y:.6f}" for x, y in zip(cam.x[:-1], cam.y[:-1]))
    c = 0.08 * r
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.6g}mm" height="{w:.6g}mm" '
            f'viewBox="{-(r + m):.6g} {-(r + m):.6g} {w:.6g} {w:.6g}">\n'
            f'  <title>mechcirc cam profile ({cam.follower} follower), mm</title>\n'
            f'  <circle cx="0" cy="0" r="{cam.base_radius:.6g}" fill="none" stroke="gray" '
            f'stroke-width="{sw}" stroke-dasharray="{r / 40:.6g} {r / 80:.6g}"/>\n'
            f'  <path d="M {-c:.6g} 0 H {c:.6g} M 0 {-c:.6g} V {c:.6g}" stroke="gray" '
            f'stroke-width="{sw}"/>\n'
            f'  <polygon points="{pts}" fill="none" stroke="black" stroke-width="{sw}"/>\n'
            f'</svg>\n')


def save_profile(cam: CamProfile, csv: str | None = None, svg: str | None = None) -> None:
    """Write the CSV and/or SVG of :func:`profile_csv`/:func:`profile_svg`, all or none.

    Each file is written to a temporary file beside it and renamed when every
    one is complete (:class:`~mechcirc.outputs.OutputSet`).

    Parameters
    ----------
    cam : CamProfile
        The profile to write.
    csv, svg : str, optional
        The file paths (None: not written).

    Raises
    ------
    InputError
        As :func:`profile_csv`, before any file is opened.
    """
    from ..outputs import OutputSet

    if csv or svg:
        _exportable(cam, " and ".join(str(p) for p in (csv, svg) if p))

    with OutputSet() as out:
        for target, text in ((csv, profile_csv), (svg, profile_svg)):
            if target:
                out.path(target).write_text(text(cam), encoding="utf-8")
