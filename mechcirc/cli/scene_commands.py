"""Sub-commands for scenes: ``scene`` (a linkage scene to its circuit) and ``reduce``."""

from __future__ import annotations

import math
import warnings

from ..errors import MechcircError
from ..limits import MAX_CYCLE_POINTS
from ..progress import Progress
from ..units import FREQUENCY_UNITS, in_unit
from ._common import (NETLIST_FILE, Default, add_handler, add_output_option, add_plot_option,
                      add_unit_option, check_output_paths, command, commands, count, crank_angle,
                      frequency_symbol, print_json, print_written, real, refuse_ignored,
                      save_figure, scene_theta, set_values, write_outputs, write_text)


@command("scene", "a scene (linkage + masses + elastic links) to its mechanical circuit",
         "Linearise a scene file at a crank angle into a netlist (--theta),\n"
         "or map its resonances and |Q0| at the shaft harmonics over one\n"
         "revolution (--cycle).  See docs/scenes.md.",
         "Examples:\n  mechcirc scene examples/heald_scene.toml --theta 40 -o heald.mcir\n"
         "  mechcirc scene examples/heald_scene.toml --cycle --points 72 --harmonics 8 --plot "
         "cycle.png", file="scene file (.toml)")
def _register_scene(p) -> None:
    what = p.add_mutually_exclusive_group()
    what.add_argument("--theta", type=crank_angle, metavar="DEG",
                      help="crank rotation from the pose [deg] to linearise at (default: "
                           "theta_deg of the file's [analysis])")
    what.add_argument("--cycle", action="store_true",
                      help="resonances and |Q0| at shaft harmonics over a revolution")
    add_output_option(p, "--theta: write the netlist (.mcir); --cycle: write a CSV table",
                      metavar="FILE")
    p.add_argument("--reflect", choices=("eta", "lever"), default="eta",
                   help="reflect through eta = ratio² (default) or explicit ideal levers")
    p.add_argument("--points", type=count(2, MAX_CYCLE_POINTS, why="10–25 ms each"),
                   default=Default(72), metavar="N", help="--cycle: crank angles over the revolution (default 72)")
    p.add_argument("--harmonics", type=count(1, 1000), default=Default(5), metavar="H",
                   help="--cycle: shaft harmonics h = 1..H for |Q0| (default 5)")
    p.add_argument("--reduce", action="store_true", default=Default(False),
                   help="reduce the circuit to what the file's [analysis] output needs over "
                        "its band, within its tol (-o then writes the reduced netlist)")
    add_plot_option(p, "--cycle: plot the map; with --mode: draw the mode on the linkage "
                       "(PNG, SVG or PDF)")
    p.add_argument("--mode", type=count(1, 10_000), metavar="N",
                   help="--theta: draw resonance N (drive held; 1 = lowest) on the linkage "
                        "into --plot")
    add_unit_option(p, "frequency unit of the tables, the --cycle CSV's column names and "
                       "plot (default rad/s)")
    add_handler(p, cmd_scene)


@command("reduce", "model only what the output needs in a frequency band",
         "Remove or merge elements of a netlist that do not matter for the output in the band [W1, "
         "W2] (rigid springs, negligible masses, chains that collapse); report the measured worst "
         "relative error of the output over the band (never above --tol) and the shift of each "
         "resonance.",
         "Example: mechcirc reduce netlists/stb_heald.mcir --band 10:2000 --tol 0.01 -o "
         "reduced.mcir", file=NETLIST_FILE, raw=False)
