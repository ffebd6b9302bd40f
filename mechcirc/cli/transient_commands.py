"""Sub-command ``transient`` (time domain of any netlist) and the netlist branch of ``crosscheck``."""

from __future__ import annotations

import math
import sys

from ..units import in_unit
from ._common import (Default, add_handler, add_output_option, add_plot_option, check_names,
                      check_output_paths, command, frequency_symbol, print_json, print_written,
                      real, refuse_ignored, shaft_speed, write_outputs)

seconds = real(above=0.0, unit="s", role="time")


@command("transient", "time response of a netlist (exact for linear circuits; backlash)",
         "Integrate a netlist from its .ic state: node displacements and velocities, every "
         "element's force and the drive's force (velocity drive) or velocity (force drive) on the "
         "grid 0, dt, ..., t_end. Linear circuits are propagated exactly between drive samples "
         "(matrix exponential); springs with backlash= use the Modelica ElastoBacklash law and an "
         "adaptive Dormand-Prince 5(4) integrator.",
         "Examples:\n"
         "  mechcirc transient examples/msl_backlash.mcir --t-end 1 --dt 1e-3 -o msl.csv\n"
         "  mechcirc transient netlists/stb_heald.mcir --t-end 0.05 --waveform harmonic:300 --json",
         file="netlist (.mcir); a drive line is optional")
def register(p) -> None:
    p.add_argument("--t-end", type=seconds, required=True, metavar="T",
                   help="end time [s]; or with a unit: 50ms")
    p.add_argument("--dt", type=seconds, metavar="DT",
                   help="output step [s] (default t_end/2000; 40 per period of a harmonic drive)")
    p.add_argument("--waveform", metavar="WAVE",
                   help="the drive's waveform in time: harmonic:OMEGA (rad/s, or with a unit: "
                        "50Hz), step, impulse, csv:PATH (time,value samples, interpolated "
                        "linearly) or rest (default: the drive stays at rest)")
    p.add_argument("--rpm", type=shaft_speed, metavar="RPM",
                   help="shaft speed [rev/min] of a drive given by its motion over a "
                        "revolution (drive ... motion=LAW or motion=TABLE.csv); required "
                        "for such a drive")
    p.add_argument("--amplitude", type=real(), metavar="A",
                   help="amplitude of harmonic/step/impulse (default: the netlist's)")
    p.add_argument("--rtol", type=real(above=0.0), default=Default(1e-10), metavar="TOL",
                   help="relative tolerance with clearances, 1e-12 to 0.1 (default 1e-10; "
                        "the absolute one is TOL x each state's peak)")
    add_output_option(p, "write the time series as CSV")
    add_plot_option(p, "plot node displacements, each clearance's deformation with its band "
                       "±B/2 and contact phases, and the --element forces")
    p.add_argument("--element", action="append", metavar="NAME",
                   help="with --plot: a panel of this element's force (repeatable)")
    add_handler(p, cmd_transient)


def cmd_transient(args) -> int:
    from ..netlist import load
    from ..transient import parse_waveform, transient
    from ..transient.model import backlash_elements

    check_output_paths(args.output, plots=(args.plot,), reads=(args.file,), table="a CSV table")
    wave = None if args.waveform is None else parse_waveform(args.waveform)   # read once
    shaped = args.rpm is not None or getattr(wave, "kind", "") in ("harmonic", "step", "impulse")
    refuse_ignored(args, {"--amplitude": (shaped, "a harmonic, step or impulse --waveform or a "
                                          "motion= drive at --rpm", "add --waveform "
                                          "harmonic:OMEGA, step or impulse"),
                          "--element": (args.plot, "a panel of the --plot", "add --plot IMAGE")})
    circuit = load(args.file, require_drive=False)
    refuse_ignored(args, {"--rtol": (bool(backlash_elements(circuit)), "netlists with a "
                                     "clearance (backlash=); without one the run is exact", "")})
    check_names(args.element, [e.name for e in circuit.elements])   # before the run
    result = transient(circuit, args.t_end, args.dt, wave, amplitude=args.amplitude,
                       rtol=args.rtol, rpm=args.rpm)
    write_outputs(args, result.columns().items(), lambda: result.plot(elements=args.element),
                  fmt=result.CSV_FORMAT)
    if args.json:
        return print_json(result.to_json())
    for n in result.notes:
        print(f"note: {n}", file=sys.stderr)
    print(f"{circuit.name}: {result.time.size} samples, t = 0 .. {result.time[-1]:.6g} s; "
          f"{result.method}; estimated error of x {result.error:.3g}")
    u = result.units
    w = max([10] + [len(n) for n in result.nodes + result.elements])
    print(f"{'node':>{w}} {'x(end) [' + u['x'] + ']':>14} {'v(end) [' + u['v'] + ']':>14} "
          f"{'max|x| [' + u['x'] + ']':>14}")
    v = result.v
    assert v is not None            # the CLI always asks for the velocities
    for i, n in enumerate(result.nodes):
        print(f"{n:>{w}} {result.x[-1, i]:14.6g} {v[-1, i]:14.6g} "
              f"{abs(result.x[:, i]).max():14.6g}")
    print(f"{'element':>{w}} {'max|F| [' + u['Q'] + ']':>14}")
    for j, e in enumerate(result.elements):
        print(f"{e:>{w}} {abs(result.force[:, j]).max():14.6g}")
    if result.drive_force is not None:
        what = "moment" if u["Q"] == "N·m" else "force"
        print(f"drive {what}: max |F| = {abs(result.drive_force).max():.6g} {u['Q']}")
    if result.drive_velocity is not None:
        print(f"drive velocity: max |v| = {abs(result.drive_velocity).max():.6g} {u['v']}")
    _print_separations(result, u)
    return 0


