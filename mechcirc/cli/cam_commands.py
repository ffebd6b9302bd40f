"""The ``cam`` sub-command: a disc cam's profile, pressure angle, curvature and undercut."""

from __future__ import annotations

import math

from ..errors import InputError
from ..units import UnitError, in_unit_of
from ._common import (MAX_LENGTH, add_handler, add_output_option, check_output_paths, command,
                      count, print_json, real, refuse_ignored, warning_lines)

_LAWS = ("harmonic", "cycloidal", "modified_sine", "modified_trapezoid", "polynomial_345")
#: Cam angles in degrees, or with a unit of the one grammar (2rad).
_ANGLE = real(least=0.0, most=360.0, unit="deg", role="angle")


def _length(least: float | None = None, above: float | None = None):
    """argparse type: a length in mm, or with a unit of the one grammar (40mm, 4cm)."""
    return real(least=least, above=above, most=MAX_LENGTH, unit="mm", role="length")


def _stroke(text: str) -> str:
    """``--stroke``: checked as a length or an angle (the follower decides which: _motion)."""
    real(most=MAX_LENGTH, role="displacement")(text)
    return text


@command("cam", "disc cam profile, pressure angle, radius of curvature, undercut; CSV/SVG",
         "Profile of a disc cam turning counter-clockwise and driving a translating roller, a "
         "translating flat face, an oscillating roller or an oscillating flat face (through the "
         "arm's pivot) follower, from a motion law cycle (rise, dwell, return, and the rest of the "
         "turn dwelling at the bottom) or a lift table. Lengths in mm, angles in degrees, or with "
         "a unit (4cm, 2rad); the stroke and a table's lift are in mm, or degrees of the arm for "
         "--follower oscillating and oscillating_flat. See docs/kinematics.md, 'Cams'.",
         "Example: mechcirc cam --law cycloidal --rise 120 --dwell 60 --return 120 --stroke 20 "
         "--base-radius 40 --roller-radius 10 -o profile.csv --svg profile.svg")
def register(p) -> None:
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--law", choices=_LAWS, help="motion law of the rise (and the return)")
    src.add_argument("--motion", metavar="CSV",
                     help="lift table: columns angle_deg,displacement over one turn")
    for name, what in (("rise", "rise"), ("dwell", "dwell at the top (default 0)"),
                       ("return", "return")):
        p.add_argument(f"--{name}", type=_ANGLE, metavar="DEG",
                       help=f"cam angle of the {what} [deg]")
    p.add_argument("--low-dwell", type=_ANGLE, metavar="DEG",
                   help="dwell at the bottom [deg] (default: the rest of 360°; given, the four "
                        "angles must sum to 360°)")
    p.add_argument("--return-law", choices=_LAWS, help="law of the return (default --law)")
    p.add_argument("--stroke", type=_stroke, metavar="H",
                   help="lift [mm; deg for an oscillating follower; or with a unit: 20mm, "
                        "2cm, 15deg] (--stroke=-20: the follower falls first)")
    p.add_argument("--base-radius", type=_length(above=0.0), required=True, metavar="MM",
                   help="base circle radius r_b [mm]")
    p.add_argument("--follower", choices=("roller", "flat", "oscillating", "oscillating_flat"),
                   default="roller", help="translating roller (default), translating flat "
                   "face, oscillating roller, oscillating flat face (needs --pivot)")
    p.add_argument("--roller-radius", type=_length(least=0.0), metavar="MM",
                   help="roller radius r_f [mm] (0: a knife edge)")
    p.add_argument("--offset", type=_length(), metavar="MM",
                   help="offset e of a translating follower's axis [mm] (default 0; a "
                        "positive one lowers the rise's pressure angle, the cam turning "
                        "counter-clockwise; --offset=-5 for a negative one)")
    p.add_argument("--arm", type=_length(above=0.0), metavar="MM",
                   help="oscillating follower: arm length, pivot to roller centre [mm]")
    p.add_argument("--pivot", type=_length(above=0.0), metavar="MM",
                   help="oscillating follower: distance from the cam's centre to the pivot [mm]")
    p.add_argument("--pressure-limit", type=real(above=0.0, most=90.0, unit="deg", role="angle"),
                   metavar="DEG", help="largest admissible pressure angle [deg] (default 30 "
                                       "translating, 45 oscillating)")
    p.add_argument("--points", type=count(8, 1_000_000), default=721, metavar="N",
                   help="cam angles from 0 to 360° inclusive (default 721)")
    add_output_option(p, "write the profile as CSV")
    p.add_argument("--svg", metavar="SVG", help="draw the profile as SVG (mm)")
    add_handler(p, cmd_cam)


