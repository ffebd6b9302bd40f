"""Sub-commands that reach into the ecosystem: ``forces``, ``compare``, ``formula``, ``study``."""

from __future__ import annotations

from pathlib import Path

from ..errors import MechcircError, did_you_mean
from ..limits import FORMULA_SECONDS
from ._common import (NETLIST_FILE, Default, add_handler, add_method_option, add_output_option,
                      add_plot_option, add_unit_option, band_omega, check_output_paths, command,
                      commands, count, fields_of, frequency_text, load_with_warnings, own_units,
                      positive_omega, print_json, print_written, real, refuse_ignored, save_figure,
                      time_limit, warning_lines)


@command("forces", "force and velocity of every element at one frequency",
         "How the drive's force splits through the mechanism: |Q| [N], |v| [m/s] and their phases "
         "[deg] (relative to the drive's amplitude) for every element carrying force, at one "
         "angular frequency.",
         "Example: mechcirc forces netlists/stb_heald.mcir --omega 300 --plot forces.png",
         file=NETLIST_FILE)
def _register_forces(p) -> None:
    p.add_argument("--omega", type=positive_omega, required=True, metavar="W",
                   help="angular frequency: rad/s, or with a unit: 50Hz, 3000rpm")
    add_unit_option(p, "show the frequency in rad/s (omega, the default), Hz or rpm (--json "
                       "stays in rad/s)")
    _method_plot_json(p, "bar chart of |Q| per element (PNG, SVG, PDF)", cmd_forces)


def _method_plot_json(p, plot: str, func) -> None:
    """The options ``forces`` and ``compare`` end with: --method, --plot (``plot``: what it
    draws), --json; and the command's function."""
    add_method_option(p, "series–parallel tree, nodal analysis, or auto (default)")
    add_plot_option(p, plot)
    add_handler(p, func)


@command("compare", "a measured mobility (Touchstone .s1p) against the model's",
         "Read a measured one-port mobility from a Touchstone file (its Z parameter, read with "
         "scikit-rf, taken in m/(N·s)), evaluate the netlist at the same frequencies and print the "
         "error in the band.",
         "Example: mechcirc compare netlists/stb_heald.mcir measured.s1p --plot cmp.png",
         file=NETLIST_FILE, raw=False)
def _register_compare(p) -> None:
    p.add_argument("measured", help="Touchstone one-port file (.s1p)")
    p.add_argument("--omega-min", type=band_omega, metavar="W1",
                   help="compare only from this angular frequency [rad/s] (or 5Hz, 300rpm)")
    p.add_argument("--omega-max", type=band_omega, metavar="W2",
                   help="compare only up to this angular frequency [rad/s] (or 50Hz, 3000rpm)")
    _method_plot_json(p, "overlay |K| and phase (PNG, SVG or PDF)", cmd_compare)


@command("formula", "K(ω) in closed form (SymPy), nested as the reduction tree",
         "The kinematic characteristic K(ω) [m/(N·s)] as a formula built from the series–parallel "
         "reduction tree: elements written as plain numbers become symbols named after them, "
         ".param names stay symbols; the values are listed below. Needs SymPy (pip install "
         "'mechcirc[formula]').",
         "Example: mechcirc formula netlists/stb_heald.mcir --latex",
         file=NETLIST_FILE, raw=False)
def _register_formula(p) -> None:
    p.add_argument("--latex", action="store_true", help="print LaTeX instead of SymPy text")
    p.add_argument("--expand", action="store_true",
                   help="one fraction, numerator and denominator multiplied out")
    p.add_argument("--numeric", action="store_true",
                   help="substitute the values (exact rationals); only omega stays a symbol")
    add_handler(p, cmd_formula, json=False)


@command("study", "a parameter grid or sample, on local cores or a Dask cluster",
         "Run a parameter study described by a TOML file (see docs/ecosystem.md): a grid, a "
         "random, Latin hypercube or Sobol sample, or the points of a CSV/Parquet file; each point "
         "re-parses the netlist with new .param values and records a sweep summary or a resonance "
         "table; failed points are rows with their error.  Rows are journalled as they finish (an "
         "interrupted study keeps them; --resume runs only the missing points of the same spec).  "
         "The output records the spec and every column's unit (CSV: OUTPUT.meta.json beside it).",
         "Example: mechcirc study examples/study_stb.toml -o results.csv", raw=False)
