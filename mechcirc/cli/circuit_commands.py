"""Sub-commands on netlists: ``check`` and ``sweep``."""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

from ..errors import MechcircError, NotSeriesParallelError, PeakAccuracyWarning, SolverError
from ..limits import (
    MAX_ADAPTIVE_NODAL_POINTS,
    MAX_ADAPTIVE_POINTS,
    MAX_JSON_POINTS,
    MAX_NODAL_POINTS,
    MAX_PLOT_POINTS,
    MAX_SWEEP_POINTS,
)
from ..units import FREQUENCY_UNITS, in_unit
from ._common import (NETLIST_FILE, Default, add_handler, add_method_option, add_output_option,
                      add_plot_option, add_unit_option, check_names, check_output_paths, command,
                      commands, fields_of, frequency_text, load_with_warnings, own_units,
                      positive_omega, print_json, print_written, real, refuse_ignored, save_figure,
                      warning_lines)

#: argparse type: an angular frequency [rad/s], or with a unit (``50Hz``, ``3000rpm``); the
#: command checks the range (a sweep's --omega-min/--omega-max together).
omega_value = real(unit="rad/s", role="omega", finite=False)
omega_value.__name__ = "frequency"


@command("check", "parse a netlist and show its elements and reduction tree",
         "Parse a netlist, list elements and nodes, warnings, and the series–parallel reduction "
         "tree seen from the drive.",
         "Example: mechcirc check netlists/stb_heald.mcir", file=NETLIST_FILE)
def _register_check(p) -> None:
    add_handler(p, cmd_check)
    p.add_argument("--explain", action="store_true",
                   help="write the series–parallel reduction out step by step, with the "
                        "lever reflections (K/r², m·r²) and each element's value·η")


@command("sweep", "K(ω) and Q0(ω) over a frequency range",
         "Sweep the kinematic characteristic K = v/Q [m/(N·s)] and the force amplitude Q0 = V0/K "
         "[N] over ω [rad/s].",
         "Example: mechcirc sweep netlists/stb_heald.mcir --omega-min 10 --omega-max 1e4 --points "
         "400 --log -o K.csv --plot K.png", file=NETLIST_FILE, raw=False)
def _register_sweep(p) -> None:
    p.add_argument("--omega-min", type=omega_value, required=True, metavar="W1",
                   help="lowest angular frequency [rad/s]; or with a unit: 5Hz, 300rpm")
    p.add_argument("--omega-max", type=omega_value, required=True, metavar="W2",
                   help="highest angular frequency [rad/s]; or with a unit: 50Hz, 3000rpm")
    p.add_argument("--points", type=int, default=200, metavar="N",
                   help="number of frequency points (default 200)")
    p.add_argument("--log", action="store_true", help="space the points logarithmically")
    add_output_option(p, "write omega,K_re,K_im,Q0_re,Q0_im to this CSV file")
    add_plot_option(p, "plot |K| and |Q0| (PNG, SVG or PDF)")
    p.add_argument("--touchstone", metavar="S1P",
                   help="write K as Z parameters in a Touchstone file (.s1p) that scikit-rf "
                        "reads; f = omega/(2 pi) in Hz, K in m/(N·s) (not ohms)")
    add_method_option(p, "series–parallel tree, nodal analysis, or auto (tree where possible; "
                         "default)")
    p.add_argument("--adaptive", action="store_true",
                   help="refine the grid around resonances and wherever |K| or |Q0| "
                        "bends (--points is then the starting grid)")
    p.add_argument("--refine", action=argparse.BooleanOptionalAction, default=Default(True),
                   help="nodal analysis: refine each solution with residuals in double-"
                        "double (the default, K to about its rounding); --no-refine: one "
                        "plain solve per point, faster, error about eps·cond(A) (the "
                        "'error' estimate says how large); no effect on the tree")
    p.add_argument("--tol", type=real(above=0.0, most=1.0), default=Default(0.005),
                   help="adaptive: largest relative midpoint deviation (default 0.005)")
    p.add_argument("--sensitivity", action="append", metavar="NAME", default=[],
                   help="also the exact derivative of |Q0| (|v0| under a force drive) with "
                        "respect to the element value, lever ratio or .param NAME: CSV "
                        "columns dQ0_dNAME and relQ0_NAME = (p/|Q0|)·d|Q0|/dp (dv0_dNAME, "
                        "relv0_NAME under a force drive; repeatable)")
    add_unit_option(p)
    p.add_argument("--node", action="append", default=[], metavar="NAME",
                   help="also this node's velocity and displacement amplitude against the "
                        "frame (CSV columns v_abs(NAME), x_abs(NAME); a plot panel); repeatable")
    p.add_argument("--element", action="append", default=[], metavar="NAME",
                   help="also the force amplitude through this element (CSV column "
                        "Q_abs(NAME); a plot panel); repeatable")
    add_handler(p, cmd_sweep)


