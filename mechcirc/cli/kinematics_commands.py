"""Sub-commands on kinematics: ``fourbar``, ``frame``, ``synth``, ``linkage`` (and ``cam``)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ..errors import InputError, MechcircError, NetlistError
from ..units import convert_frequency
from ._common import (MAX_LENGTH, MAX_OMEGA, Default, add_handler, add_output_option,
                      add_plot_option, check_output_paths, command, count, crank_angle, print_json,
                      print_written, real, refuse_ignored, save_figure, shaft_speed, write_outputs)

#: A crank speed > 0 [rad/s], or with a unit (``600rpm``).
crank_omega = real(above=0.0, most=MAX_OMEGA, unit="rad/s", role="omega")


def register(sub) -> None:
    """The kinematics sub-commands, each with its options."""
    from . import cam_commands

    # the cam command lives in its own module
    for add in (_register_fourbar, _register_frame, _register_synth, _register_linkage,
                cam_commands.register):
        add(sub)


@command("fourbar", "four-bar dead centres, swing, transmission angle and ε4T",
         "Closed-form four-bar analysis: Grashof class, dead centres, swing Ψ, transmission angle "
         "range and the theoretical rocker acceleration ε4T = ν·ω². Angles are measured "
         "counter-clockwise from the frame line A→D; the crank turns with θ increasing.",
         "Example: mechcirc fourbar --crank 29 --coupler 37 --rocker 188 --frame 189 --omega 100 "
         "--plot fourbar.png")
def _register_fourbar(p) -> None:
    """``fourbar``: the closed-form four-bar."""
    _add_lengths(p, "(any unit)")
    p.add_argument("--omega", type=real(most=MAX_OMEGA, unit="rad/s", role="omega"), metavar="W",
                   help="crank speed [rad/s; or with a unit: 955rpm] for ε4T = ν·ω²")
    p.add_argument("--branch", type=int, choices=(1, -1), default=1,
                   help="assembly mode (default +1; see docs/kinematics.md)")
    add_plot_option(p, "plot φ4, μ, ν (or ε4T) and γ against θ")
    add_handler(p, cmd_fourbar)


def _add_lengths(p, unit: str) -> None:
    """The four-bar's required --crank, --coupler, --rocker and --frame (``unit``: how the
    help names their unit)."""
    for name, what in (("crank", "AB"), ("coupler", "BC"), ("rocker", "CD"), ("frame", "AD")):
        p.add_argument(f"--{name}", type=real(above=0.0, most=MAX_LENGTH), required=True,
                       metavar="L", help=f"{name} length {what} {unit}")


@command("frame", "four-bar frame loading: bearing forces, shaking force and moments (eq. 7)",
         "Kineto-static analysis of a four-bar at constant crank speed (patent CN104178888 eq. 7): "
         "bearing forces at the crankshaft A and the rocking shaft D, driving torque T, shaking "
         "force S = −(F_A + F_D) on the frame and shaking moments T_a, T_d. Lengths and centres of "
         "mass in --unit (default mm), masses in kg, inertias in kg·m² about the centre of mass, "
         "forces in N. Link frames: crank x along A→B, coupler x along B→C, rocker x along D→C. "
         "The reed force is a half sine over a window of crank angle around the front dead centre, "
         "given in the rocker's frame.",
         "Example: mechcirc frame --crank 35 --coupler 57.8 --rocker 155.6 --frame 162.75 --rpm "
         "600 --mass 2,1.5,15 --rocker-com 110,30 --rocker-inertia 0.08 --reed-force=-50,-500 "
         "--reed-point 140,50 --plot frame.png -o frame.csv\n"
         "(write a value that starts with a minus with '=', as --reed-force=-50,-500)")
def _register_frame(p) -> None:
    """``frame``: the four-bar's bearing forces and shaking (eq. 7)."""
    _add_lengths(p, "[--unit]")
    p.add_argument("--unit", choices=("mm", "m"), default="mm",
                   help="length unit of lengths, centres of mass and the reed point (default mm)")
    speed = p.add_mutually_exclusive_group(required=True)
    speed.add_argument("--rpm", type=shaft_speed, metavar="N",
                       help="crank speed [rev/min]")
    speed.add_argument("--omega", type=crank_omega, metavar="W", help="crank speed [rad/s; or with a unit: 600rpm]")
    p.add_argument("--mass", type=_vector("--mass", 3, nonneg=True), default=(0.0, 0.0, 0.0),
                   metavar="M2,M3,M4", help="masses of crank, coupler, rocker (with sley and "
                   "reed) [kg] (default 0,0,0)")
    for link in ("crank", "coupler", "rocker"):
        p.add_argument(f"--{link}-com", type=_vector(f"--{link}-com", 2), default=(0.0, 0.0),
                       metavar="X,Y", help=f"{link} centre of mass in its frame [--unit] "
                       f"(--{link}-com=-5,2 when it starts with a minus)")
        p.add_argument(f"--{link}-inertia", type=real(least=0.0, most=1e30, unit="kg·m²"),
                       default=0.0, metavar="J", help=f"{link} inertia about its centre of "
                       f"mass [kg·m²]")
    p.add_argument("--reed-force", type=_vector("--reed-force", 2), default=Default((0.0, 0.0)),
                   metavar="FX,FY", help="peak cloth force on the reed, rocker frame [N] "
                   "(--reed-force=-50,-500 when it starts with a minus)")
    p.add_argument("--reed-point", type=_vector("--reed-point", 2), default=Default((0.0, 0.0)),
                   metavar="X,Y", help="where it acts, rocker frame [--unit]")
    p.add_argument("--beat-window", type=real(above=0.0, most=360.0, unit="deg"),
                   default=Default(40.0), metavar="DEG", help="crank window of the half-sine reed force [deg] "
                   "(default 40, centred on the front dead centre)")
    p.add_argument("--gravity", action="store_true", help="add gravity, 9.81 m/s² along −y")
    p.add_argument("--branch", type=int, choices=(1, -1), default=1, help="assembly mode")
    p.add_argument("--points", type=count(3, 100_000, why="one 9×9 solve per angle"),
                   default=361, metavar="N",
                   help="crank angles over one turn, 0…360° (default 361; 3…100000)")
    add_output_option(p, "write every angle's loads as CSV")
    add_plot_option(p, "shaking force polar curve and magnitude (patent Figs. 5–6), bearing "
                       "forces, torque and shaking moments")
    add_handler(p, cmd_frame)