def _register_study(p) -> None:
    p.add_argument("spec", help="study description (.toml)")
    add_output_option(p, "write the table to this CSV file")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on an existing Dask cluster (tcp://host:8786); needs "
                        "'mechcirc[study]'")
    p.add_argument("--workers", type=count(1, 1024), metavar="N",
                   help="local processes (default: all cores; 1 = this process)")
    p.add_argument("--resume", action="store_true",
                   help="keep the rows already in -o and run only the missing points "
                        "(refused if -o was made from another spec)")
    p.add_argument("--connect-timeout", type=real(above=0, most=3600, unit="s"),
                   default=Default(10.0), metavar="SECONDS",
                   help="with --scheduler: wait this long for the scheduler, then as long "
                        "for its first worker (default 10)")
    p.add_argument("--curves", metavar="PARQUET",
                   help="also write K(omega) of every point (analysis = \"sweep\") to this "
                        "Parquet file, one row per point and omega: design, omega, K_re, K_im "
                        "(units in its metadata; needs pyarrow)")
    add_plot_option(p, "plot a result column against the parameters (PNG, SVG or PDF)")
    p.add_argument("--plot-column", metavar="NAME",
                   help="the column to plot (default Q0_abs_max for sweeps, resonance_1 "
                        "for resonance tables)")
    add_handler(p, cmd_study)


register = commands(_register_forces, _register_compare, _register_formula, _register_study)


def cmd_forces(args) -> int:
    from ..circuit import units_of
    from ..forces import element_forces
    check_output_paths(plots=(args.plot,), reads=(args.file,))
    circuit, warns = load_with_warnings(args.file)
    rows, K, Q0, flag = element_forces(circuit, args.omega, method=args.method)
    warning_lines(warns)
    if args.plot:
        from ..plotting import plot_forces

        save_figure(plot_forces(rows, omega=args.omega, name=circuit.name,
                                units=units_of(circuit.drive)), args.plot)
    if args.json:
        return print_json({
            "file": args.file, "name": circuit.name, "omega": args.omega, "K": K, "Q0": Q0,
            "flag": flag,
            "elements": [fields_of(r, "name kind n1 n2 Q Q_abs Q_phase_deg v v_abs v_phase_deg "
                                      "share") for r in rows]})
    u = units_of(circuit.drive)
    print(f"{args.file}: {frequency_text(args.omega, args.unit)}, K = {K.real:.6g}{K.imag:+.6g}j {u['K']}, |Q0| = {abs(Q0):.6g} {u['Q']}")
    if flag:
        print("  this omega is on or within rounding of a pole or zero of K (flagged)")
    width = max([len(r.name) for r in rows] + [7])
    print(f"  {'element':<{width}} {'kind':<6} {'|Q| [' + u['Q'] + ']':>12} {'arg Q [deg]':>11} "
          f"{'|Q|/|Q0|':>9} {'|v| [' + u['v'] + ']':>12} {'arg v [deg]':>11}")
    own = own_units(circuit)
    for r in rows:
        print(f"  {r.name:<{width}} {r.kind:<6} {r.Q_abs:>12.5g} {_deg(r.Q_phase_deg):>11.2f} "
              f"{r.share:>9.4f} {r.v_abs:>12.5g} {_deg(r.v_phase_deg):>11.2f}"
              f"{own.get(r.name, '')}")
    print_written(("plot", args.plot))
    return 0


def _deg(x: float) -> float:
    """A phase for printing with two decimals: never '-0.00'."""
    return round(x, 2) + 0.0


def cmd_compare(args) -> int:
    from ..circuit import units_of
    from ..interop.skrf import compare
    check_output_paths(plots=(args.plot,), reads=(args.file, args.measured))
    circuit, warns = load_with_warnings(args.file)
    result = compare(circuit, args.measured, method=args.method,
                     omega_min=args.omega_min, omega_max=args.omega_max)
    summary = result.summary()
    warning_lines(warns)
    if args.plot:
        from ..plotting import plot_comparison

        save_figure(plot_comparison(result, name=circuit.name, measured=args.measured,
                                    units=units_of(circuit.drive)), args.plot)
    if args.json:
        return print_json({"file": args.file, "measured": args.measured, **summary})
    print(f"{args.file} against {args.measured}: {summary['points']} measured points, "
          f"omega {summary['omega_min']:.6g} .. {summary['omega_max']:.6g} rad/s")
    if summary["compared"] < summary["points"]:
        print(f"  {summary['points'] - summary['compared']} point(s) not compared: on or near a "
              "pole or zero of the model's K, or a measured K of 0 (no dB error)")
    if summary["compared"]:
        print(f"  relative error |K_meas - K_model|/|K_model|: max {summary['rel_max']:.3g} "
              f"(at omega {summary['omega_at_rel_max']:.6g} rad/s), median "
              f"{summary['rel_median']:.3g}")
        print(f"  magnitude: RMS {summary['db_rms']:.3g} dB, max {summary['db_max']:.3g} dB; "
              f"phase: max {summary['phase_max_deg']:.3g} deg")
    print_written(("plot", args.plot))
    return 0