@command("resonances", "exact resonances (K = 0) and anti-resonances (K = ∞)",
         "Natural frequencies seen from the drive, from the network's matrices: resonances (K = 0, "
         "Q0 → ∞ under kinematic excitation; the drive held) and anti-resonances (K → ∞; the drive "
         "released). Damped networks also get the damping ratio.",
         "Example: mechcirc resonances netlists/stb_heald.mcir --omega-max 5000",
         file=NETLIST_FILE, raw=False)
def _register_resonances(p) -> None:
    p.add_argument("--omega-max", type=positive_omega, metavar="W",
                   help="report only up to this angular frequency [rad/s]; or with a unit: "
                        "50Hz, 3000rpm")
    p.add_argument("--modes", action="store_true",
                   help="also each mode: node velocities (largest 1), each mass's and "
                        "spring's share of the energy, each damper's part of zeta, and "
                        "each element's velocity and force")
    p.add_argument("--sensitivity", action="store_true",
                   help="also the relative sensitivity (p/omega)·d(omega)/dp of each root to "
                        "every element value, lever ratio and .param, ranked, with what "
                        "would raise omega by 10 %% (a linear estimate)")
    add_plot_option(p, "plot the mode shapes (PNG, SVG or PDF)")
    add_unit_option(p)
    add_handler(p, cmd_resonances)


register = commands(_register_check, _register_sweep, _register_resonances)


def _tree_text(circuit) -> str:
    """The reduction tree as text, or why there is none (nodal analysis is used)."""
    try:
        return str(circuit.tree)
    except NotSeriesParallelError as exc:
        return f"(not series–parallel: {exc.message}; nodal analysis is used)"


def cmd_check(args) -> int:
    circuit, warns = load_with_warnings(args.file)
    elements = [fields_of(e, "name kind n1 n2 value eta line") for e in circuit.elements]
    levers = [fields_of(lv, "name p1 p2 s1 s2 ratio line") for lv in circuit.levers]
    d = circuit.drive
    tree, unloaded = _tree_text(circuit), circuit.unloaded
    doc = {
        "file": args.file, "name": circuit.name,
        "drive": {**fields_of(d, "name n1 n2 kind amplitude"),
                  **({"motion": d.motion.spec} if d.motion is not None else {})},
        "nodes": circuit.nodes, "elements": elements, "levers": levers,
        "unloaded": list(unloaded), "warnings": warns, "tree": tree,
    }
    if args.explain:
        from ..explain import explain, explain_lines

        steps, root = explain(circuit)
        doc["steps"] = [dict(vars(s)) for s in steps]     # Step's fields: label, kind, ...
        doc["root"] = root
    if args.json:
        return print_json(doc)
    print(f"{args.file}: {len(elements)} elements, {len(levers)} levers, "
          f"{len(circuit.nodes)} nodes")
    if args.explain:
        warning_lines(warns)
        print("\n".join(explain_lines(circuit)))
        return 0
    from ..circuit import element_unit, units_of

    unit = units_of(d)["v" if d.kind == "velocity" else "Q"]
    print(f"drive {d.name}: {d.kind} {d.amplitude:g} {unit} between {d.n1} and {d.n2}"
          + (f"; over the revolution {d.motion.spec} ('mechcirc periodic')"
             if d.motion is not None else ""))
    # Columns as wide as the longest name (at least the classic widths); no trailing spaces.
    es = circuit.elements
    wn = max([8] + [len(x.name) for x in es] + [len(lv.name) for lv in circuit.levers])
    wp = max([6] + [len(n) for x in es for n in (x.n1, x.n2)])
    values = [f"{x.value:g} {element_unit(x.kind, circuit.rotational(x))}" for x in es]
    wv = max([12] + [len(v) for v in values])
    for e, value in zip(es, values):
        eta = f"  eta={e.eta:g}" if e.eta != 1 else ""
        gap = f"  backlash={e.backlash:g} {units_of(circuit.rotational(e))['x']}" \
            if e.backlash else ""
        print(f"  {e.kind:<7} {e.name:<{wn}} {e.n1:>{wp}} {e.n2:>{wp}}  "
              f"{value:<{wv}}{eta}{gap}".rstrip())
    for lv in circuit.levers:
        print(f"  lever   {lv.name:<{wn}} {lv.p1}-{lv.p2} -> {lv.s1}-{lv.s2}  ratio={lv.ratio:g}")
    warning_lines(warns)
    print(f"K = {tree}")
    return 0