@command("synth", "beat-up four-bar synthesis after patent CN104178888",
         "Explore crank-rockers meeting every criterion of the patent (γ at the front dead centre "
         "> 70°, γmin > 45°, |Φ2''|/|Φ1''| < 0.3, d < 180 mm, eq. (9), swing 23–26°) and rank "
         "them. Lengths in mm.",
         "Example: mechcirc synth --load medium --swing 24 --plot synth.png\n"
         "         mechcirc synth --load medium --frame 165 --swing-range 24:26 --export designs/")
def _register_synth(p) -> None:
    """``synth``: beat-up four-bar synthesis and export."""
    p.add_argument("--load", choices=("light", "medium", "heavy"), default="medium",
                   help="loom class: crank 33–34, 35–36 or 37–38 mm (default medium)")
    p.add_argument("--swing", type=real(above=0.0, most=180.0, unit="deg", role="angle"), metavar="DEG",
                   help="swing Ψ [deg] (default: explore 23–26°)")
    p.add_argument("--objective", choices=("margin", "ratio"), default="margin",
                   help="rank by the smallest criterion margin (default) or by |Φ2''|/|Φ1''|")
    p.add_argument("--limit", type=count(1, 100_000), default=10, metavar="N",
                   help="number of designs shown, distinct shapes (default 10)")
    p.add_argument("--swing-range", type=_range("--swing-range"), metavar="LO:HI",
                   help="admissible swing Ψ [deg] (default the patent's 23:26)")
    for name in ("crank", "coupler", "rocker", "frame"):
        p.add_argument(f"--{name}", type=real(above=0.0, most=MAX_LENGTH), metavar="MM",
                       help=f"hold the {name} length fixed [mm]"
                       + (" (replaces the load's range)" if name == "crank" else "")
                       + (" (not with --frame)" if name == "rocker" else ""))
    p.add_argument("--b-a-range", type=_range("--b-a-range"), default=(1.5, 8.0),
                   metavar="LO:HI", help="coupler/crank ratios explored (default 1.5:8)")
    p.add_argument("--d-a-range", type=_range("--d-a-range"), default=(1.5, 8.0),
                   metavar="LO:HI", help="frame/crank ratios explored (default 1.5:8)")
    p.add_argument("--step", type=real(above=0.0, most=1e3), default=0.05,
                   metavar="S", help="grid step of b/a and d/a (default 0.05)")
    p.add_argument("--crank-step", type=real(above=0.0, most=1e3, unit="mm"), default=0.5,
                   metavar="MM", help="grid step of the crank length (default 0.5 mm)")
    p.add_argument("--swing-step", type=real(above=0.0, most=180.0, unit="deg"),
                   default=Default(0.5), metavar="DEG", help="grid step of the swings explored without --swing (default 0.5°)")
    p.add_argument("--no-refine", action="store_true",
                   help="report the grid's designs without the continuous refinement")
    _register_synth_export(p)
    add_plot_option(p, "the best design drawn at both dead centres with its swing, beside the "
                       "transmission angle and rocker acceleration against θ")
    add_handler(p, cmd_synth)