def _register_reduce(p) -> None:
    p.add_argument("--band", required=True, metavar="W1:W2",
                   help="angular frequency band [rad/s], W1 < W2")
    p.add_argument("--tol", type=real(above=0.0, most=1.0), required=True, metavar="T",
                   help="largest relative error of the output allowed over the band (> 0)")
    p.add_argument("--element", dest="element", metavar="ELEMENT",
                   help="the force in this element is the output (default: K at the drive)")
    # --output used to name the element; everywhere else it is a file.  It stays
    # a file here too (the reduced netlist, as -o), so the name means one thing.
    add_output_option(p, "write the reduced netlist here", metavar="FILE", dest="out")
    p.add_argument("--points", type=count(10, 1_000_000), default=2000, metavar="N",
                   help="log-spaced check points over the band (default 2000; two more "
                        "beside each resonance in the band)")
    add_handler(p, cmd_reduce)


register = commands(_register_scene, _register_reduce)


def cmd_scene(args) -> int:
    check_output_paths(args.output, plots=(args.plot,), reads=(args.file,),
                       table="a CSV table (--cycle) or a netlist (--theta)")
    one = args.plot and not (args.cycle or args.reduce)
    refuse_ignored(args, {"--points": (args.cycle, "--cycle", "add --cycle"),
                          "--harmonics": (args.cycle, "--cycle", "add --cycle"),
                          "--plot": (args.cycle or args.mode is not None, "the --cycle map or a "
                                     "--mode N drawing", "add --cycle or --mode N"),
                          "--mode": (one, "one crank angle drawn into --plot, without --cycle "
                                     "or --reduce", "add --plot IMAGE"),
                          "--reduce": (not args.cycle, "one crank angle, not to --cycle", "")})
    from ..scene import build, build_needed, load_scene

    scene = load_scene(args.file)
    if args.cycle:
        return _cycle(args, scene)
    if args.reduce and scene.analysis.band is None:
        raise MechcircError(f"{args.file}: --reduce needs band = [W1, W2] and tol = T in the "
                            "file's [analysis] table")
    theta_deg = scene_theta(args, scene, " or --cycle")
    model, reduced = build_needed(scene, math.radians(theta_deg), reflect=args.reflect) \
        if args.reduce else (build(scene, math.radians(theta_deg), reflect=args.reflect), None)
    args.theta = theta_deg
    found = model.circuit.resonances()
    if args.mode is not None:
        from ..scene.plots import plot_mode

        save_figure(plot_mode(scene, math.radians(theta_deg), args.mode), args.plot)
    if args.output:
        write_text(args.output, model.netlist if reduced is None else reduced.netlist)
    if args.json:
        return print_json({
            "file": args.file, "theta_deg": args.theta, "drive_ratio": model.drive_ratio,
            "rotational": model.rotational, "parts": {k: list(v) for k, v in model.parts.items()},
            "ratios": model.ratios, "dropped": [{"name": n, "why": w} for n, w in model.dropped],
            "resonances": [r.as_dict() for r in found],
            "netlist": model.netlist, "output": args.output,
            "reduced": None if reduced is None else reduced.as_dict()})
    _print_scene(args, scene, model, found, reduced)
    return 0


def _print_scene(args, scene, model, found, reduced) -> None:
    """What ``mechcirc scene --theta`` prints without ``--json``."""
    units = "rotary drive: v in rad/s, Q in N·m" if model.rotational else \
        "translational drive: v in m/s, Q in N"
    print(f"{args.file}: scene {scene.name!r} at θ = {args.theta:g}° "
          f"({units}; drive ratio r0 = {model.drive_ratio:.6g})")
    for node, part in model.parts.items():
        print(f"  node {node}: {', '.join(part)}")
    print("velocity ratios to the drive:")
    for name, r in model.ratios.items():
        print(f"  {name:<10} {r: .6g}")
    for name, why in model.dropped:
        print(f"  left out {name}: {why}")
    print("resonances (K = 0) and anti-resonances (K = ∞):")
    for r in found:
        z = f"  zeta={r.zeta:.4g}" if r.zeta else ""
        hz = f"  {r.f_hz:10.5g} Hz" if args.unit == "rad/s" else ""      # f beside omega
        print(f"  {r.kind:<14} {in_unit(r.omega, args.unit):12.6g} {args.unit}{hz}{z}")
    if reduced is not None:
        what = "K at the drive" if reduced.output is None else f"the force in {reduced.output}"
        print(f"reduced for {what} over ω ∈ [{reduced.band[0]:g}, {reduced.band[1]:g}] rad/s: "
              f"{reduced.elements_before} -> {reduced.elements_after} elements, measured worst "
              f"relative error {reduced.error:.3g} (tol {reduced.tol:g})")
        for step in reduced.steps:
            print(f"  {step}")
    if args.output:
        print(f"wrote {args.output}" + (" (reduced)" if reduced is not None else ""))
    if args.mode is not None:
        print(f"resonance {args.mode} drawn on the linkage into {args.plot}")