def _omega_grid(args):
    import numpy as np

    lo, hi, n = args.omega_min, args.omega_max, args.points
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo < 0 or hi <= lo:
        raise MechcircError(f"need 0 <= --omega-min < --omega-max (finite), got "
                            f"{lo:g} and {hi:g}")
    if n < 2 or n > MAX_SWEEP_POINTS:
        # One point would be --omega-min alone: the band and its peak need both ends.
        raise MechcircError(f"--points must be between 2 and {MAX_SWEEP_POINTS} (a sweep "
                            f"spans --omega-min to --omega-max), got {n}")
    larger = "write larger sweeps with -o CSV"
    for wanted, limit, what, why in (
            (args.plot, MAX_PLOT_POINTS, "--plot", larger),
            (args.json, MAX_JSON_POINTS, "--json", larger),
            (args.method == "nodal", MAX_NODAL_POINTS, "--method nodal", larger),
            (args.node, MAX_NODAL_POINTS, "--node", larger),
            (args.sensitivity, MAX_NODAL_POINTS, "--sensitivity", "a nodal solve at each")):
        if wanted and n > limit:
            raise MechcircError(f"--points {n} with {what}: the limit is {limit} points ({why})")
    if args.log:
        if lo <= 0:
            raise MechcircError("--log needs --omega-min > 0")
        return np.geomspace(lo, hi, n)
    return np.linspace(lo, hi, n)


def _some_omega(values, limit: int = 5, unit: str = "rad/s") -> str:
    text = ", ".join(f"{in_unit(w, unit):.10g}" for w in values[:limit])
    return text + (f" and {len(values) - limit} more" if len(values) > limit else "")


def _peak_doc(pk) -> dict:
    """The exact peak for ``--json``: value inf when unbounded (see mechcirc.peak)."""
    return {"quantity": pk.quantity, "value": pk.value, "omega": pk.omega,
            "unbounded": pk.unbounded, "unbounded_at": list(pk.poles),
            "grid_value": pk.grid_value, "grid_omega": pk.grid_omega, "note": pk.note}


def _peak_text(pk, units: dict, unit: str = "rad/s") -> str:
    q = {"Q0": units["Q"], "v0": units["v"], "K": units["K"]}[pk.quantity]
    name = FREQUENCY_UNITS[unit][0]
    if pk.unbounded:
        return (f"max |{pk.quantity}| = inf: undamped resonance at {name} = "
                f"{_some_omega(list(pk.poles), unit=unit)} {unit} (the grid's largest, "
                f"{pk.grid_value:.4g} {q}, depends only on how close a point falls)")
    where = f"{pk.note}; " if pk.note else "located; "
    return (f"max |{pk.quantity}| = {pk.value:.7g} {q} at {name} = "
            f"{in_unit(pk.omega, unit):.9g} {unit} ({where}the grid's largest is "
            f"{pk.grid_value:.4g} {q})")