def _motion(args):
    from ..motion_laws import cam_cycle, read_motion_table

    osc = args.follower.startswith("oscillating")
    scale, unit = (math.pi / 180, "°") if osc else (1.0, " mm")
    refuse_ignored(args, {f"--{o}": (not args.motion, "a --law cycle, not to a --motion table", "")
                          for o in ("rise", "dwell", "return", "low-dwell", "stroke", "return-law")})
    if args.motion:
        m = read_motion_table(args.motion)
        note = (f" (periodic spline; its slope uncertain by ~{m.error:.1g} of its peak)"
                if math.isfinite(m.error) else " (periodic spline; under 9 rows: no error "
                "estimate)")
        return m.scaled(scale), f"lift table {args.motion}{note}"
    if missing := [o for o in ("rise", "return", "stroke") if getattr(args, o) is None]:
        raise InputError(f"--law {args.law} needs --{missing[0]} (a law cycle takes --rise, "
                         "--return and --stroke; --dwell defaults to 0)")
    dwell = args.dwell or 0.0
    ret = getattr(args, "return")       # (a keyword: no args.return)
    total = args.rise + dwell + ret
    if args.low_dwell is not None and abs(total + args.low_dwell - 360.0) > 1e-9:
        raise InputError(f"rise + dwell + return + low dwell = {args.rise:g} + {dwell:g} + "
                         f"{ret:g} + {args.low_dwell:g} = {total + args.low_dwell:g}°, "
                         "not 360° (one turn)")
    try:
        stroke = in_unit_of(args.stroke, "angle" if osc else "length", "deg" if osc else "mm")
        m = cam_cycle(args.law, args.rise, dwell, ret, stroke * scale, args.return_law)
    except UnitError as exc:
        raise InputError(f"--stroke {args.stroke}: the stroke of --follower {args.follower} is "
                         + ("the arm's swing, an angle" if osc else "a lift, a length")
                         + f" ({exc.expected}; no unit means {'deg' if osc else 'mm'})") from None
    except ValueError as exc:
        raise InputError(str(exc)) from None
    law = f" ({args.return_law})" if args.return_law else ""
    return m, (f"{args.law} rise {args.rise:g}° dwell {dwell:g}° return {ret:g}°{law}, "
               f"low dwell {360 - total:g}°, stroke {stroke:g}{unit}")


def _mm(v: float) -> str:
    """A length for the report: 4 decimals, or 6 digits when that would be very long."""
    return f"{v:.4f}" if abs(v) < 1e6 else f"{v:.6g}"


def cmd_cam(args) -> int:
    from ..kinematics.cam import cam_profile, save_profile

    _check_args(args)
    motion, what = _motion(args)
    cam = cam_profile(motion, args.base_radius, args.follower,
                      roller_radius=args.roller_radius or 0.0, offset=args.offset or 0.0,
                      arm=args.arm or 0.0, pivot=args.pivot or 0.0, points=args.points,
                      pressure_limit_deg=args.pressure_limit)
    warnings = _warnings(cam)
    save_profile(cam, args.output, args.svg)
    if args.json:
        print_json(_as_json(cam, motion, warnings))
    else:
        _report(cam, what, [p for p in (args.output, args.svg) if p])
    warning_lines(warnings)
    return 0


def _check_args(args) -> None:
    """The output paths, and the options each follower needs or does not take."""
    check_output_paths(args.output, args.svg, table="a CSV table", drawn_by="--svg SVG")
    if args.svg and not args.svg.lower().endswith(".svg"):
        raise InputError(f"--svg {args.svg}: the drawing is SVG; give a file ending in .svg")
    if args.follower not in ("flat", "oscillating_flat") and args.roller_radius is None:
        raise InputError(f"{'an' if args.follower[0] in 'aeiou' else 'a'} {args.follower} "
                         "follower needs --roller-radius (0 for a knife edge)")
    if args.follower == "oscillating" and (args.arm is None or args.pivot is None):
        raise InputError("an oscillating follower needs --arm and --pivot")
    if args.follower == "oscillating_flat" and args.pivot is None:
        raise InputError("an oscillating_flat follower needs --pivot (the face turns about it)")
    f = args.follower
    osc = f.startswith("oscillating")
    rules = (("--roller-radius", f in ("roller", "oscillating"), "a roller"),
             ("--arm", f == "oscillating", "an oscillating roller"),
             ("--pivot", osc, "an oscillating"), ("--offset", not osc, "a translating"))
    refuse_ignored(args, {key: (takes, f"{which} follower, not --follower {f}", "")
                          for key, takes, which in rules})


