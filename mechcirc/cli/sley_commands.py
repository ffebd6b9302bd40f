"""Sub-commands on the sley (beat-up) model: ``simulate`` and ``crosscheck``."""

from __future__ import annotations

import math

from ..errors import InputError
from ..limits import (MAX_POINTS_PER_REVOLUTION, MAX_REVOLUTIONS, MAX_SCIPY_REVOLUTIONS,
                      METHODS, SCIPY_METHODS)
from ..progress import Progress
from ..units import FREQUENCY_UNITS, in_unit
from ._common import (Default, add_handler, add_output_option, add_plot_option, add_unit_option,
                      check_output_paths, command, commands, count, crank_angle, positive_omega,
                      print_json, print_written, real, refuse_ignored, set_values, write_outputs,
                      write_text)

_UNITS = {"eps4T": "rad/s^2", "eps2P": "rad/s^2", "eps4P": "rad/s^2", "eps5P": "rad/s^2",
          "M2V": "N m", "M5V": "N m"}


@command("simulate", "sley beat-up dynamics (Mrázek, Tables 1 and 2) in the time domain",
         "Integrate the sley model (eq. 4 one-side, eq. 9 both-sides; the presets run as their "
         "scenes, examples/mrazek_*.toml) from the crank angle of zero sley acceleration over R "
         "revolutions and print the min/max of the last one beside the paper's printed values. The "
         "beat-up interval alpha is not printed in the paper: default 10 deg, the best fit to the "
         "printed cells (sigma = alpha).",
         "Example: mechcirc simulate --drive one-side --variant 3 --plot sley.png\n"
         "         mechcirc simulate --variant all --json")
def _register_simulate(p) -> None:
    p.add_argument("scene", nargs="?", metavar="SCENE.toml",
                   help="simulate this scene file over whole revolutions (docs/scenes.md); "
                        "without it, the sley presets (--drive, --variant)")
    p.add_argument("--omega", type=positive_omega, metavar="W",
                   help="crank shaft speed [rad/s; or 955rpm] (default the file's or the preset's)")
    p.add_argument("--start-deg", type=crank_angle, metavar="DEG",
                   help="scene: crank rotation from the pose at t = 0 (default the file's, "
                        "else 0)")
    p.add_argument("--no-error-estimate", action="store_true",
                   help="skip the half-step rerun that estimates the error")
    _sley_arguments(p)
    add_plot_option(p, "plot eps2P, eps4P, eps4T, M2V (Figs. 4-9)")
    add_handler(p, cmd_simulate)
    p.add_argument("--shaft", action="store_true", default=Default(False),
                   help="scene: the dynamic main shaft of its [shaft] table (flywheel, motor) "
                        "turning the mechanism with its elastic parts: speed fluctuation, "
                        "motor torque, elastic forces, start-up")
    p.add_argument("--rigid", action="store_true", default=Default(False),
                   help="with --shaft: every elastic element rigid (θ the only DOF)")
    p.add_argument("--flywheel", type=real(least=0.0, unit="kg·m²"), metavar="J",
                   help="with --shaft: the flywheel's inertia [kg·m²] (default the file's)")


def _sley_arguments(p) -> None:
    """simulate's options for the sley presets and the integration."""
    p.add_argument("--drive", choices=("one-side", "both-sides"), default=Default("one-side"),
                   help="Table 1 (one-side, default) or Table 2 (both-sides)")
    p.add_argument("--variant", metavar="N", default=Default("3"),
                   help="variant 1-7 (default 3), or 'all' for all 14 of both tables "
                        "on every core")
    p.add_argument("--revolutions", type=count(1, MAX_REVOLUTIONS), metavar="R",
                   help="revolutions to integrate; the last is tabulated (default 5)")
    p.add_argument("--revolution", type=count(1, MAX_REVOLUTIONS), metavar="K",
                   help="tabulate revolution K (1..R) instead of the last")
    p.add_argument("--alpha", type=real(above=0.0, most=360.0, unit="deg", role="angle"),
                   default=Default(10.0), metavar="DEG",
                   help="beat-up interval alpha [deg] (default 10, the best fit to the "
                        "printed cells; not printed in the paper)")
    p.add_argument("--beat-sign", type=int, choices=(-1, 1), default=Default(-1),
                   help="sign of M4 in the sley equation: -1 as eq. (4) prints it (default), "
                        "+1 along the rigid acceleration at beat-up (see docs/sley.md)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override a parameter, in SI or a unit of its kind, e.g. --set "
                        "clearance=0.002 or clearance=0.1deg (repeatable)")
    p.add_argument("--method", choices=METHODS,
                   help="integrator (default rk4, and rk8 for a rigid --shaft; numba if "
                        "installed, else pure Python; "
                        "rk8: DOP853's 8th-order formula at a fixed step; "
                        "DOP853, RK45, LSODA: scipy's, with --rtol)")
    p.add_argument("--rtol", type=real(above=0.0, most=1.0), metavar="TOL",
                   help="relative tolerance of the scipy methods (default 1e-10)")
    p.add_argument("--steps-per-period", type=real(least=1.0, most=1e6), metavar="N",
                   help="rk4 or rk8 steps per period of the fastest mode (default: 25, or 50 "
                        "if the error estimate at 25 exceeds 1e-3; rk8: 8, or 16; --shaft: "
                        "rk4 100, rk8 16)")
    p.add_argument("--points", type=count(16, MAX_POINTS_PER_REVOLUTION), metavar="N",
                   help="output points per revolution (default 7200, i.e. 0.05 deg)")
    add_output_option(p, "write the curves as CSV")