def cmd_sweep(args) -> int:
    check_output_paths(args.output, args.touchstone, plots=(args.plot,), reads=(args.file,),
                       table="a CSV table")
    refuse_ignored(args, {"--tol": (args.adaptive, "--adaptive sweeps", "add --adaptive"),
                          "--no-refine": (not args.adaptive or args.refine, "a fixed grid, not "
                                          "--adaptive", "leave out --adaptive")})
    if args.touchstone and Path(args.touchstone).suffix.lower() != ".s1p":
        # K seen by one drive is a one-port: a .s2p name would promise a
        # 2-port file that scikit-rf then cannot read.
        raise MechcircError(
            f"{args.touchstone}: --touchstone writes K at the drive, a one-port: name "
            "the file .s1p (a 2-port of two nodes is mechcirc.interop.skrf.two_port)")
    from ..circuit import node_names

    circuit, warns = load_with_warnings(args.file)
    check_names(args.node, node_names(circuit.elements, circuit.levers), "node", "--node")
    check_names(args.element, [e.name for e in circuit.elements])     # before the sweep
    if args.sensitivity:                # its names, checked at no ω (no solve)
        from ..modes import sweep_sensitivity

        sweep_sensitivity(circuit, [], args.sensitivity)
    omega = _omega_grid(args)
    result = _run_sweep(args, circuit, omega)
    extra = _responses(result, args.node, args.element)
    everything = refused = None
    if args.plot or args.json:
        try:
            # The band's top as peak() asks for it (1e-9 above): computed once for both.
            everything = circuit.resonances(omega_max=omega[-1] * (1 + 1e-9))
        except SolverError as exc:      # too large for the eigenproblem: sweep anyway
            warns.append(f"resonance markers left out: {exc}")
            refused = exc               # (peak() is told, not made to ask again)
    found = [r for r in everything or () if omega[0] <= r.omega <= omega[-1]]
    # (sweep_sensitivity imported above, where the names were checked)
    sens = sweep_sensitivity(circuit, result.omega, args.sensitivity) if args.sensitivity else None
    from .._sweep import FLAG_SINGULAR, peak

    # (a grid-only peak's note is in its line and the JSON: not again as a warning)
    with warnings.catch_warnings(action="ignore", category=PeakAccuracyWarning):
        pk = peak(result, resonances=everything if refused is None else refused)
    singular = [float(w) for w in result.omega[result.flags == FLAG_SINGULAR]]
    notes = list(getattr(result, "notes", ()))
    if singular:
        notes.append(f"{len(singular)} point(s) exactly on a pole or zero of K "
                     f"({FREQUENCY_UNITS[args.unit][0]} = "
                     f"{_some_omega(singular, unit=args.unit)} {args.unit}): there "
                     "K is +inf·j or 0 and Q0 is 0 or +inf·j (flag 1)")
    warning_lines(warns)
    dropped = _write_sweep_outputs(args, result, extra, sens, found, pk)
    if args.json:
        return print_json(_sweep_doc(args, result, extra, sens, found, pk, singular, notes, warns))
    _print_sweep(args, result, extra, sens, pk, notes, dropped)
    return 0


def _run_sweep(args, circuit, omega):
    """The sweep on the grid, or on an adaptive grid from it (``--adaptive``)."""
    if not args.adaptive:
        return circuit.sweep(omega, method=args.method, refine=args.refine, error=True)
    from ..adaptive import adaptive_sweep

    if omega[0] <= 0:
        raise MechcircError("--adaptive needs --omega-min > 0")
    # By nodal analysis a point costs ~0.1 ms or more, so its budget is smaller;
    # the work (points × elements) is bounded in adaptive_sweep on either path.
    budget = MAX_ADAPTIVE_NODAL_POINTS if args.method == "nodal" else MAX_ADAPTIVE_POINTS
    if args.points > budget:        # refused, not cut to the budget without a word
        raise MechcircError(f"--points {args.points} with --adaptive is the starting grid, over "
                            f"the adaptive budget of {budget:,} points (give fewer, or leave "
                            f"out --adaptive for a fixed grid of up to {MAX_SWEEP_POINTS:,})")
    return adaptive_sweep(circuit, omega[0], omega[-1], tol=args.tol, initial=args.points,
                          method=args.method, max_points=budget)