#: ``synth --export``'s options of the exported scene: (name, what, default).
_SCENE_OPTIONS = (("sley-inertia", "I4P, sley [kg·m²]", 0.35),
                  ("rocker-inertia", "I4, rocker [kg·m²]", 0.025),
                  ("crank-inertia", "I2P, crank side [kg·m²]", 0.005),
                  ("c2", "C2, torsion rod shaft–crank [N·m/rad]", 1e5),
                  ("c4", "C4, torsion rod rocker–sley [N·m/rad]", 5e4),
                  ("k2", "k2, damping of C2 [N·m·s/rad]", 7.0),
                  ("k4", "k4, damping of C4 [N·m·s/rad]", 29.0),
                  ("beat-moment", "M0, beat-up moment [N·m], + counter-clockwise "
                   "on the sley (--beat-moment=-500 for a negative one)", 0.0),
                  ("beat-window", "α, beat-up window [deg]", 10.0))


def _register_synth_export(p) -> None:
    """``synth --export``: the directory and what goes into the exported files."""
    p.add_argument("--export", metavar="DIR",
                   help="write DIR/design_K.linkage.toml and DIR/design_K.scene.toml per design")
    p.add_argument("--omega", type=crank_omega, default=Default(100.0), metavar="W",
                   help="crank speed in exported files [rad/s] (default 100)")
    for name, what, default in _SCENE_OPTIONS:     # (inertias and rods > 0: the scene's rule)
        free, zero = name == "beat-moment", name in ("k2", "k4")
        p.add_argument(f"--{name}", type=real(least=0.0 if zero else None, most=1e30,
                                              above=None if free or zero else 0.0),
                       default=Default(default), metavar="X",
                       help=f"exported scene: {what} (default {default:g}, "
                       f"Mrázek's one-side variant 1)")


@command("linkage", "positions, velocities and conditional-stop velocities of a TOML linkage",
         "Solve a planar linkage (revolute joints and sliders) with any number of driving cranks "
         "(TOML file, see docs/kinematics.md) at a rotation θ of the first crank from the file's "
         "pose; velocities are also split into each crank's contribution with the others stopped.",
         "Example: mechcirc linkage examples/fnf_sixbar.toml --theta 30 --plot fnf.png",
         file="linkage file (.toml)")
def _register_linkage(p) -> None:
    """``linkage``: a TOML linkage at one θ."""
    p.add_argument("--theta", type=crank_angle, default=0.0, metavar="DEG",
                   help="rotation of the first crank from the pose [deg] (default 0)")
    add_plot_option(p, "draw the linkage at θ with the paths of its points")
    add_handler(p, cmd_linkage)


def _vector(option, n, *, nonneg=False, sep=",", wants=None):
    """argparse type: ``n`` finite numbers separated by commas (each as :func:`real` checks;
    ``sep`` and ``wants``, what the message says is wanted, for other forms)."""
    single = real(least=0.0 if nonneg else None, most=1e30)
    wants = wants or f"{n} numbers separated by commas (no spaces)"

    def parse(text):
        parts = text.split(sep)
        if len(parts) != n:
            raise argparse.ArgumentTypeError(f"{option} wants {wants}, got {text!r}")
        return tuple(single(x.strip()) for x in parts)
    return parse