def _warnings(cam) -> list:
    """A failed pressure-angle or undercut check, in words, with its value."""
    phi, cut = cam.check("pressure_angle"), cam.check("undercut")
    warnings = []
    if not phi.ok:
        warnings.append(f"pressure angle {math.degrees(phi.value):.4f}° at θ = "
                        f"{math.degrees(phi.theta):.3f}° exceeds the limit "
                        f"{math.degrees(phi.limit):g}° (a larger base circle, a longer rise or "
                        "an offset lowers it)")
    if not cut.ok and cut.value == -math.inf:       # the oscillating face turns back
        warnings.append(f"undercut at θ = {math.degrees(cut.theta):.3f}°: the face stops "
                        "turning against the cam there (1 + dψ/dθ = 0), so its contact point "
                        "runs off to infinity; the cam cannot give this motion (a longer "
                        "return or rise, or a smaller swing)")
    elif not cut.ok:
        why = (f"the roller radius {cam.roller_radius:g} mm exceeds the pitch curve's radius "
               f"of curvature {cut.value + cam.roller_radius:.4g} mm there, so the profile's "
               if cam.rho_pitch is not None else "the profile's radius of curvature "
               + ("r_b + s + s'' " if cam.follower == "flat" else ""))
        warnings.append(f"undercut at θ = {math.degrees(cut.theta):.3f}°: {why}is "
                        f"{cut.value:.4g} mm; the cam cannot give this motion (enlarge the "
                        "base circle or lengthen the rise)")
    return warnings


def _as_json(cam, motion, warnings) -> dict:
    """The ``--json`` document: the cam, its checks, warnings and profile.

    ``turned_back`` is true where an oscillating flat face turns back (the undercut
    check at −∞, its angle in ``checks``): no cam gives that motion, so ``profile``
    is null, as the export refuses it, rather than the envelope's points running off
    to infinity.
    """
    import numpy as np

    turned_back = cam.check("undercut").value == -math.inf
    return {
        "motion": motion.spec, "follower": cam.follower, "base_radius": cam.base_radius,
        "roller_radius": cam.roller_radius, "offset": cam.offset, "arm": cam.arm,
        "pivot": cam.pivot, "unit": "mm",
        "checks": {c.name: {"ok": c.ok, "theta_deg": math.degrees(c.theta),
                            **({"value_deg": math.degrees(c.value),
                                "limit_deg": math.degrees(c.limit)}
                               if c.name == "pressure_angle" else {"value": c.value})}
                   for c in cam.checks},
        "warnings": warnings, "turned_back": turned_back,
        "profile": None if turned_back else {
            "theta_deg": np.degrees(cam.theta), "x": cam.x, "y": cam.y,
            "pressure_angle_deg": np.degrees(cam.pressure_angle), "radius_of_curvature": cam.rho}}


def _report(cam, what: str, written: list) -> None:
    """The text report: the follower, the worst pressure angle and curvature, the files."""
    phi, cut = cam.check("pressure_angle"), cam.check("undercut")
    kind = {"roller": f"translating roller r_f = {cam.roller_radius:g} mm, offset "
                      f"{cam.offset:g} mm",
            "flat": "translating flat face",
            "oscillating": f"oscillating roller r_f = {cam.roller_radius:g} mm, arm "
                           f"{cam.arm:g} mm, pivot {cam.pivot:g} mm",
            "oscillating_flat": f"oscillating flat face, pivot {cam.pivot:g} mm"}[cam.follower]
    print(f"cam: {what}")
    print(f"  follower: {kind}; base circle r_b = {cam.base_radius:g} mm; "
          f"{cam.theta.size} cam angles")
    print(f"  pressure angle: max |φ| = {math.degrees(phi.value):.4f}° at θ = "
          f"{math.degrees(phi.theta):.3f}° (limit {math.degrees(phi.limit):g}°"
          + ("" if phi.ok else ", EXCEEDED") + ")")
    pitch = "" if cam.rho_pitch is None else \
        f" (pitch curve {_mm(cut.value + cam.roller_radius)} mm)"
    print(f"  radius of curvature: smallest convex {_mm(cut.value)} mm at θ = "
          f"{math.degrees(cut.theta):.3f}°{pitch}")
    if cam.follower == "flat":       # the contact runs along the face by x = s'
        print(f"  contact on the face from x = {_mm(cam.dlift.min())} to "
              f"{_mm(cam.dlift.max())} mm of its axis")
    print(f"  undercut: {'no' if cut.ok else 'YES'}")
    if written:
        print(f"  wrote {', '.join(written)}")