#: Openings of a contact listed one by one (the rest are counted).
SHOWN = 8


def _print_separations(result, u) -> None:
    """Each clearance's contact openings: when (shaft angle), for how long, impact velocity."""
    for name in result.clearances:
        seps = [s for s in result.separations if s.element == name]
        if not seps:
            print(f"contact {name}: never opened after closing")
            continue
        print(f"contact {name}: opened {len(seps)} time(s)")
        for s in seps[:SHOWN]:
            when = (f"at θ = {s.angle_deg:.4f} deg (revolution {s.revolution}), "
                    if s.revolution >= 0 else "") + f"t = {s.t_open:.6g} s"
            span = (f"{s.duration_deg:.4f} deg, " if s.revolution >= 0 else "") + \
                f"{s.duration:.4g} s"
            print(f"  {when}: " + ("still open at the end" if math.isnan(s.t_close) else
                                   f"open {span}; impact velocity {s.impact_velocity:.6g} {u['v']}"))
        if len(seps) > SHOWN:
            print(f"  ... {len(seps) - SHOWN} more (--json lists all)")


def cmd_crosscheck_netlist(args) -> int:
    """``mechcirc crosscheck FILE.mcir``: frequency domain vs transients of any netlist."""
    from ..netlist import load
    from ..transient import crosscheck

    circuit = load(args.file)
    from ..progress import Progress

    with Progress(0, f"{circuit.name}: crosscheck") as bar:   # total set by crosscheck
        result = crosscheck(circuit, omega_max=args.omega_max, progress=bar)
    from ..verdict import summary_line, verdict_text

    summary = result.verdict
    if args.json:
        print_json(result.to_json())
        return summary["exit"]
    print_written(notes=result.notes, indent="")
    print(f"{circuit.name}: {result.drive_kind} drive")
    fu = args.unit
    sym = frequency_symbol(fu)
    print(f"(a) resonances / anti-resonances vs ringing of the impulse response [{fu}]; "
          "rel. diff = |s_time − s_freq| / |s_freq| of the pole s = −σ + iω_d")
    for r in result.resonances:
        ringing = "" if r["ringing_omega_d"] is None else (
            f"  ringing {in_unit(r['ringing_omega_d'], fu):12.6g}  decay {r['decay']:.5g} 1/s "
            f"(expected {r['decay_expected']:.5g})  rel. diff {r['rel_error']:.2e}")
        print(f"    {r['kind']:>13} {sym}_d {in_unit(r['omega_d'], fu):12.6g}{ringing}: "
              f"{verdict_text(r)}")
    from ..circuit import units_of

    u = units_of(circuit.drive)
    label = f"|Q0| [{u['Q']}]" if result.drive_kind == "velocity" else f"|v0| [{u['v']}]"
    print(f"(b) {label} from the sweep vs the harmonic transient started in its periodic "
          f"steady state, at {sym} [{fu}]")
    for s in result.steady_state:
        measured = "" if s["measured"] is None else (
            f" sweep {s['expected']:.8g}  transient {s['measured']:.8g}  rel. diff "
            f"{s['rel_error']:.2e} (departure from a sinusoid {s['periodic_deviation']:.1e}):")
        print(f"    {sym} {in_unit(s['omega'], fu):12.6g}:{measured} {verdict_text(s)}")
    print(summary_line(summary))
    return summary["exit"]