def _range(option):
    """argparse type: ``LO:HI``, two finite numbers with LO ≤ HI."""
    pair = _vector(option, 2, sep=":", wants="LO:HI")

    def parse(text):
        lo, hi = pair(text)
        if not lo <= hi:
            raise argparse.ArgumentTypeError(f"{option}: LO must not exceed HI, got {text!r}")
        return lo, hi
    return parse


#: The longest link may be at most this many times the shortest (float64 keeps ~16 digits).
MAX_LENGTH_RATIO = 1e6


def _check_length_ratio(args) -> None:
    lengths: dict[str, float] = {n: getattr(args, n) for n in ("crank", "coupler", "rocker",
                                                             "frame")}
    lo, hi = min(lengths, key=lengths.__getitem__), max(lengths, key=lengths.__getitem__)
    if lengths[hi] > MAX_LENGTH_RATIO * lengths[lo]:
        raise InputError(f"--{hi} {lengths[hi]:g} is more than {MAX_LENGTH_RATIO:g} times "
                         f"--{lo} {lengths[lo]:g}; the four-bar's angles would be lost to "
                         "rounding (give the lengths in a unit that keeps them comparable)")


def cmd_fourbar(args) -> int:
    from ..kinematics import FourBar

    check_output_paths(plots=(args.plot,))
    _check_length_ratio(args)

    fb = FourBar(args.crank, args.coupler, args.rocker, args.frame, branch=args.branch)
    doc = fb.summary(args.omega)
    if args.plot:
        from ..kinematics.plots import plot_fourbar
        save_figure(plot_fourbar(fb, args.omega), args.plot)
    if args.json:
        return print_json(doc)
    kind = (f"change-point (Grashof equality s + l = p + q): {fb.linkage_type}"
            if fb.grashof_class == "change-point" else f"{fb.grashof_class} {fb.linkage_type}")
    print(f"four-bar a={fb.crank:g} b={fb.coupler:g} c={fb.rocker:g} d={fb.frame:g}, "
          f"branch {fb.branch:+d}: {kind}")
    if doc["branch_crossings_deg"]:
        print("  branches cross at θ = "
              + ", ".join(f"{t:g}°" for t in doc["branch_crossings_deg"])
              + " (the two assembly modes cross: the motion beyond is not fixed by the geometry)")
    if not doc["crank_rotates_fully"]:
        lo, hi = doc["crank_range_deg"]
        print(f"  the input link cannot turn fully: it rocks in θ ∈ [{lo:.3f}°, {hi:.3f}°]"
              + ("" if lo < 0 or hi > 180 else f" (and in [{360 - hi:.3f}°, {360 - lo:.3f}°])")
              + "; μ and ν grow without bound at the ends, where it locks")
    if "dead_centres" in doc:
        for dc in doc["dead_centres"]:
            print(f"  {dc['kind']:5s} dead centre: θ = {dc['theta_deg']:8.3f}°  "
                  f"φ4 = {dc['phi4_deg']:8.3f}°  ν = {dc['nu']:+.6f} 1/rad"
                  + ("" if args.omega is None else f"  ε4 = {dc['rocker_acceleration']:+.1f} rad/s²"))
        print(f"  swing Ψ = {doc['swing_deg']:.4f}°")
    tmin = ", ".join(f"{t:.2f}°" for t in doc["theta_at_gamma_min_deg"])
    tmax = ", ".join(f"{t:.2f}°" for t in doc["theta_at_gamma_max_deg"])
    print(f"  transmission angle γ: min {doc['gamma_min_deg']:.3f}° at θ = {tmin}; "
          f"max {doc['gamma_max_deg']:.3f}° at θ = {tmax}")
    if doc["nu_min"] is not None:
        print(f"  ν range: [{doc['nu_min']:+.6f}, {doc['nu_max']:+.6f}] 1/rad at θ = "
              f"{doc['theta_at_nu_min_deg']:.2f}°, {doc['theta_at_nu_max_deg']:.2f}°")
        if args.omega is not None:
            print(f"  ε4T = ν·ω² at ω = {args.omega:g} rad/s "
                  f"({convert_frequency(args.omega, 'rad/s', 'rpm'):.6g} rpm): "
                  f"[{doc['eps4T_min']:.1f}, {doc['eps4T_max']:.1f}] rad/s²")
    print_written(notes=doc["notes"])
    return 0