def _cycle(args, scene) -> int:
    import numpy as np

    from ..scene.cycle import cycle_map, plot_cycle

    with Progress(args.points, "crank angles") as bar:
        cmap = cycle_map(scene, points=args.points, harmonics=args.harmonics,
                         reflect=args.reflect, progress=bar)
    W = cmap.natural_frequencies()
    u = args.unit
    name = FREQUENCY_UNITS[u][0]
    write_outputs(args, [("theta_deg", np.degrees(cmap.theta))]
                  + [(f"{name}_res{k + 1}", w) for k, w in enumerate(in_unit(W, u).T)]
                  + [(f"abs_Q0_h{h}", q) for h, q in zip(cmap.harmonics, np.abs(cmap.Q0).T)],
                  lambda: plot_cycle(cmap, unit=u), fmt="%.10g")
    if args.json:
        return print_json({**cmap.as_dict(), "file": args.file, "output": args.output,
                           "plot": args.plot})
    unit = "N·m" if cmap.rotational else "N"
    turns = round(cmap.cycle / (2 * math.pi))    # geared: the cycle is this many shaft turns
    fund = "Ω" if turns == 1 else f"Ω/{turns}"    # the harmonics' fundamental, omega_shaft
    print(f"{args.file}: scene {scene.name!r}, {len(cmap.theta)} crank angles, shaft Ω = "
          f"{in_unit(turns * cmap.omega_shaft, u):g} {u}" + (f"; the cycle of {turns} turns "
          f"repeats at {fund} = {in_unit(cmap.omega_shaft, u):g} {u}" if turns > 1 else ""))
    sym = frequency_symbol(u)
    print(f"resonances [{u}] and |Q0| [{unit}] at h·{fund}:")
    print("  θ [deg]  " + " ".join(f"{sym + '_r' + str(k + 1):>10}" for k in range(W.shape[1]))
          + "  " + " ".join(f"{'|Q0| h=' + str(h):>11}" for h in cmap.harmonics))
    for i, th in enumerate(cmap.theta):
        row = f"skipped: {cmap.skipped[i]}" if i in cmap.skipped else \
            " ".join(f"{w:10.5g}" for w in in_unit(W[i], u)) + "  " + \
            " ".join(f"{abs(q):11.4g}" for q in cmap.Q0[i])
        print(f"  {math.degrees(th):7.2f}  {row}")
    if cross := cmap.crossings():
        print("a resonance meets a shaft harmonic at:")
        for c in cross:
            print(f"  θ ≈ {c['theta_deg']:7.2f}°: resonance {c['mode'] + 1} = "
                  f"{c['harmonic']}·{fund} = {in_unit(c['omega'], u):g} {u}")
    else:
        print(f"no resonance meets a harmonic h·{fund} (h ≤ "
              f"{cmap.harmonics[-1]}) over the cycle")
    for path in filter(None, (args.output, args.plot)):
        print(f"wrote {path}")
    return 0


