"""Sub-commands on kinematics: ``fourbar``, ``synth`` and ``linkage``."""

from __future__ import annotations

import argparse
import math

from ._common import (MAX_LENGTH, MAX_OMEGA, check_output_paths, count, print_json, real,
                      save_figure)


def register(sub) -> None:
    p = sub.add_parser(
        "fourbar", help="four-bar dead centres, swing, transmission angle and ε4T",
        description="Closed-form four-bar analysis: Grashof class, dead centres, swing Ψ, "
                    "transmission angle range and the theoretical rocker acceleration "
                    "ε4T = ν·ω². Angles are measured counter-clockwise from the frame "
                    "line A→D; the crank turns with θ increasing.",
        epilog="Example: mechcirc fourbar --crank 29 --coupler 37 --rocker 188 --frame 189 "
               "--omega 100 --plot fourbar.png",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    for name, what in (("crank", "AB"), ("coupler", "BC"), ("rocker", "CD"), ("frame", "AD")):
        p.add_argument(f"--{name}", type=real(above=0.0, most=MAX_LENGTH), required=True,
                       metavar="L",
                       help=f"{name} length {what} (any unit)")
    p.add_argument("--omega", type=real(most=MAX_OMEGA, unit="rad/s"), metavar="W",
                   help="crank speed [rad/s] for ε4T = ν·ω²")
    p.add_argument("--branch", type=int, choices=(1, -1), default=1,
                   help="assembly mode (default +1; see docs/kinematics.md)")
    p.add_argument("--plot", metavar="IMAGE", help="plot φ4, μ, ν (or ε4T) and γ against θ")
    p.add_argument("--json", action="store_true", help="print one JSON document")
    p.set_defaults(func=cmd_fourbar)

    p = sub.add_parser(
        "synth", help="beat-up four-bar synthesis after patent CN104178888",
        description="Explore crank-rockers meeting every criterion of the patent "
                    "(γ at the front dead centre > 70°, γmin > 45°, |Φ2''|/|Φ1''| < 0.3, "
                    "d < 180 mm, eq. (9), swing 23–26°) and rank them. Lengths in mm.",
        epilog="Example: mechcirc synth --load medium --swing 24 --plot synth.png",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--load", choices=("light", "medium", "heavy"), default="medium",
                   help="loom class: crank 33–34, 35–36 or 37–38 mm (default medium)")
    p.add_argument("--swing", type=real(above=0.0, most=180.0, unit="deg"), metavar="DEG",
                   help="swing Ψ [deg] (default: explore 23–26°)")
    p.add_argument("--objective", choices=("margin", "ratio"), default="margin",
                   help="rank by the smallest criterion margin (default) or by |Φ2''|/|Φ1''|")
    p.add_argument("--limit", type=count(1, 100_000), default=10, metavar="N",
                   help="number of designs shown (default 10)")
    p.add_argument("--plot", metavar="IMAGE",
                   help="transmission angle and rocker acceleration against θ")
    p.add_argument("--json", action="store_true", help="print one JSON document")
    p.set_defaults(func=cmd_synth)

    p = sub.add_parser(
        "linkage", help="positions, velocities and conditional-stop velocities of a TOML linkage",
        description="Solve a planar revolute-jointed linkage with any number of driving "
                    "cranks (TOML file, see docs/kinematics.md) at a rotation θ of the first "
                    "crank from the file's pose; velocities are also split into each "
                    "crank's contribution with the others stopped.",
        epilog="Example: mechcirc linkage examples/fnf_sixbar.toml --theta 30 --plot fnf.png",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="linkage file (.toml)")
    p.add_argument("--theta", type=real(most=1e9, unit="deg"), default=0.0, metavar="DEG",
                   help="rotation of the first crank from the pose [deg] (default 0)")
    p.add_argument("--plot", metavar="IMAGE",
                   help="draw the linkage at θ with the paths of its points")
    p.add_argument("--json", action="store_true", help="print one JSON document")
    p.set_defaults(func=cmd_linkage)


def _deg(x):
    return f"{math.degrees(x):.3f}°"


#: The longest link may be at most this many times the shortest (float64 keeps ~16 digits).
MAX_LENGTH_RATIO = 1e6


def _check_length_ratio(args) -> None:
    from ..errors import InputError

    lengths = {n: getattr(args, n) for n in ("crank", "coupler", "rocker", "frame")}
    lo, hi = min(lengths, key=lengths.get), max(lengths, key=lengths.get)
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
        print_json(doc)
        return 0
    print(f"four-bar a={fb.crank:g} b={fb.coupler:g} c={fb.rocker:g} d={fb.frame:g}, "
          f"branch {fb.branch:+d}: {fb.grashof_class} {fb.linkage_type}")
    if not doc["crank_rotates_fully"]:
        lo, hi = doc["crank_range_deg"]
        print(f"  the input link cannot turn fully: it rocks in θ ∈ [{lo:.3f}°, {hi:.3f}°]"
              + ("" if lo < 0 or hi > 180 else f" (and in [{360 - hi:.3f}°, {360 - lo:.3f}°])")
              + "; μ and ν grow without bound at the ends, where it locks")
    if "dead_centres" in doc:
        for dc in doc["dead_centres"]:
            line = (f"  {dc['kind']:5s} dead centre: θ = {dc['theta_deg']:8.3f}°  "
                    f"φ4 = {dc['phi4_deg']:8.3f}°  ν = {dc['nu']:+.6f}")
            if args.omega is not None:
                line += f"  ε4 = {dc['rocker_acceleration']:+.1f} 1/s²"
            print(line)
        print(f"  swing Ψ = {doc['swing_deg']:.4f}°")
    tmin = ", ".join(f"{t:.2f}°" for t in doc["theta_at_gamma_min_deg"])
    tmax = ", ".join(f"{t:.2f}°" for t in doc["theta_at_gamma_max_deg"])
    print(f"  transmission angle γ: min {doc['gamma_min_deg']:.3f}° at θ = {tmin}; "
          f"max {doc['gamma_max_deg']:.3f}° at θ = {tmax}")
    print(f"  ν range: [{doc['nu_min']:+.6f}, {doc['nu_max']:+.6f}] 1/rad at θ = "
          f"{doc['theta_at_nu_min_deg']:.2f}°, {doc['theta_at_nu_max_deg']:.2f}°")
    if args.omega is not None:
        print(f"  ε4T = ν·ω² at ω = {args.omega:g} rad/s: "
              f"[{doc['eps4T_min']:.1f}, {doc['eps4T_max']:.1f}] 1/s²")
    return 0


def cmd_synth(args) -> int:
    import sys

    from ..errors import MechcircError
    from ..kinematics import synthesize

    check_output_paths(plots=(args.plot,))
    if args.limit < 1:
        raise MechcircError(f"--limit must be at least 1, got {args.limit}")

    res = synthesize(args.load, args.swing, objective=args.objective, limit=args.limit)
    if args.plot and res.designs:
        from ..kinematics.plots import plot_synthesis
        save_figure(plot_synthesis(res.designs[:5]), args.plot)
    if args.json:
        print_json(res.as_dict())
        return 0 if res.designs else 2
    if not res.designs:
        print(f"mechcirc: error: {res.message}", file=sys.stderr)
        for name, count in res.rejected.items():
            print(f"  {name:20s} rejects {count} of {res.explored}", file=sys.stderr)
        return 2
    print(res.message + ".")
    print(f"{'#':>2} {'a':>6} {'b':>7} {'c':>7} {'d':>7} {'Ψ°':>6} {'γ1°':>6} {'γmin°':>6} "
          f"{'ratio':>6} {'c/a':>6} {'bound':>6}  binding")
    for k, des in enumerate(res.designs, 1):
        cr = des.criteria
        bound = float(cr["rocker_ratio"].limit.lstrip("> "))
        print(f"{k:2d} {des.a:6.2f} {des.b:7.2f} {des.c:7.2f} {des.d:7.2f} "
              f"{des.swing_deg:6.2f} {cr['front_transmission'].value:6.2f} "
              f"{cr['min_transmission'].value:6.2f} {cr['acceleration_ratio'].value:6.3f} "
              f"{cr['rocker_ratio'].value:6.3f} {bound:6.3f}  {', '.join(des.binding)}")
    print(f"({res.explored} crank-rockers explored; lengths in mm; ratio = |Φ2''|/|Φ1''|)")
    return 0


def cmd_linkage(args) -> int:
    import numpy as np

    from ..kinematics import load_linkage

    check_output_paths(plots=(args.plot,))

    lk = load_linkage(args.file)
    theta = math.radians(args.theta)
    state = lk.solve(theta)
    if args.plot:
        from ..kinematics.plots import plot_linkage
        w1 = lk.cranks[0].omega
        # one turn of the first crank, started from the requested position
        sweep = lk.solve(theta + np.sign(w1) * np.radians(np.arange(0.0, 361.0, 3.0)))
        moving = [p for p in lk.pose if p not in lk.ground]
        paths = {p: np.array([s.points[p] for s in sweep]) for p in moving}
        save_figure(plot_linkage(lk, state, paths), args.plot)
    groups = lk.assur_groups()
    doc = {"file": args.file, "name": lk.name, "links": len(lk.links),
           "revolute_pairs": lk.revolute_pairs, "mobility": lk.mobility,
           "assur_groups": [{"links": list(g.links), "class": g.group_class, "order": g.order,
                             "base": g.base, "external_pairs": list(g.external_pairs)}
                            for g in groups],
           "cranks": [{"link": c.link, "pivot": c.pivot, "omega": c.omega} for c in lk.cranks],
           **state.as_dict()}
    if args.json:
        print_json(doc)
        return 0
    print(f"{lk.name}: {len(lk.links)} moving links, {lk.revolute_pairs} revolute pairs, "
          f"W = {lk.mobility}; cranks "
          + ", ".join(f"{c.link} (ω = {c.omega:g} rad/s)" for c in lk.cranks))
    for g in groups:
        cls = {2: "class-II dyad", 3: "class-III group"}.get(g.group_class, "group")
        base = f" on base {g.base}" if g.base else ""
        print(f"  {cls} ({', '.join(g.links)}){base}, order {g.order} "
              f"(external pairs {', '.join(g.external_pairs)})")
    print(f"at θ = {args.theta:g}° (t = {state.t:.6g} s):")
    cols = "".join(f" {('v from ' + c.link):>24s}" for c in lk.cranks)
    print(f"  {'point':6s} {'x':>10s} {'y':>10s} {'v (vx, vy)':>24s}{cols}")
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