def cmd_frame(args) -> int:
    import numpy as np

    from ..kinematics import FourBar, LinkMass, beat_up_force, frame_loading

    check_output_paths(args.output, plots=(args.plot,), table="a CSV table")
    shaped = (not isinstance(args.reed_force, Default), "the --reed-force",
              "add --reed-force FX,FY")
    refuse_ignored(args, {"--reed-point": shaped, "--beat-window": shaped,
                          "--reed-force": (True, "", "")})     # (its default)
    a, b, c, d = args.crank, args.coupler, args.rocker, args.frame
    FourBar(a, b, c, d, branch=args.branch)     # refused (if it is) in the lengths typed
    k = 1e-3 if args.unit == "mm" else 1.0            # to metres
    fb = FourBar(a * k, b * k, c * k, d * k, branch=args.branch)
    if not fb.is_full_turn_crank_rocker:
        raise MechcircError(
            f"frame loading needs a crank-rocker whose crank turns fully; this four-bar is a "
            f"{fb.grashof_class} {fb.linkage_type} (see mechcirc fourbar)")
    omega = args.omega if args.omega is not None else convert_frequency(args.rpm, "rpm", "rad/s")
    links = {name: LinkMass(m, tuple(x * k for x in getattr(args, f"{name}_com")),
                            getattr(args, f"{name}_inertia"))
             for name, m in zip(("crank", "coupler", "rocker"), args.mass)}
    theta = np.radians(np.linspace(0.0, 360.0, args.points))
    reed = beat_up_force(fb, args.reed_force, args.beat_window)
    res = frame_loading(fb, theta, omega, reed_force=reed,
                        reed_point=tuple(x * k for x in args.reed_point),
                        gravity=(0.0, -9.81) if args.gravity else (0.0, 0.0), **links)
    cols, summary = res.columns(), res.summary()
    from ..kinematics.plots import plot_shaking

    write_outputs(args, cols.items(), lambda: plot_shaking(res),
                  f"# mechcirc frame: a={args.crank:g} b={args.coupler:g} c={args.rocker:g} "
                  f"d={args.frame:g} {args.unit}, omega={omega:.10g} rad/s; {res.CONVENTION}")
    if args.json:
        return print_json({"fourbar": {"crank": args.crank, "coupler": args.coupler,
                                       "rocker": args.rocker, "frame": args.frame,
                                       "unit": args.unit, "branch": fb.branch},
                           "omega": omega, "rpm": convert_frequency(omega, "rad/s", "rpm"),
                           "convention": res.CONVENTION, "summary": summary,
                           "columns": {n: v.tolist() for n, v in cols.items()}})
    _print_frame(args, fb, res, summary, omega)
    return 0


def _print_frame(args, fb, res, summary, omega) -> None:
    """The ``frame`` command's table: each load's extremes and where the crank is."""
    front, _ = fb.dead_centres()
    print(f"frame loading of the four-bar a={args.crank:g} b={args.coupler:g} "
          f"c={args.rocker:g} d={args.frame:g} {args.unit} at ω = {omega:.6g} rad/s "
          f"({convert_frequency(omega, 'rad/s', 'rpm'):.6g} rpm), {args.points} crank angles; front dead "
          f"centre θ = {math.degrees(front.theta):.3f}°")
    print(f"  {'quantity':34s} {'min':>11s} {'at θ':>8s} {'max':>11s} {'at θ':>8s}")
    labels = {"S_abs_N": "|S| shaking force on the frame [N]",
              "F_A_abs_N": "|F_A| crankshaft bearing [N]",
              "F_D_abs_N": "|F_D| rocking-shaft bearing [N]",
              "T_Nm": "T driving torque [N·m]", "T_a_Nm": "T_a shaking moment about A [N·m]",
              "T_d_Nm": "T_d shaking moment about D [N·m]"}
    for name, label in labels.items():
        e = summary[name]
        print(f"  {label:34s} {e['min']:11.4g} {e['theta_at_min_deg']:7.1f}° "
              f"{e['max']:11.4g} {e['theta_at_max_deg']:7.1f}°")
    print(f"  sign convention: {res.CONVENTION}.")
    print(f"  the printed eq. 7's T_d would differ from this T_d by up to "
          f"{summary['T_d_printed_minus_T_d_max_abs_Nm']:.4g} N·m here (column T_d_printed_Nm "
          f"of the CSV).")