def cmd_reduce(args) -> int:
    from ..netlist import load
    from .._simplify import parse_band, simplify

    check_output_paths(args.out, reads=(args.file,), table="the reduced netlist")
    band, circuit = parse_band(args.band), load(args.file)
    result = simplify(circuit, band, args.tol, output=args.element, points=args.points)
    if args.out:
        write_text(args.out, result.netlist)
    if args.json:
        return print_json({**result.as_dict(), "file": args.file, "written": args.out})
    print(f"{args.file}: {result.elements_before} elements -> {result.elements_after} "
          f"over ω ∈ [{band[0]:g}, {band[1]:g}] rad/s, output "
          f"{'K at the drive' if args.element is None else 'force in ' + args.element}")
    for step in result.steps:
        print(f"  {step}")
    print(f"measured worst relative error over the band: {result.error:.3g} "
          f"(tolerance {args.tol:g}; on {result.points} check points: {args.points} "
          f"log-spaced and two beside each resonance in the band)")
    if result.shifts:
        print("resonances in the band (full -> reduced):")
        for s in result.shifts:
            red = f"{s['reduced']:.6g}" if s["reduced"] is not None else "gone"
            rel = f"  ({s['relative_shift']:+.3g})" if s["relative_shift"] is not None else ""
            print(f"  {s['kind']:<14} {s['full']:.6g} -> {red} rad/s{rel}")
    if args.out:
        print(f"wrote {args.out}")
    return 0


# ------------------------------------------------------------ simulate SCENE.toml
def cmd_simulate_scene(args) -> int:
    """``mechcirc simulate SCENE.toml``: the scene's motion over whole revolutions."""
    from ..scene import load_scene

    if args.method is None and not args.shaft:  # the shaft's default is the library's (rk8)
        args.method = "rk4"
    fixed = args.method in (None, "rk4", "rk4-python", "rk8")
    refuse_ignored(args, {
        "--rtol": (not fixed, "the scipy methods (DOP853, RK45, LSODA), not "
                   f"{args.method or 'the default rk8'}", "use --steps-per-period"),
        "--steps-per-period": (fixed, f"rk4 and rk8, not {args.method}", "use --rtol")})
    check_output_paths(args.output, plots=(args.plot,), reads=(args.scene,),
                       table="a CSV table")
    scene = _with_overrides(args, load_scene(args.scene))
    if args.shaft:
        return _shaft(args, scene)
    result = _simulate_with_bar(args, scene)
    from ..scene.plots import plot_motion

    write_outputs(args, result.columns().items(), lambda: plot_motion(result),
                  f"# {scene.name} ({args.scene}); revolution {result.revolution}; "
                  f"omega = {result.omega!r} rad/s")
    contact = _cam_contact(scene, result)
    if args.json:
        return print_json({**result.summary(), "file": args.scene, "output": args.output,
                           **({} if contact is None else {"cam_contact": contact})})
    _print_motion(args, scene, result)
    if contact is not None:
        _print_contact(contact)
    return 0


def _cam_contact(scene, result) -> dict | None:
    """The cam contact report of a scene whose follower can jump, as plain data (None: the
    scene has no such contact); a follower that flew across the whole gap (``flight``:
    ``simulate_scene`` has warned of it) has the report {"flight": message}."""
    from ..scene.jump import contact_report, flight

    if not getattr(scene.linkage, "contact", ""):
        return None
    if flew := flight(scene, result):
        return {"flight": flew}
    rep, L = contact_report(scene, result), scene.length_scale
    return {"contact": scene.linkage.contact, "min_contact_N": rep.min_contact,
            "min_contact_angle_deg": rep.min_contact_angle_deg,
            "travel": [float(rep.travel.min() / L), float(rep.travel.max() / L)],
            "travel_unit": scene.units or "m",
            "max_contact_N": float(rep.contact_force.max()),
            "separations": [{"angle_deg": a, "duration_deg": d} for a, d in rep.separations]}


