"""Sub-command ``periodic``: the drive's force over one revolution at machine speed, or
the operating-speed map of its peak."""

from __future__ import annotations

import math

from ..errors import MechcircError
from ..units import in_unit
from ._common import (Default, add_handler, add_method_option, add_output_option, add_plot_option,
                      add_unit_option, check_names, check_output_paths, command, count, crank_angle,
                      load_with_warnings, print_json, print_written, real, refuse_ignored,
                      scene_theta, shaft_speed, warning_lines, write_outputs)


@command("periodic", "drive force over one revolution at machine speed; speed map",
         "Steady-state periodic force of a drive given by its motion over one revolution ('drive "
         "... motion=lift.csv' or 'motion=cycloidal rise=... dwell=... return=... stroke=...'): "
         "the harmonics kΩ of the drive's velocity through K(kΩ), as many as the error asked for "
         "needs (said). With --rpm: Q(θ) over the crank angle and the harmonics near resonances. "
         "With --rpm-min/--rpm-max: the peak |Q(θ)| against machine speed and the speeds where a "
         "harmonic meets a resonance (k·Ω = ωn).",
         "Examples:\n  mechcirc periodic docs/examples/cam_drive.mcir --rpm 600 -o Q.csv\n"
         "  mechcirc periodic docs/examples/cam_drive.mcir --rpm-min 100 --rpm-max 1200\n"
         "  mechcirc periodic docs/examples/rocker_drive.toml --theta 30 --rpm 300")
def register(p) -> None:
    p.add_argument("file", help="netlist (.mcir) whose drive has motion=, or a scene (.toml): "
                                "its circuit at --theta driven by the motion its linkage imposes")
    p.add_argument("--theta", type=crank_angle, metavar="DEG",
                   help="scene: the crank rotation [deg] at which it is linearised "
                        "(default: the file's [analysis] theta_deg)")
    p.add_argument("--rpm", type=shaft_speed, metavar="RPM",
                   help="machine speed [rev/min]")
    p.add_argument("--rpm-min", type=shaft_speed, metavar="A",
                   help="lowest speed of the speed map [rev/min]")
    p.add_argument("--rpm-max", type=shaft_speed, metavar="B",
                   help="highest speed of the speed map [rev/min]")
    p.add_argument("--points", type=count(2, 100_000), default=Default(200), metavar="N",
                   help="speed map: its speeds (default 200)")
    p.add_argument("--angles", type=count(4, 1_000_000), default=Default(360), metavar="N",
                   help="--rpm: crank angles per revolution in the outputs (default 360)")
    p.add_argument("--tol", type=real(above=0.0, most=0.5), default=1e-4, metavar="TOL",
                   help="error asked for, relative to the peak force (default 1e-4)")
    p.add_argument("--harmonics", type=count(1, 4096), metavar="N",
                   help="use exactly N harmonics (the error is still estimated)")
    p.add_argument("--elements", metavar="NAMES",
                   help="comma-separated elements whose force (and velocity) to add, or 'all'")
    p.add_argument("--near", type=real(above=0.0, most=1.0), default=Default(0.03), metavar="FRAC",
                   help="--rpm: name harmonics within this relative distance of a resonance "
                        "(default 0.03)")
    add_method_option(p, "how K is evaluated (default auto)")
    add_output_option(p, "write the table as CSV")
    add_plot_option(p, "plot (PNG, SVG or PDF)")
    add_unit_option(p, "unit of the frequencies printed: shaft speed Ω, harmonics kΩ, "
                       "resonances ωn (default rad/s; --json stays in rad/s)")
    add_handler(p, cmd_periodic)


def _elements(args, circuit):
    if not args.elements:
        return []
    names = [e.name for e in circuit.elements]
    if args.elements.strip() == "all":
        return names
    asked = [n.strip() for n in args.elements.split(",") if n.strip()]
    check_names(asked, names, "element", "--elements")
    return asked