def _write_sweep_outputs(args, result, extra, sens, found, pk) -> int:
    """CSV, Touchstone and plot, all or none; returns the points left out of the Touchstone."""
    from ..outputs import OutputSet

    dropped = 0
    with OutputSet() as out:
        if args.output:
            from ..io_csv import write_sweep_csv

            write_sweep_csv(result, out.path(args.output), unit=args.unit,
                            extra={**extra, **_sensitivity_columns(sens)})
        if args.touchstone:
            from ..interop.skrf import write_touchstone

            dropped = write_touchstone(out.path(args.touchstone), result.omega, result.K,
                                       name=result.name,
                                       unit=result.units["K"].replace("·", "*"))
        if args.plot:
            from ..plotting import plot_sweep

            # "v_abs(NAME)" -> "|v(NAME)| [m/s]"
            panels = {f"|{key[0]}{key[key.index('('):]}| [{result.units[key[0]]}]": values
                      for key, values in extra.items()}
            save_figure(plot_sweep(result, resonances=found, peak=pk, unit=args.unit,
                                   extra=panels), args.plot, out.path(args.plot), tight=False)
    return dropped


def _sweep_doc(args, result, extra, sens, found, pk, singular, notes, warns) -> dict:
    """The ``sweep --json`` document."""
    import numpy as np

    doc = {
        "file": args.file, "name": result.name, "method": result.method,
        "points": len(result.omega), "omega": result.omega,
        "K": {"re": result.K.real, "im": result.K.imag},
        "Q0": {"re": result.Q0.real, "im": result.Q0.imag},
        "flags": result.flags, "n_flagged": int(np.count_nonzero(result.flags)),
        "warnings": warns, "resonances": [r.as_dict() for r in found],
        "peak": _peak_doc(pk), "singular_omega": singular, "notes": notes,
        "units": {"omega": "rad/s", **result.units},
    }
    if extra:
        doc["responses"] = extra
    if result.drive.kind == "force":
        doc["v0"] = {"re": result.v0.real, "im": result.v0.imag}
    if sens is not None:
        doc["sensitivity"] = {name: {"value": sens.value[name], "quantity": sens.quantity,
                                     "derivative": sens.derivative(name),
                                     "relative": sens.relative(name)}
                              for name in sens.dK}
    return doc


def _print_sweep(args, result, extra, sens, pk, notes, dropped) -> None:
    """The summary ``sweep`` prints without ``--json``."""
    import numpy as np

    units, unit = result.units, args.unit
    how = "adaptive grid points" if args.adaptive else "points"
    print(f"{args.file}: {len(result.omega)} {how}, {FREQUENCY_UNITS[unit][0]} {in_unit(result.omega[0], unit):g} .. "
          f"{in_unit(result.omega[-1], unit):g} {unit}, method {result.method}")
    ranges = [("|K|", result.K, units["K"], "")]
    if result.drive.kind == "force":    # Q0 is the prescribed F0: show the response
        ranges.append(("|v0|", result.v0, units["v"], " (velocity response v0 = F0·K to the "
                       f"force drive F0 = {result.drive.amplitude:g} {units['Q']})"))
    else:
        ranges.append(("|Q0|", result.Q0, units["Q"], ""))
    ranges += [(f"|{key[0]}{key[key.index('('):]}|", values, units[key[0]], "")
               for key, values in extra.items()]
    with np.errstate(all="ignore"):
        for label, values, its_unit, more in ranges:
            size = np.abs(values)
            print(f"  {label:<4} {np.nanmin(size):.4g} .. {np.nanmax(size):.4g} {its_unit} on "
                  f"the grid{more}")
    print(f"  {_peak_text(pk, units, unit)}")
    if sens is not None:
        _print_sweep_sensitivity(sens, result)
    if n_flag := int(np.count_nonzero(result.flags)):
        print(f"  {n_flag} point(s) on or within rounding of a pole or zero of K "
              "(flagged; see the 'flag' column)")
    print_written(("CSV", args.output), ("plot", args.plot), ("Touchstone", args.touchstone),
                  notes=notes)
    if dropped:
        print(f"  {dropped} point(s) with omega = 0 or a non-finite K left out of "
              f"{args.touchstone}")

def _sensitivity_columns(sens) -> dict:
    """CSV columns ``d{q}_d{name}`` and ``rel{q}_{name}`` of ``sweep --sensitivity``."""
    if sens is None:
        return {}
    q = sens.quantity
    return {column: values for name in sens.dK for column, values in (
        (f"d{q}_d{name}", sens.derivative(name)), (f"rel{q}_{name}", sens.relative(name)))}