def _print_contact(c: dict) -> None:
    """The text of the cam contact report (:func:`_cam_contact`)."""
    if "flight" in c:
        print("cam contact: no report (the follower flew across the model's whole gap; see "
              "the warning)")
        return
    u = c["travel_unit"]
    print(f"cam contact {c['contact']!r}: least contact force {c['min_contact_N']:.6g} N at "
          f"{c['min_contact_angle_deg']:.2f}° (k_c × compression: below 0 the follower has "
          f"left the cam), largest {c['max_contact_N']:.6g} N; follower travel "
          f"{c['travel'][0]:.6g} … {c['travel'][1]:.6g} {u}")
    seps = c["separations"]
    if not seps:
        print("  the contact stays closed")
    for s in seps:
        print(f"  opens at {s['angle_deg']:7.2f}° for {s['duration_deg']:6.2f}°")


def _simulate_with_bar(args, scene):
    """:func:`simulate_scene` as the options say, with a progress bar on a terminal; the
    accuracy warnings stay in the result's notes."""
    from ..scene.simulation import SceneAccuracyWarning, simulate_scene

    # The total is set by the first progress(done, total).
    with Progress(0, scene.name) as bar, warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneAccuracyWarning)   # kept in notes, printed in the report
        return simulate_scene(scene, revolutions=args.revolutions, start_deg=args.start_deg,
                              steps_per_period=args.steps_per_period, points=args.points,
                              method=args.method, rtol=args.rtol, revolution=args.revolution,
                              error_estimate=not args.no_error_estimate, progress=bar)


def _print_motion(args, scene, result) -> None:
    """The text report of a scene's motion: run, accuracy, extrema and notes."""
    est = "not computed" if result.error_estimate is None else f"{result.error_estimate:.2g}"
    per = "n/a (1 revolution)" if result.periodicity is None else f"{result.periodicity:.2g}"
    print(f"{args.scene}: scene {scene.name!r}, revolution {result.revolution} at "
          f"Ω = {result.omega:g} rad/s, {result.method} ({result.backend}), "
          f"{result.wall_time * 1e3:.1f} ms")
    print(f"error estimate {est}, periodicity {per} (relative change of the extrema at twice "
          f"the step / from the previous revolution)")
    _print_extrema(result.extrema, result.units)
    print_written(notes=result.notes, indent="")


def _with_overrides(args, scene):
    """``scene`` with ``--set NAME=VALUE`` and ``--omega`` applied."""
    from ..scene.files import apply_overrides

    # the texts as typed: the scene reader checks each unit against its key (as in the file,
    # a stiffness in kN is refused)
    over = set_values(args.set, texts=True)
    if args.omega is not None:
        over["omega"] = args.omega
    return apply_overrides(scene, over) if over else scene


def _print_extrema(extrema: dict, units: dict) -> None:
    """The table of each output's least and largest value over the cycle, with its unit."""
    print(f"{'quantity':<28} {'min':>14} {'max':>14}  unit")
    for k, (lo, hi) in extrema.items():
        print(f"{k:<28} {lo + 0.0:>14.6g} {hi + 0.0:>14.6g}  {units[k]}")