def cmd_periodic(args) -> int:
    check_output_paths(args.output, plots=(args.plot,), reads=(args.file,), table="a CSV table")
    single = args.rpm is not None
    ranged = args.rpm_min is not None or args.rpm_max is not None
    if single == ranged:
        raise MechcircError("give either --rpm RPM, or --rpm-min A and --rpm-max B "
                            "(an operating-speed map)")
    if ranged and (args.rpm_min is None or args.rpm_max is None
                   or not args.rpm_min < args.rpm_max):
        raise MechcircError("the speed map needs both --rpm-min and --rpm-max, with "
                            "--rpm-min < --rpm-max")
    scene = args.file.lower().endswith(".toml")
    one = (single, "one speed", "give --rpm instead of --rpm-min/--rpm-max")
    refuse_ignored(args, {"--points": (ranged, "a speed map", "add --rpm-min and --rpm-max "
                                       "instead of --rpm"), "--angles": one, "--near": one,
                          "--theta": (scene, "a scene (.toml), not to a netlist", "")})
    if scene:
        circuit, motion = _scene(args)
    else:
        circuit, warns = load_with_warnings(args.file)
        motion = None
        warning_lines(warns)
    return (_one_speed if single else _speed_map)(args, circuit, _elements(args, circuit), motion)


def _scene(args):
    """A scene's circuit at --theta and the motion its rigid linkage imposes on the drive."""
    from ..scene import build, load_scene
    from ..scene.cycle import drive_motion

    scene = load_scene(args.file)
    theta = math.radians(scene_theta(args, scene))
    if scene.drive.kind != "velocity":
        raise MechcircError(f"{args.file}: the drive is a force; the periodic drive imposes "
                            "the linkage's motion, which needs a velocity drive")
    return build(scene, theta).circuit, drive_motion(scene, theta)


def _one_speed(args, circuit, elements, motion) -> int:
    import numpy as np

    from ..periodic import periodic

    r = periodic(circuit, args.rpm, motion=motion, tol=args.tol, harmonics=args.harmonics,
                 points=args.angles, elements=elements, near=args.near, method=args.method)
    unit, vu = r.units["Q"], r.units["v"]
    fu = args.unit
    cols = [("angle_deg", r.angle_deg), ("x", r.x), ("v", r.v), ("Q", r.Q)]
    for name in elements:
        cols += [(f"F_{name}", r.forces.get(name, np.full_like(r.Q, np.nan))),
                 (f"v_{name}", r.velocities.get(name, np.full_like(r.Q, np.nan)))]
    write_outputs(args, cols, r.plot)
    if args.json:
        return _print_one_speed_json(args, r)
    d = circuit.drive
    spec = (motion or d.motion).spec
    spec += f" (stroke in {r.units['x']})" if "stroke=" in spec else ""
    print(f"{args.file}: drive {d.name} {spec} at {r.rpm:g} rpm "
          f"(Ω = {in_unit(r.omega_shaft, fu):.6g} {fu})")
    print(f"  {r.harmonics} harmonics; estimated error {r.error:.2g} of the peak "
          f"(asked {r.tol:g}); forces about their mean (no static preload)")
    print("  peak |Q| = inf: the steady periodic force is unbounded" if r.unbounded else
          f"  peak |Q| = {r.peak:.7g} {unit} at θ = {r.peak_angle_deg:.4f} deg; "
          f"drive velocity up to {np.max(np.abs(r.v)):.4g} {vu}")
    near = np.flatnonzero(r.near)
    if near.size:
        print(f"  harmonics within {args.near:.0%} of a resonance:")
        for i in near:
            print(f"    k = {r.k[i]}: kΩ = {in_unit(r.omega[i], fu):.6g} {fu}, resonance "
                  f"ωn = {in_unit(r.nearest[i], fu):.6g} {fu} ({r.distance[i]:+.2%}), "
                  f"|Q_k| = {abs(r.amplitude[i]):.4g} {unit}")
    else:
        print(f"  no harmonic within {args.near:.0%} of a resonance")
    top = np.argsort(-np.nan_to_num(np.abs(r.amplitude), nan=np.inf))[:8]
    print(f"  {'k':>5} {f'kΩ [{fu}]':>12} {f'|V_k| [{vu}]':>12} {f'|Q_k| [{unit}]':>12} "
          f"{f'nearest ωn [{fu}]':>17} {'distance':>9}")
    for i in sorted(top):           # (no resonance known: dashes, not "nan +nan%")
        res = (f"{'—':>17} {'—':>9}" if np.isnan(r.nearest[i]) else
               f"{in_unit(r.nearest[i], fu):>17.6g} {r.distance[i]:>+9.2%}")
        print(f"  {r.k[i]:>5} {in_unit(r.omega[i], fu):>12.6g} {abs(r.V[i]):>12.4g} "
              f"{abs(r.amplitude[i]):>12.4g} {res}")
    if r.harmonics > top.size:
        print(f"  (the {top.size} largest of {r.harmonics} harmonics; --json lists all)")
    for name in elements:
        if (pk := r.element_peaks.get(name)) is not None:
            print(f"  element {name}: peak |force| {pk[0]:.6g} {unit} at θ = {pk[1]:.4f} deg")
    print_written(("CSV", args.output), ("plot", args.plot), notes=r.notes)
    return 0