def _print_sweep_sensitivity(sens, result) -> None:
    import numpy as np

    q = sens.quantity
    mag = np.abs(getattr(result, q))
    finite = np.isfinite(mag)
    i = int(np.argmax(np.where(finite, mag, -1.0))) if finite.any() else 0
    print(f"  (p/|{q}|) d|{q}|/dp, exact (the relative change of |{q}| per relative change "
          f"of p), on the grid and at the grid's largest |{q}| (omega = {result.omega[i]:.6g} "
          "rad/s):")
    for name in sens.dK:
        rel = sens.relative(name)
        ok = rel[np.isfinite(rel)]
        lo, hi = (ok.min(), ok.max()) if ok.size else (math.nan, math.nan)
        print(f"    {name:<10} p = {sens.value[name]:<10.6g} {lo + 0.0:+.4g} .. {hi + 0.0:+.4g}; "
              f"{rel[i] + 0.0:+.4g} there")


def _responses(result, nodes, elements) -> dict:
    """``{column: |amplitude|}`` of ``--node`` (v_abs, x_abs) and ``--element`` (Q_abs)."""
    import numpy as np

    out = {}
    with np.errstate(all="ignore"):
        for name in nodes:
            try:
                v = np.abs(result.node_velocity(name))
            except KeyError as exc:
                raise MechcircError(f"--node: {exc.args[0]}") from None
            out[f"v_abs({name})"] = v
            out[f"x_abs({name})"] = v / result.omega        # |x| = |v| / ω
        for name in elements:
            try:
                out[f"Q_abs({name})"] = np.abs(result.force(name))
            except KeyError as exc:
                raise MechcircError(f"--element: {exc.args[0]}") from None
    return out


def cmd_resonances(args) -> int:
    from ..circuit import units_of
    from ..resonances import Resonances

    check_output_paths(plots=(args.plot,))
    circuit, warns = load_with_warnings(args.file)
    modes = circuit.modes(omega_max=args.omega_max) if args.modes or args.sensitivity or \
        args.plot else None
    found = circuit.resonances(omega_max=args.omega_max) if modes is None else \
        [m.resonance for m in modes]
    warning_lines(warns)
    if args.plot and modes is not None:     # --plot found the modes above
        _plot_modes(args, circuit, modes)
    if args.json:
        return _print_resonances_json(args, circuit, found, modes)
    nr, na = (sum(r.kind == k for r in found) for k in ("resonance", "antiresonance"))
    print(f"{args.file}: {nr} resonance{'s' * (nr != 1)} (K = 0), {na} anti-resonance"
          f"{'s' * (na != 1)} (K = ∞)"
          + (f" up to {in_unit(args.omega_max, args.unit):g} {args.unit}" if args.omega_max
             else ""))
    for line in Resonances(found).table(args.unit):
        print(f"  {line}")
    kinds = {e.name: e.kind for e in circuit.elements} | {lv.name: "lever" for lv in circuit.levers}
    for i, m in enumerate(modes or (), 1):
        r = m.resonance
        print(f"\n{i}: {r.kind} {frequency_text(r.omega, args.unit, 10)}"
              + (f", zeta = {r.zeta:.4g}" if r.zeta else ""))
        if m.note and (m.shape or not args.modes):   # else the mode table says it
            print(f"  note: {m.note}")
        if args.modes:
            _print_mode(m, kinds, units_of(circuit.drive), own_units(circuit))
        if args.sensitivity:
            _print_sensitivity(m, kinds)
    print_written(("plot", args.plot))
    return 0


def _plot_modes(args, circuit, modes) -> None:
    """``resonances --plot``: the lowest :data:`MAX_MODE_PANELS` mode shapes, one panel each."""
    from ..plotting import plot_modes

    if len(modes) > MAX_MODE_PANELS:
        warning_lines([f"--plot draws the lowest {MAX_MODE_PANELS} of {len(modes)} modes "
                       "(give --omega-max for fewer)"])
    save_figure(plot_modes(modes[:MAX_MODE_PANELS], circuit.name, unit=args.unit), args.plot)