def cmd_formula(args) -> int:
    from ..circuit import units_of
    from ..interop.formula import formula_and_values

    circuit, warns = load_with_warnings(args.file)
    warning_lines(warns)
    with time_limit(FORMULA_SECONDS, "the symbolic formula", "evaluate K numerically "
                    "instead: mechcirc sweep FILE --method nodal, or mechcirc forces FILE "
                    "--omega W"):
        K, values = formula_and_values(circuit, expand=args.expand, numeric=args.numeric)
        if args.latex:
            import sympy

            text = f"K(\\omega) = {sympy.latex(K)}"
        else:
            text = f"K(omega) = {K}"
    print(text)
    if not args.numeric and values:
        print(f"where (SI values; K in {units_of(circuit.drive)['K']}, omega in rad/s):")
        for sym in sorted(values, key=lambda s: s.name):
            print(f"  {sym.name} = {values[sym]} ({float(values[sym]):g})")
    return 0


def _plot_column(args, spec) -> str:
    """The result column ``--plot`` draws: ``--plot-column`` (checked, with did-you-mean;
    refused without ``--plot``) or the analysis's default."""
    column = args.plot_column or ("Q0_abs_max" if spec.analysis == "sweep" else "resonance_1")
    results = spec.columns[len(spec.params) + 3:]
    if args.plot and column not in results:
        raise MechcircError(f"--plot-column {column!r} is not a result column"
                            f"{did_you_mean(column, results)} (expected one of "
                            f"{', '.join(results)})")
    return column


def cmd_study(args) -> int:
    from ..progress import Progress
    from ..study import column_units, load_spec, run_study, sidecar_path

    refuse_ignored(args, {"--workers": (not args.scheduler, "local processes, not a "
                                        "--scheduler's cluster", ""),
                          "--connect-timeout": (args.scheduler, "a --scheduler",
                                                "add --scheduler ADDRESS"),
                          "--plot-column": (args.plot, "the --plot", "add --plot IMAGE")})
    if args.resume and not args.output:
        raise MechcircError("--resume needs -o FILE (the table to continue)")
    spec = load_spec(args.spec)
    check_output_paths(args.output, args.curves, plots=(args.plot,),
                       reads=(args.spec, spec.netlist_source), table="a CSV or Parquet table")
    column = _plot_column(args, spec)
    with Progress(len(spec.points), "study") as bar:
        result = run_study(spec, output=args.output, scheduler=args.scheduler,
                           workers=args.workers, resume=args.resume,
                           connect_timeout=args.connect_timeout, on_rows=bar.update,
                           keep_rows=bool(args.json or args.plot or not args.output),
                           curves=args.curves)
    if args.plot:
        from ..plotting import plot_study

        save_figure(plot_study(result, spec.params, column, name=Path(args.spec).stem,
                               units=column_units(spec)), args.plot)
    if args.json:
        return print_json({"spec": args.spec, "spec_sha256": spec.sha256,
                           "netlist": spec.netlist_source, "analysis": spec.analysis,
                           "executor": result.executor, "workers": result.workers,
                           "points": result.count, "resumed": result.skipped,
                           "failed": result.failed, "columns": result.columns,
                           "units": column_units(spec),
                           "rows": [[r.get(c, None) for c in result.columns]
                                    for r in result.rows]})
    where = {"dask": f"Dask cluster {args.scheduler} ({result.workers} threads)",
             "local": f"{result.workers} local processes",
             "inline": "this process"}[result.executor]
    model = spec.netlist_source if spec.sley is None else \
        f"the sley model, {spec.sley[0]} variant {spec.sley[1]}"
    print(f"{args.spec}: {result.count} points of {model} ({spec.analysis}) on {where}")
    if result.skipped:
        print(f"  {result.skipped} point(s) kept from {args.output}")
    if result.failed:
        print(f"  {result.failed} point(s) failed (status 'error', message in column 'error')")
        for r in [r for r in result.rows if r["status"] != "ok"][:3]:
            print(f"    point {r['index']}: {r['error']}")
    if args.output:
        meta = "" if args.output.lower().endswith(".parquet") else \
            f" (spec and units in {sidecar_path(args.output)})"
        print(f"  table written to {args.output}{meta}")
    print_written(("K(omega) of every point", args.curves), (f"plot of {column}", args.plot))
    return 0