def cmd_synth(args) -> int:
    from ..kinematics import synthesize
    from ..kinematics.synthesis_export import SceneOptions, export_designs

    check_output_paths(plots=(args.plot,))
    export_only = (bool(args.export), "the files --export writes", "add --export DIR")
    rules = {f"--{n}": export_only for n, _, _ in _SCENE_OPTIONS}
    refuse_ignored(args, {**rules, "--omega": export_only, "--swing-step": (
        args.swing is None, "the swings explored, not a fixed --swing", "")})
    if args.export and not Path(args.export).is_dir():
        raise MechcircError(f"--export {args.export}: no such folder (create it first)")
    fixed = {n: getattr(args, n) for n in ("crank", "coupler", "rocker", "frame")
             if getattr(args, n) is not None}
    scene = SceneOptions(args.omega, args.crank_inertia, args.rocker_inertia,
                         args.sley_inertia, args.c2, args.c4, args.k2, args.k4,
                         args.beat_moment, args.beat_window)
    res = synthesize(args.load, args.swing, objective=args.objective, limit=args.limit,
                     b_a_range=args.b_a_range, d_a_range=args.d_a_range, step=args.step,
                     crank_step=args.crank_step, swing_step=args.swing_step,
                     swing_range=args.swing_range, fixed=fixed, refine=not args.no_refine)
    if args.plot and res.designs:
        from ..kinematics.plots import plot_synthesis
        save_figure(plot_synthesis(res.designs[:5]), args.plot)
    exported = export_designs(res.designs, args.export, scene) if args.export and \
        res.designs else []
    if args.json:
        print_json({**res.as_dict(),
                    "exported": [{"linkage": str(lk), "scene": str(sc)} for lk, sc in exported]})
        return 0 if res.designs else 2
    if not res.designs:
        print(f"mechcirc: error: {res.message}", file=sys.stderr)
        for name, n_rejected in res.rejected.items():
            print(f"  {name:20s} rejects {n_rejected} of {res.explored}", file=sys.stderr)
        return 2
    _print_designs(args, res, exported)
    return 0


def _print_designs(args, res, exported) -> None:
    """The ``synth`` command's table of designs, then the exported files."""
    print(res.message + ".")
    what = "margin" if args.objective == "margin" else "ratio"
    print(f"{'#':>2} {'a':>6} {'b':>7} {'c':>7} {'d':>7} {'Ψ°':>6} {'γ1°':>6} {'γmin°':>6} "
          f"{'ratio':>6} {'c/a':>6} {'bound':>6} {what + ' (grid)':>16}  binding")
    for k, des in enumerate(res.designs, 1):
        cr = des.criteria
        bound = float(cr["rocker_ratio"].limit.lstrip("> "))
        print(f"{k:2d} {des.a:6.2f} {des.b:7.2f} {des.c:7.2f} {des.d:7.2f} "
              f"{des.swing_deg:6.2f} {cr['front_transmission'].value:6.2f} "
              f"{cr['min_transmission'].value:6.2f} {cr['acceleration_ratio'].value:6.3f} "
              f"{cr['rocker_ratio'].value:6.3f} {bound:6.3f} "
              f"{des.objective:7.4f} ({des.grid_objective:6.4f})  {', '.join(des.binding)}")
    lo, hi = res.swing_range
    print(f"({res.explored} crank-rockers explored; lengths in mm; ratio = |Φ2''|/|Φ1''|; "
          f"swing {lo:g}–{hi:g}°; one design per shape b/a, c/a, d/a; "
          + ("each refined from its grid point (objective at the grid point in brackets)"
             if res.refined else "grid points, not refined") + ")")
    if exported:
        print("exported:")
        for lk, sc in exported:
            print(f"  {lk}\n  {sc}")
        print("  (the scene has the sley inertia and the torsion rods; "
              + ("the beat-up moment is its [[moments]] table)" if args.beat_moment
                 else "no beat-up moment: give --beat-moment M0 for one)"))