def _print_resonances_json(args, circuit, found, modes) -> int:
    """``resonances --json``: the roots, with their modes and sensitivities when asked."""
    rows = [r.as_dict() for r in found]
    for row, m in zip(rows, modes or ()):
        if args.modes:
            row.update(_mode_doc(m))
        if args.sensitivity:
            row.update(element_sensitivity=m.sensitivity, param_sensitivity=m.param_sensitivity,
                       zeta_sensitivity=m.zeta_sensitivity,
                       param_zeta_sensitivity=m.param_zeta_sensitivity)
        if m.note:
            row["note"] = m.note
    return print_json({"file": args.file, "name": circuit.name, "resonances": rows})


#: The most mode shapes one ``resonances --plot`` draws (one panel each).
MAX_MODE_PANELS = 12


def _mode_doc(m) -> dict:
    """A mode for ``--json``: node → [re, im], element → energy share (null when overdamped)."""
    if not m.shape:
        return {"mode": None, "energy": None, "dissipation": None}
    return {"mode": {n: [v.real, v.imag] for n, v in m.shape.items()}, "energy": m.energy,
            "dissipation": m.dissipation,
            "velocity": {n: [v.real, v.imag] for n, v in m.velocity.items()},
            "force": {n: [q.real, q.imag] for n, q in m.force.items()}}


def _print_mode(m, kinds, units: dict, own: dict) -> None:
    import cmath

    if not m.shape:
        print(f"  no mode shape: {m.note}")
        return
    # Name columns as wide as the longest name (at least 10), as in 'check'.
    wn = max([10] + [len(n) for n in m.shape])
    we = max([10] + [len(n) for n in m.velocity])
    print(f"  {'node':<{wn}} {'|v|':>10} {'phase [deg]':>12}")
    for n, v in m.shape.items():
        print(f"  {n:<{wn}} {abs(v):>10.4g} {math.degrees(cmath.phase(v)) if v else 0:>12.4g}")
    print(f"  {'element':<{we}} {'kind':<7} {'energy':>8} {'zeta part':>10} "
          f"{'|v| [' + units['v'] + ']':>10} {'|Q| [' + units['Q'] + ']':>10}")
    for name, v in m.velocity.items():
        energy = f"{100 * m.energy[name]:.3g} %" if m.energy.get(name, 0) > 1e-12 else \
            "0 %" if name in m.energy else ""
        zeta = f"{m.dissipation[name]:.4g}" if name in m.dissipation else ""
        print(f"  {name:<{we}} {kinds[name]:<7} {energy:>8} {zeta:>10} {abs(v):>10.4g} "
              f"{abs(m.force[name]):>10.4g}{own.get(name, '')}")


#: What raising (True) or lowering (False) a quantity of each kind is called.
_VERBS = {"mass": ("add mass to", "lighten"), "spring": ("stiffen", "soften"),
          "damper": ("raise the damping of", "lower the damping of"),
          "lever": ("raise the ratio of", "lower the ratio of"), ".param": ("raise", "lower")}


def _print_sensitivity(m, kinds, shown: int = 10) -> None:
    ranked = sorted([(name, kinds[name], x) for name, x in m.sensitivity.items()]
                    + [(p, ".param", x) for p, x in m.param_sensitivity.items()],
                    key=lambda t: -abs(t[2]))
    moves = []
    for name, kind, x in ranked:
        change = 0.1 / x if abs(x) > 1e-12 else math.inf
        if abs(change) <= 1:        # beyond 100 % a first-order estimate says nothing
            moves.append(f"{_VERBS[kind][change < 0]} {name} by {abs(change) * 100:.3g} %")
        if len(moves) == 3:
            break
    if moves:
        print("  to raise omega by 10 % (linear estimate): " + ", or ".join(moves))
    w = max([10] + [len(name) for name, _, _ in ranked[:shown]])
    print(f"  {'name':<{w}} {'kind':<7} {'(p/omega) d(omega)/dp':>22} {'p d(zeta)/dp':>13}")
    zeta = m.zeta_sensitivity | m.param_zeta_sensitivity
    for name, kind, x in ranked[:shown]:
        print(f"  {name:<{w}} {kind:<7} {x + 0.0:>+22.4g} {zeta[name] + 0.0:>+13.3g}")
    if len(ranked) > shown:
        print(f"  ... and {len(ranked) - shown} smaller (--json gives every one)")