@command("crosscheck", "a netlist, scene or sley preset's circuit against its time domain",
         "(a) resonances (K = 0) of the sley's netlist at crank angle theta against the "
         "eigenfrequencies of the linearised equations; (b) ringing of the sley after the beat-up "
         "pulse against the predicted damped frequency; (c) harmonic forcing of the netlist in "
         "time (its periodic steady state) against |Q0| of its sweep.",
         "Example: mechcirc crosscheck --drive one-side --variant 3 --theta 60\n"
         "         mechcirc crosscheck examples/heald_scene.toml --theta 40\n"
         "         mechcirc crosscheck netlists/stb_heald.mcir --omega-max 5000\n"
         "(a scene .toml: circuit resonances at --theta against the ringing of its time-domain "
         "motion, and |Q0| against the forced response to a drive-speed ripple; a netlist: see the "
         "transient command)")
def _register_crosscheck(p) -> None:
    p.add_argument("file", nargs="?", metavar="FILE",
                   help="a scene (.toml): cross-check it at --theta; a netlist (.mcir): "
                        "cross-check its resonances and |Q0| against its transients")
    p.add_argument("--omega-max", type=positive_omega, metavar="W",
                   help="with a netlist FILE: check resonances up to W [rad/s, or 50Hz] "
                        "(default 1.5 x the highest)")
    p.add_argument("--drive", choices=("one-side", "both-sides"), default=Default("one-side"),
                   help="sley preset: the drive's layout (default one-side)")
    p.add_argument("--variant", type=int, choices=range(1, 8), default=Default(3), metavar="N",
                   help="sley preset: variant 1-7 (default 3)")
    p.add_argument("--theta", type=crank_angle, metavar="DEG",
                   help="crank angle of the linearisation [deg] (default: the start angle, "
                        "where the sley's rigid acceleration is zero)")
    p.add_argument("--netlist", metavar="FILE",
                   help="also write the netlist built from the scene or the sley preset "
                        "(refused with a netlist FILE: that file is the netlist used)")
    add_unit_option(p, "show frequencies in rad/s (omega, the default), Hz (f = omega/2 pi) "
                       "or rpm (n = 60 omega/2 pi); --json stays in rad/s")
    add_handler(p, cmd_crosscheck)


register = commands(_register_simulate, _register_crosscheck)


# ------------------------------------------------------------------ helpers
#: Names --set cannot take (it sets numbers), and what to use instead.
_NOT_NUMBERS = {"drive": "choose the layout with --drive one-side|both-sides",
                "variant": "choose the table row with --variant 1-7|all",
                "label": "the label is text naming the variant, set by --drive and --variant"}


def _overrides(args) -> dict:
    from ..sley.models import UNIT_ROLES

    out = {"alpha": math.radians(args.alpha), "beat_sign": args.beat_sign}
    # SI, or in a unit of the parameter's kind: omega=3000rpm, clearance=0.1deg
    return out | set_values(args.set, _NOT_NUMBERS, roles=UNIT_ROLES)


def _options(args) -> dict:
    if args.method in SCIPY_METHODS and args.revolutions > MAX_SCIPY_REVOLUTIONS:
        raise InputError(f"--revolutions {args.revolutions} with --method {args.method}: the "
                         f"limit is {MAX_SCIPY_REVOLUTIONS} (a Python right-hand side, ~0.3 s "
                         "a revolution); the compiled rk4 takes up to "
                         f"{MAX_REVOLUTIONS}")
    # None (rtol, steps_per_period, revolution): the method's default
    return {"points_per_revolution": args.points, "revolution": args.revolution,
            "rtol": args.rtol, "steps_per_period": args.steps_per_period,
            "error_estimate": not args.no_error_estimate}