def _shaft(args, scene) -> int:
    """``mechcirc simulate SCENE.toml --shaft``: the dynamic main shaft (docs/scenes.md)."""
    import numpy as np

    from ..scene.shaft import ShaftWarning, simulate_shaft

    if args.method not in (None, "rk4", "rk8", "DOP853"):
        raise MechcircError(f"--method {args.method} does not apply to --shaft: use rk4, rk8 "
                            "(fixed steps, --steps-per-period) or DOP853 (--rtol)")
    # (the shaft's warnings are kept in the notes, printed below)
    with warnings.catch_warnings(record=True, action="always", category=ShaftWarning):
        r = simulate_shaft(scene, flywheel=args.flywheel, points=args.points or 720,
                           rigid=args.rigid, method=args.method,
                           steps_per_period=args.steps_per_period,
                           **({} if args.rtol is None else {"rtol": args.rtol}))
    curves = r.curves()
    write_outputs(args, [("theta_deg", np.degrees(r.theta)), ("time", r.time), *curves.items()],
                  comment=f"# {scene.name} ({args.scene}); steady cycle of the dynamic main "
                          f"shaft, flywheel {r.flywheel!r} kg·m²")
    if args.json:
        return print_json({**r.summary(), "file": args.scene, "output": args.output,
                           "notes": list(r.notes), "extrema": {
                               k: [float(v.min()), float(v.max())] for k, v in curves.items()}})
    m = scene.shaft.motor
    what = (f"Kloss, ω_s = {m.sync_speed:g} rad/s, T_b = {m.breakdown_torque:g} N·m, "
            f"s_b = {m.breakdown_slip:.4g}") if m.kind == "kloss" else \
        f"table of {len(m.speeds)} points"
    print(f"{args.scene}: scene {scene.name!r}, dynamic main shaft: flywheel {r.flywheel:g} "
          f"kg·m², motor ({what})")
    print(f"steady cycle: ω_mean = {r.omega_mean:.6g} rad/s, ω_min = {r.omega_min:.6g}, "
          f"ω_max = {r.omega_max:.6g}, δ = (ω_max − ω_min)/ω_mean = {r.delta:.4g}, "
          f"period {r.period:.6g} s")
    print(f"motor torque {float(r.motor_torque.min()):.6g} … {float(r.motor_torque.max()):.6g} "
          "N·m over the cycle")
    if r.startup_time is not None:
        print(f"start-up from rest: within 1 % of ω_mean of the steady band after "
              f"{r.startup_time:.4g} s")
    _print_extrema({k: (float(v.min()), float(v.max())) for k, v in curves.items()}, r.units)
    print_written(notes=r.notes, indent="")
    return 0


# ------------------------------------------------------------- crosscheck SCENE.toml
def cmd_crosscheck_scene(args) -> int:
    """``mechcirc crosscheck SCENE.toml --theta DEG``."""
    check_output_paths(args.netlist, reads=(args.file,), table="the netlist", option="--netlist")
    from ..scene import build, load_scene
    from ..scene.crosscheck import crosscheck_scene

    scene = load_scene(args.file)
    theta_deg = scene_theta(args, scene)
    result = crosscheck_scene(scene, math.radians(theta_deg))
    if args.netlist:
        write_text(args.netlist, build(scene, math.radians(theta_deg)).netlist)
    from ..verdict import summary_line, verdict_text

    summary = result.verdict
    if args.json:
        print_json(result.summary())
        return summary["exit"]
    u = args.unit
    sym = frequency_symbol(u)
    print(f"{args.file}: scene {scene.name!r} at θ = {theta_deg:g}°: resonances of the circuit "
          "against the ringing of the time-domain motion after a kick"
          + ("" if u == "rad/s" else f" (frequencies {sym} in {u})"))
    print(f"{'circuit ' + sym + '_n':>14} {'ζ':>9} {'ringing ' + sym + '_n':>14} {'ζ':>9} "
          f"{'rel. diff':>10}  verdict")
    for r in result.resonances:
        ringing = "" if r["ringing_omega"] is None else (
            f" {in_unit(r['ringing_omega'], u):>14.6g} {r['ringing_zeta']:>9.4g} "
            f"{r['rel_error']:>10.2e}")
        print(f"{in_unit(r['omega'], u):>14.6g} {r['zeta']:>9.4g}{ringing}  {verdict_text(r)}")
    if result.forced:
        print("forced response to a drive-speed ripple: |Q0| of the circuit against the "
              "time domain")
        print(f"{sym:>14} {'|Q0| circuit':>16} {'|Q0| time':>16} {'rel. diff':>10}  verdict")
        for f in result.forced:
            print(f"{in_unit(f['omega'], u):>14.6g} {f['Q0_circuit']:>16.8g} "
                  f"{f['Q0_time']:>16.8g} {f['rel_error']:>10.2e}  {verdict_text(f)}")
    print_written(notes=result.notes, indent="")
    print(summary_line(summary))
    return summary["exit"]