def _load_linkage(path: str):
    """:func:`mechcirc.kinematics.load_linkage`; a scene's table in the file (an unknown
    top-level key to a linkage) is answered with the commands that read scene files."""
    import re

    from ..kinematics import load_linkage
    from ..scene.files import SCENE_TABLES

    try:
        return load_linkage(path)
    except NetlistError as exc:
        m = re.match(r"unknown top-level key '([^']*)'", exc.message)
        if m and m.group(1) in SCENE_TABLES:
            exc.message += (f"; [{m.group(1)}] is a table of a scene: 'mechcirc scene {path} "
                            "--theta DEG' or 'mechcirc simulate' read scene files (in Python, "
                            "mechcirc.scene.load_scene(FILE).linkage is its linkage)")
            exc.args = (str(exc),)
        raise


def cmd_linkage(args) -> int:
    import numpy as np

    check_output_paths(plots=(args.plot,), reads=(args.file,))

    lk, theta = _load_linkage(args.file), math.radians(args.theta)
    state = lk.solve(theta)
    if args.plot:
        from ..kinematics.plots import plot_linkage
        # one turn of the first crank, started from the requested position
        turn = np.sign(lk.cranks[0].omega) * np.radians(np.arange(0.0, 361.0, 3.0))
        sweep = lk.solve(theta + turn)
        paths = {p: np.array([s.points[p] for s in sweep]) for p in lk.pose if p not in lk.ground}
        save_figure(plot_linkage(lk, state, paths), args.plot)
    groups = lk.assur_groups()
    doc = {"file": args.file, "name": lk.name, "units": lk.units or None,
           "links": len(lk.links),
           "revolute_pairs": lk.revolute_pairs, "prismatic_pairs": len(lk.sliders),
           "mobility": lk.mobility,
           "assur_groups": [{"links": list(g.links), "class": g.group_class, "order": g.order,
                             "base": g.base, "external_pairs": list(g.external_pairs)}
                            for g in groups],
           "cranks": [{"link": c.link, "pivot": c.pivot, "omega": c.omega} for c in lk.cranks],
           **state.as_dict()}
    if args.json:
        return print_json(doc)
    prism = f", {len(lk.sliders)} prismatic" if lk.sliders else ""
    print(f"{lk.name}: {len(lk.links)} moving links, {lk.revolute_pairs} revolute pairs{prism}, "
          f"W = {lk.mobility}; cranks "
          + ", ".join(f"{c.link} (ω = {c.omega:g} rad/s, "
                      f"{convert_frequency(c.omega, 'rad/s', 'rpm'):.6g} rpm)" for c in lk.cranks))
    for g in groups:
        cls = {2: "class-II dyad", 3: "class-III group"}.get(g.group_class, "group")
        base = f" on base {g.base}" if g.base else ""
        print(f"  {cls} ({', '.join(g.links)}){base}, order {g.order} "
              f"(external pairs {', '.join(g.external_pairs)})")
    length = lk.units or "length"       # the file's unit, or a neutral word without one
    print(f"at θ = {args.theta:g}° (t = {state.t:.6g} s); positions in {length}, velocities "
          f"in {length}/s:")
    cols = "".join(f" {('v from ' + c.link + f' [{length}/s]'):>24s}" for c in lk.cranks)
    print(f"  {'point':6s} {f'x [{length}]':>10s} {f'y [{length}]':>10s} "
          f"{f'v (vx, vy) [{length}/s]':>24s}{cols}")
    vscale = max(float(np.max(np.abs(v))) for v in state.velocities.values()) or 1.0

    def vec(v):   # rounding residue of a resting point prints as 0, not -0.000
        v = np.where(np.abs(v) < 1e-12 * vscale, 0.0, v)
        return f" {v[0]:11.3f},{v[1]:11.3f}"

    for p, x in state.points.items():
        parts = "".join(vec(state.contributions[c.link][p]) for c in lk.cranks)
        print(f"  {p:6s} {x[0]:10.3f} {x[1]:10.3f}{vec(state.velocities[p])}{parts}")
    print("  link angular velocities [rad/s]: "
          + ", ".join(f"{k} {w:+.4f}" for k, w in state.angular_velocities.items()))
    return 0