#: Overrides that change only how the paper is read (the beat-up window it did
#: not print), not the case it computed: the paper's columns still apply.
_READINGS = {"alpha", "sigma", "beat_sign"}


def _table(result, paper_applies: bool = True) -> str:
    from ..sley import PAPER

    p = result.params
    variant = int(p.label.split()[-1]) if p.label.split()[-1:] and \
        p.label.split()[-1].isdigit() else None
    paper = PAPER.get(p.drive, {}).get(variant, {}) if paper_applies and variant else {}
    speed = f"{result.wall_time * 1e3:.1f} ms" + (
        f" + {result.compile_time:.2f} s compile/cache load" if result.compile_time else "")
    lines = [f"{p.label or p.drive}: revolution {result.revolution}, alpha = "
             f"{result.alpha_deg:g} deg, method {result.method} ({result.backend}), {speed}",
             f"{'quantity':<9} {'unit':<7} {'min':>10} {'max':>10}   {'paper min':>10} "
             f"{'paper max':>10}"]
    for key in [k for k in _UNITS if k in result.extrema]:
        lo, hi = result.extrema[key]
        plo, phi = paper.get(key, ("-", "-"))
        lines.append(f"{key:<9} {_UNITS[key]:<7} {lo:>10.0f} {hi:>10.0f}   {plo!s:>10} {phi!s:>10}")
    total = result.M2V if result.M5V is None else result.M2V + result.M5V
    name = "-M2V*" if result.M5V is None else "-(M2+M5)*"
    plo, phi = paper.get("M2V", ("-", "-"))
    lines.append(f"{name:<9} {'N m':<7} {-total.max():>10.0f} {-total.min():>10.0f}   "
                 f"{plo!s:>10} {phi!s:>10}")
    if paper_applies:
        both = " and the sum of both cranks" if result.M5V is not None else ""
        lines.append(f"* the paper's printed moments fit this sign{both} (docs/sley.md)")
    else:
        lines.append("* changed parameters: the paper did not compute this case ('-' columns)")
    # (a note "warning: ..." is the SleyAccuracyWarning the command prints as a warning)
    lines.extend(f"note: {n}" for n in result.notes if not n.startswith("warning: "))
    return "\n".join(lines)


# ----------------------------------------------------------------- handlers
def _refuse_unread(args) -> None:
    """simulate's options that the input (a sley preset or a scene file) or --shaft leaves
    unread are refused (:func:`refuse_ignored`)."""
    preset_only = (args.scene is None, f"a sley preset, not to the scene {args.scene}", "")
    with_shaft = (args.shaft, "--shaft", "add --shaft")
    refuse_ignored(args, {"--drive": preset_only, "--variant": preset_only,
                          "--alpha": preset_only, "--beat-sign": preset_only,
                          "--start-deg": (args.scene is not None, "a scene file; the presets "
                                          "start where the rigid sley acceleration is zero, as "
                                          "the paper", ""),
                          "--shaft": (args.scene is not None, "a scene file's [shaft] table, "
                                      "not to a sley preset", ""),
                          "--rigid": with_shaft, "--flywheel": with_shaft,
                          **{o: (not args.shaft, "a fixed crank speed, not to --shaft's steady "
                                 "cycle", "") for o in ("--revolutions", "--revolution",
                                                        "--plot")}})


def cmd_simulate(args) -> int:
    _refuse_unread(args)
    if args.scene is not None:
        from .scene_commands import cmd_simulate_scene

        return cmd_simulate_scene(args)
    from ..sley import (PAPER, ParameterError, all_presets, preset, simulate_batch,
                        simulate_params)

    args.revolutions = 5 if args.revolutions is None else args.revolutions
    args.points = 7200 if args.points is None else args.points
    args.method = args.method or "rk4"
    check_output_paths(args.output, plots=(args.plot,), table="a CSV table")
    over = _overrides(args)
    if args.omega is not None:
        over["omega"] = args.omega
    paper_applies = set(over) <= _READINGS     # the paper computed this case
    opts = _options(args)
    if args.variant == "all":
        if args.output or args.plot:
            raise ParameterError("-o/--plot need one variant, not --variant all")
        results = simulate_batch(all_presets(**over), args.revolutions, args.method, **opts)
        if args.json:
            return print_json({"results": [r.summary() for r in results]})
        print("\n\n".join(_table(r, paper_applies) for r in results))
        return 0
    try:
        variant = int(args.variant)
    except ValueError:
        raise ParameterError(f"--variant must be 1-7 or 'all', got {args.variant!r}") from None
    params = preset(args.drive, variant, **over)
    with Progress(0, params.label) as bar:     # total set by the first progress(done, total)
        result = simulate_params(params, args.revolutions, args.method, progress=bar, **opts)
    from ..sley.plots import plot_result

    write_outputs(args, result.columns().items(), lambda: plot_result(result),
                  f"# {result.params.label}; revolution {result.revolution}; "
                  f"alpha = {result.alpha_deg:g} deg; method {result.method}")
    if args.json:
        doc = result.summary()
        if paper_applies:
            doc["paper"] = {k: list(v) for k, v in PAPER[params.drive][variant].items()}
        return print_json(doc)
    print(_table(result, paper_applies))
    return 0


