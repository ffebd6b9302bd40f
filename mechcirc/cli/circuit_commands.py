"""Sub-commands on netlists: ``check`` and ``sweep``."""

from __future__ import annotations

import argparse
import sys

from ._common import print_json, save_figure


def register(sub) -> None:
    p = sub.add_parser(
        "check", help="parse a netlist and show its elements and reduction tree",
        description="Parse a netlist, list elements and nodes, warnings, and the "
                    "series–parallel reduction tree seen from the drive.",
        epilog="Example: mechcirc check netlists/stb_heald.mcir",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="netlist file (.mcir)")
    p.add_argument("--json", action="store_true", help="print one JSON document")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser(
        "sweep", help="K(ω) and Q0(ω) over a frequency range",
        description="Sweep the kinematic characteristic K = v/Q [m/(N·s)] and the "
                    "force amplitude Q0 = V0/K [N] over ω [rad/s].",
        epilog="Example: mechcirc sweep netlists/stb_heald.mcir --omega-min 10 "
               "--omega-max 1e4 --points 400 --log -o K.csv --plot K.png")
    p.add_argument("file", help="netlist file (.mcir)")
    p.add_argument("--omega-min", type=float, required=True, metavar="W1",
                   help="lowest angular frequency [rad/s]")
    p.add_argument("--omega-max", type=float, required=True, metavar="W2",
                   help="highest angular frequency [rad/s]")
    p.add_argument("--points", type=int, default=200, metavar="N",
                   help="number of frequency points (default 200)")
    p.add_argument("--log", action="store_true", help="space the points logarithmically")
    p.add_argument("-o", "--output", metavar="CSV",
                   help="write omega,K_re,K_im,Q0_re,Q0_im to this CSV file")
    p.add_argument("--plot", metavar="IMAGE", help="plot |K| and |Q0| (PNG, SVG or PDF)")
    p.add_argument("--json", action="store_true", help="print one JSON document")
    p.set_defaults(func=cmd_sweep)


def _load_with_warnings(path):
    """Load and reduce a netlist, returning the circuit and the warnings raised."""
    import warnings

    from ..netlist import load

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        circuit = load(path)
        circuit.tree    # reduce now, so topology errors and warnings surface here
    messages = [str(w.message) for w in caught]
    return circuit, messages


def cmd_check(args) -> int:
    circuit, warns = _load_with_warnings(args.file)
    elements = [
        {"name": e.name, "kind": e.kind, "n1": e.n1, "n2": e.n2, "value": e.value,
         "eta": e.eta, "line": e.line} for e in circuit.elements]
    levers = [{"name": lv.name, "p1": lv.p1, "p2": lv.p2, "s1": lv.s1, "s2": lv.s2,
               "ratio": lv.ratio, "line": lv.line} for lv in circuit.levers]
    d = circuit.drive
    doc = {
        "file": args.file, "name": circuit.name,
        "drive": {"name": d.name, "n1": d.n1, "n2": d.n2, "kind": d.kind,
                  "amplitude": d.amplitude},
        "nodes": circuit.nodes, "elements": elements, "levers": levers,
        "unloaded": list(circuit.unloaded), "warnings": warns, "tree": str(circuit.tree),
    }
    if args.json:
        print_json(doc)
        return 0
    print(f"{args.file}: {len(elements)} elements, {len(levers)} levers, "
          f"{len(circuit.nodes)} nodes")
    unit = "m/s" if d.kind == "velocity" else "N"
    print(f"drive {d.name}: {d.kind} {d.amplitude:g} {unit} between {d.n1} and {d.n2}")
    for e in circuit.elements:
        eta = f"  eta={e.eta:g}" if e.eta != 1 else ""
        print(f"  {e.kind:<7} {e.name:<8} {e.n1:>6} {e.n2:>6}  {e.value:<12g}{eta}")
    for lv in circuit.levers:
        print(f"  lever   {lv.name:<8} {lv.p1}-{lv.p2} -> {lv.s1}-{lv.s2}  ratio={lv.ratio:g}")
    for w in warns:
        print(f"warning: {w}", file=sys.stderr)
    print(f"K = {circuit.tree}")
    return 0


def _omega_grid(args):
    import numpy as np

    from ..errors import MechcircError

    lo, hi, n = args.omega_min, args.omega_max, args.points
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo < 0 or hi <= lo:
        raise MechcircError(f"need 0 <= --omega-min < --omega-max (finite), got "
                            f"{lo:g} and {hi:g}")
    if n < 1 or n > 10_000_000:
        raise MechcircError(f"--points must be between 1 and 10000000, got {n}")
    if args.log:
        if lo <= 0:
            raise MechcircError("--log needs --omega-min > 0")
        return np.geomspace(lo, hi, n)
    return np.linspace(lo, hi, n)


def write_sweep_csv(result, path) -> None:
    """Write ``omega,K_re,K_im,Q0_re,Q0_im`` rows atomically."""
    import numpy as np

    from ..outputs import atomic_open

    table = np.column_stack([result.omega, result.K.real, result.K.imag,
                             result.Q0.real, result.Q0.imag])
    with atomic_open(path, "w", newline="") as fh:
        fh.write("omega,K_re,K_im,Q0_re,Q0_im\n")
        np.savetxt(fh, table, delimiter=",", fmt="%.17g")


def cmd_sweep(args) -> int:
    import numpy as np

    circuit, warns = _load_with_warnings(args.file)
    omega = _omega_grid(args)
    result = circuit.sweep(omega)
    for w in warns:
        print(f"warning: {w}", file=sys.stderr)
    if args.output:
        write_sweep_csv(result, args.output)
    if args.plot:
        from ..plotting import plot_sweep

        save_figure(plot_sweep(result), args.plot)
    n_flag = int(np.count_nonzero(result.flags))
    if args.json:
        print_json({
            "file": args.file, "name": circuit.name, "omega": result.omega,
            "K": {"re": result.K.real, "im": result.K.imag},
            "Q0": {"re": result.Q0.real, "im": result.Q0.imag},
            "flags": result.flags, "n_flagged": n_flag, "warnings": warns,
        })
        return 0
    absK = np.abs(result.K)
    absQ = np.abs(result.Q0)
    print(f"{args.file}: {len(omega)} points, omega {omega[0]:g} .. {omega[-1]:g} rad/s")
    print(f"  |K|  {np.nanmin(absK):.4g} .. {np.nanmax(absK):.4g} m/(N·s)")
    print(f"  |Q0| {np.nanmin(absQ):.4g} .. {np.nanmax(absQ):.4g} N")
    if n_flag:
        print(f"  {n_flag} point(s) on a pole or zero of K (flagged)")
    for label, path in (("CSV", args.output), ("plot", args.plot)):
        if path:
            print(f"  {label} written to {path}")
    return 0