def _print_one_speed_json(args, r) -> int:
    """The periodic result ``r`` at one speed as JSON, every harmonic listed."""
    import numpy as np

    rows = [{"k": int(k), "omega": float(w), "velocity": complex(v),
             "amplitude": float(abs(q)), "phase_deg": float(np.degrees(np.angle(q))),
             "nearest_resonance": float(n), "distance": float(d), "near": bool(nr)}
            for k, w, v, q, n, d, nr in zip(r.k, r.omega, r.V, r.amplitude, r.nearest,
                                            r.distance, r.near)]
    return print_json({"file": args.file, "name": r.name, "unit": r.units["Q"], "rpm": r.rpm,
                       "omega_shaft": r.omega_shaft, "angle_deg": r.angle_deg, "x": r.x,
                       "v": r.v, "Q": r.Q, "peak": r.peak, "peak_angle_deg": r.peak_angle_deg,
                       "error": r.error, "tol": r.tol, "n_harmonics": r.harmonics,
                       "harmonics": rows,
                       "resonances": [{"omega": w, "zeta": z} for w, z in r.resonances],
                       "unbounded": list(r.unbounded), "forces": r.forces,
                       "element_peaks": {n: {"peak": p, "angle_deg": a}
                                         for n, (p, a) in r.element_peaks.items()},
                       "velocities": r.velocities, "notes": list(r.notes)})


def _speed_map(args, circuit, elements, motion) -> int:
    import numpy as np

    from ..periodic import speed_map

    m = speed_map(circuit, args.rpm_min, args.rpm_max, args.points, motion=motion, tol=args.tol,
                  harmonics=args.harmonics, elements=elements, method=args.method)
    unit = m.units["Q"]
    write_outputs(args, [("rpm", m.rpm), ("peak_Q", m.peak), ("harmonics", m.harmonics),
                         ("error", m.error)]
                  + [(f"peak_{name}", m.element_peaks[name]) for name in elements], m.plot)
    crossings = [{"rpm": r, "k": k, "omega_n": w, "zeta": z, "weight": wt}
                 for r, k, w, z, wt in m.crossings]
    if args.json:
        return print_json({"file": args.file, "name": m.name, "unit": unit, "rpm": m.rpm,
                           "peak": m.peak,
                           "harmonics": m.harmonics, "error": m.error, "crossings": crossings,
                           "element_peaks": m.element_peaks, "notes": list(m.notes)})
    finite = np.isfinite(m.peak)
    print(f"{args.file}: peak drive force over the cycle at {m.rpm.size} speeds, "
          f"{m.rpm[0]:g} .. {m.rpm[-1]:g} rpm ({int(m.harmonics.min())} .. "
          f"{int(m.harmonics.max())} harmonics; largest estimated error "
          f"{np.max(m.error):.2g})")
    if finite.any():
        lo, hi = np.argmin(np.where(finite, m.peak, np.inf)), np.argmax(
            np.where(finite, m.peak, -np.inf))
        print(f"  on the speed grid: smallest peak {m.peak[lo]:.6g} {unit} at {m.rpm[lo]:.6g} "
              f"rpm; largest {m.peak[hi]:.6g} {unit} at {m.rpm[hi]:.6g} rpm")
    strong = [c for c in crossings if c["weight"] >= 1e-3]
    print(f"  speeds where a harmonic meets a resonance (k·Ω = ωn; {len(strong)} of "
          f"{len(crossings)} with a harmonic of at least 1e-3 of the drive velocity)"
          + (":" if crossings else ": none in this range"))
    for c in strong[:30]:
        print(f"    {c['rpm']:10.6g} rpm: k = {c['k']:>3}, ωn = "
              f"{in_unit(c['omega_n'], args.unit):.6g} {args.unit} "
              f"(ζ = {c['zeta']:.3g}, harmonic weight {c['weight']:.2g})")
    if len(strong) > 30:
        print(f"    ... {len(strong) - 30} more (--json lists all)")
    print_written(("CSV", args.output), ("plot", args.plot), notes=m.notes)
    return 0