#: crosscheck's options that apply to some inputs only (the input's kind is a word of it).
_CROSSCHECK_APPLIES = {"--drive": "a sley preset", "--variant": "a sley preset",
                       "--omega-max": "a netlist FILE", "--theta": "a scene or a sley preset",
                       "--netlist": "a scene or a sley preset"}


def cmd_crosscheck(args) -> int:
    kind = "preset" if args.file is None else "scene" if args.file.endswith(".toml") else "netlist"
    given = {"preset": "without a FILE a sley preset is checked", "scene":
             f"'{args.file}' is a scene", "netlist": f"'{args.file}' is a netlist already"}[kind]
    refuse_ignored(args, {opt: (kind in where, f"{where}; {given}", "")
                          for opt, where in _CROSSCHECK_APPLIES.items()})
    if kind == "scene":
        from .scene_commands import cmd_crosscheck_scene

        return cmd_crosscheck_scene(args)
    if kind == "netlist":
        from .transient_commands import cmd_crosscheck_netlist

        return cmd_crosscheck_netlist(args)
    from ..sley import preset
    from ..sley.crosscheck import crosscheck_sley
    from ..sley.simulation import start_angle

    check_output_paths(args.netlist, table="the netlist", option="--netlist")
    params = preset(args.drive, args.variant)
    theta0 = start_angle(params) if args.theta is None else math.radians(args.theta)
    with Progress(4, "crosscheck") as bar:      # drawn on a terminal after 1 s
        doc, netlist = crosscheck_sley(params, theta0, on_step=bar.update)
    if args.netlist:
        write_text(args.netlist, netlist)
    if args.json:
        print_json(doc)
    else:
        _print_sley_crosscheck(doc, args.unit)
    return doc["summary"]["exit"]


def _print_sley_crosscheck(doc: dict, u: str = "rad/s") -> None:
    from ..verdict import summary_line, verdict_text

    print(f"{doc['label']}, linearised at crank angle {doc['theta_deg']:.4f} deg")
    print(f"(a) resonances K = 0 of the netlist against the eigenfrequencies [{u}]")
    for row in doc["resonances"]:
        tag = "damped  " if row["damping"] else "undamped"
        for e, ed, w, wd in zip(row["eigen_omega"], row["eigen_omega_d"],
                                row["circuit_omega"], row["circuit_omega_d"]):
            print(f"    {tag} eigen {in_unit(e, u):14.8f} (d {in_unit(ed, u):12.6f})   circuit "
                  f"{in_unit(w, u):14.8f} (d {in_unit(wd, u):12.6f})")
        print(f"    {tag} largest relative difference {row['rel_error']:.2e} "
              f"({row['how']}): {verdict_text(row)}")
    ring = doc["ringing"]
    if ring["omega_measured"] is None:
        print(f"(b) ringing after beat-up: {verdict_text(ring)}")
    else:
        print(f"(b) ringing after beat-up at {ring['theta_mid_deg']:.1f} deg: measured "
              f"{in_unit(ring['omega_measured'], u):.3f} {u}, predicted "
              f"{in_unit(ring['omega_predicted'], u):.3f} {u}, difference "
              f"{ring['rel_error']:.2e}: {verdict_text(ring)}")
    print_written(notes=ring["notes"], indent="    ")
    print("(c) harmonic forcing of the netlist in time, |Q0|/V0 [N m s/rad]"
          + ("" if u == "rad/s" else f" at {FREQUENCY_UNITS[u][0]} [{u}]"))
    for row in doc["harmonic"]["rows"]:
        print(f"    {FREQUENCY_UNITS[u][0]} {in_unit(row['omega'], u):10.3f}: time domain "
              f"{row['q0_time']:.6g}, circuit {row['q0_circuit']:.6g}, difference "
              f"{row['rel_error']:.2e}: {verdict_text(row)}")
    print(f"    ({doc['harmonic']['how']})")
    print(summary_line(doc["summary"]))
