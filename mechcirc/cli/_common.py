"""Shared command-line plumbing: error reporting, exit codes, JSON and file output."""

from __future__ import annotations

import argparse
import contextlib
import errno
import functools
import math
import os
import signal
import sys
import threading
import warnings
from dataclasses import dataclass
from pathlib import Path

from ..errors import (MAX_QUOTED, InputError, MechcircError, MechcircWarning, NetlistError,
                      NotSeriesParallelError, clip, did_you_mean, shorten)
from ..units import (FREQUENCY_UNITS, UnitError, in_unit, in_unit_of, is_bare_number,
                     parse_quantity, parse_unit)

EXIT_OK, EXIT_INTERNAL, EXIT_USER = 0, 1, 2
#: Exit status after SIGINT and SIGTERM (128 + the signal number, as shells report).
EXIT_SIGINT, EXIT_SIGTERM = 128 + signal.SIGINT, 128 + signal.SIGTERM


class Terminated(BaseException):
    """SIGTERM arrived; raised so that ``finally`` blocks and temporary outputs unwind.

    Python's default SIGTERM action ends the process at once, leaving the
    temporary files of :mod:`mechcirc.outputs` behind.
    """


@contextlib.contextmanager
def sigterm_unwinds():
    """Within the block, SIGTERM raises :class:`Terminated` (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def on_sigterm(signum, frame):
        raise Terminated()

    old = signal.signal(signal.SIGTERM, on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


@contextlib.contextmanager
def time_limit(seconds: float, what: str, instead: str):
    """Raise :class:`MechcircError` once the block has used ``seconds`` of CPU time.

    For work whose size cannot be bounded beforehand (SymPy).  CPU time of the
    process (``ITIMER_PROF``, user and system, all threads; what
    ``time.process_time`` counts), not the wall clock: the same input gets the
    same answer on a loaded machine.  Uses SIGPROF, so only in the main thread
    of a POSIX process (elsewhere: no limit).
    """
    if not hasattr(signal, "setitimer") or \
            threading.current_thread() is not threading.main_thread():
        yield
        return

    class _Expired(BaseException):
        pass

    def on_expiry(signum, frame):
        raise _Expired()

    old = signal.signal(signal.SIGPROF, on_expiry)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    try:
        yield
    except _Expired:
        raise MechcircError(f"{what} used more than the limit of {seconds:g} s of CPU time; "
                            f"{instead}") from None
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, old)


def run_handler(args) -> int:
    """Call ``args.func(args)`` and map errors to messages and exit codes.

    Warnings are held back while the command runs: when it ends in a user
    error, numpy's ``RuntimeWarning`` lines (overflow, invalid value: symptoms
    of the bad input the message names) are dropped, so the one-line message
    stands alone; otherwise every warning is shown as usual.
    """
    _SHOWN.clear()
    with warnings.catch_warnings(record=True) as caught:
        status = _run(args)
    for w in caught:
        if issubclass(w.category, MechcircWarning):
            # The package's own warnings read as the command's: one "warning:" line
            # each, and not again when the command already printed that message.
            warning_lines([str(w.message)])
        elif status != EXIT_USER or not issubclass(w.category, RuntimeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return status


#: The warning messages a command printed (:func:`warning_lines`), so that
#: :func:`run_handler` does not print a warning raised again later a second time.
_SHOWN: set[str] = set()


def warning_lines(messages) -> None:
    """Print each message on stderr as ``warning: MESSAGE``, once per command run.

    Parameters
    ----------
    messages : iterable of str
        The warnings' texts.
    """
    for text in map(str, messages):
        if text not in _SHOWN:
            _SHOWN.add(text)
            print(f"warning: {text}", file=sys.stderr)


def _run(args) -> int:
    try:
        status = args.func(args)
        return EXIT_OK if status is None else status
    except MechcircError as exc:
        located = isinstance(exc, NetlistError)
        where = getattr(exc, "location", None)      # FILE:LINE:COL of a statement error
        print(str(exc) if located else f"{where}: error: {exc}" if where
              else f"mechcirc: error: {exc}", file=sys.stderr)
        return EXIT_USER
    except (FileNotFoundError, IsADirectoryError) as exc:
        what = "no such file" if isinstance(exc, FileNotFoundError) else \
            "is a directory, expected a file"
        print(f"{_name(exc)}: error: {what}", file=sys.stderr)
        return EXIT_USER
    except KeyboardInterrupt:
        print("mechcirc: interrupted", file=sys.stderr)
        return EXIT_SIGINT
    except Terminated:
        print("mechcirc: terminated", file=sys.stderr)
        return EXIT_SIGTERM
    except BrokenPipeError:
        return EXIT_OK
    except OSError as exc:
        # A file the system would not read or write (a full disk, a read-only file
        # system, no permission): the environment's refusal, named, not a bug; a
        # write's refusal (no room on the disk, /dev/full) has no file name.
        if exc.strerror is None or (exc.filename is None and exc.errno not in _REFUSALS):
            return _internal(args, exc)
        where = "mechcirc" if exc.filename is None else _name(exc)
        print(f"{where}: error: {exc.strerror.lower()}", file=sys.stderr)
        return EXIT_USER
    except Exception as exc:  # noqa: BLE001 - the last line of defence
        return _internal(args, exc)


#: The system's refusals of a read or write (OSError.errno), reported as user errors.
_REFUSALS = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EACCES, errno.EPERM}


def _name(exc: OSError) -> str:
    """The file an OSError names, clipped: a path typed on the command line can be long."""
    return clip(str(exc.filename), 2 * MAX_QUOTED)


def _internal(args, exc: Exception) -> int:
    """Report an internal error in one line (the traceback with ``--debug``)."""
    if getattr(args, "debug", False):
        raise exc
    first = shorten((str(exc).splitlines() or [""])[0])    # one line, whatever the message
    print(f"mechcirc: internal error: {type(exc).__name__}: {first}\n"
          "This is a bug in mechcirc; please report it with the input "
          "(run again with --debug for the traceback).", file=sys.stderr)
    return EXIT_INTERNAL


def join_spaced_quantities(argv: list[str]) -> list[str]:
    """Join ``--opt 50 Hz`` into ``--opt "50 Hz"`` so options take spaced units as netlists do.

    A number right after an option, followed by a token that the unit grammar
    reads as a unit, is one quantity; anything else is left alone.
    """
    out: list[str] = []
    i = 0
    while i < len(argv):
        tok = argv[i]
        out.append(tok)
        if (i + 1 < len(argv) and out[:-1] and out[-2].startswith("--") and "=" not in out[-2]
                and is_bare_number(tok)):
            unit = argv[i + 1]
            try:
                ok = unit in ("1/s",) or (not unit.startswith("-") and parse_unit(unit) and
                                          not os.path.exists(unit))   # a file named "m"
            except UnitError:
                ok = False
            if ok:
                out[-1] = f"{tok} {unit}"
                i += 1
        i += 1
    return out


# ------------------------------------------------------------------ option values
# One validator for every number the command line takes: argparse calls it,
# so a bad value is a usage error (exit 2) naming the option, before any work.
def real(*, least: float | None = None, above: float | None = None,
         most: float | None = None, unit: str = "", finite: bool = True,
         role: str | None = None):
    """argparse type: a finite number (``role="omega"``: also ``50Hz``, ``3000rpm``) in range.

    ``least`` ≤ x, ``above`` < x, x ≤ ``most``; ``nan``, ``inf`` and
    overflowing literals such as ``1e400`` are refused (``finite=False``: let
    the command check the range itself, with its own message).  ``role``
    (``"omega"``, ``"angle"``, ``"time"``, ...): the value may carry a unit of
    the one grammar (:mod:`mechcirc.units`), converted to ``unit``
    (``--theta 0.5rad`` is 28.6… when ``unit="deg"``); without one it is in ``unit``.
    """
    def parse(text: str) -> float:
        try:
            value = in_unit_of(text, role, unit) if role else float(text)   # in the option's unit
        except UnitError as exc:
            noun = "frequency" if role == "omega" else role    # "unknown frequency unit 'x'"
            message = exc.message.replace("unknown unit", f"unknown {noun} unit")
            raise argparse.ArgumentTypeError(f"{message} (expected {exc.expected}" + (
                f"; no unit means {unit}" if unit else "") + ")") from None
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        u = f" {unit}" if unit else ""
        if not finite:
            return value
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not a finite number"
                                             + (f" (largest magnitude {most:g}{u})"
                                                if most is not None else ""))
        if least is not None and value < least:
            raise argparse.ArgumentTypeError(f"must be ≥ {least:g}{u}, got {text!r}")
        if above is not None and value <= above:
            raise argparse.ArgumentTypeError(f"must be > {above:g}{u}, got {text!r}")
        if most is not None and abs(value) > most:
            raise argparse.ArgumentTypeError(f"must be at most {most:g}{u} in magnitude, "
                                             f"got {text!r}")
        return value

    parse.__name__ = "number"          # argparse names the type in its messages
    return parse


#: A shaft speed option [rev/min]: ``600``, or with a unit of frequency (``600rpm``, ``10Hz``).
shaft_speed = real(above=0.0, most=1e9, unit="rpm", role="omega")
#: An angular frequency ≥ 0 [rad/s], or with a unit (``50Hz``, ``3000rpm``): a band's bound.
band_omega = real(least=0.0, unit="rad/s", role="omega")
#: The same, > 0: one frequency at which to evaluate, a crank shaft's speed.
positive_omega = real(above=0.0, unit="rad/s", role="omega")
#: A crank rotation [deg], or with a unit (``0.5rad``).
crank_angle = real(most=1e9, unit="deg", role="angle")


def count(least: int = 1, most: int | None = None, *, why: str = ""):
    """argparse type: an integer in ``least..most`` (``1e6`` accepted); the limit is named."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            number = math.nan                   # not a number either: not an integer
            with contextlib.suppress(ValueError):
                number = float(text)
            if not (math.isfinite(number) and number.is_integer()):
                raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
            value = int(number)
        if value < least:
            raise argparse.ArgumentTypeError(f"must be at least {least}, got {text}")
        if most is not None and value > most:
            raise argparse.ArgumentTypeError(
                f"{text} is more than the limit of {most:,}" + (f" ({why})" if why else ""))
        return value

    parse.__name__ = "integer"
    return parse


def add_command(sub, name: str, summary: str, description: str, example: str, *,
                file: str | None = None, raw: bool = True):
    """Start a command's parser: its name, one-line help, description and example.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The sub-command table the parser joins.
    name : str
        The command (``mechcirc NAME``).
    summary : str
        Its line in ``mechcirc --help``.
    description : str
        The text above its options.
    example : str
        The text below them (``Example: mechcirc NAME ...``).
    file : str, optional
        Help of a positional ``file`` argument, added first; none by default.
    raw : bool, optional
        Print the description and example as written (True) or re-wrapped.

    Returns
    -------
    argparse.ArgumentParser
    """
    p = sub.add_parser(name, help=summary, description=description, epilog=example,
                       formatter_class=argparse.RawDescriptionHelpFormatter if raw
                       else argparse.HelpFormatter)
    if file:
        p.add_argument("file", help=file)
    return p


def command(name: str, summary: str, description: str, example: str, *,
            file: str | None = None, raw: bool = True):
    """Decorate ``options(p)``, which adds a command's options to its parser ``p``: the
    result, ``register(sub)``, starts the parser with :func:`add_command` (the arguments
    are its own) and calls ``options`` on it.

    Parameters
    ----------
    name, summary, description, example : str
        The command and its texts, as :func:`add_command` takes them.
    file : str, optional
        Help of a positional ``file`` argument.
    raw : bool, optional
        Print the description and example as written (True) or re-wrapped.

    Returns
    -------
    callable
        The decorator.
    """
    def decorate(options):
        @functools.wraps(options)
        def register(sub) -> None:
            options(add_command(sub, name, summary, description, example, file=file, raw=raw))
        return register
    return decorate


def add_handler(p, func, *, json: bool = True) -> None:
    """A command's handler and its ``--json`` option, listed in its help where this is called:
    last, after the other options, unless the command adds more after it.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    func : callable
        The handler: takes the parsed arguments, returns the exit status.
    json : bool, optional
        Add ``--json`` (print one JSON document); False for a command without it.
    """
    if json:
        p.add_argument("--json", action="store_true", help="print one JSON document")
    p.set_defaults(func=func)


def commands(*adders):
    """A module's ``register(sub)``: each of ``adders`` adds its command to ``sub``, in the
    order ``mechcirc --help`` lists them.

    Parameters
    ----------
    *adders : callable
        Each takes the sub-command table (``argparse._SubParsersAction``) and adds one
        command's parser to it.

    Returns
    -------
    callable
    """
    def register(sub) -> None:
        for add in adders:
            add(sub)
    return register


# ------------------------------------------------------------------ shared options
# The options several commands take, each declared here once; ``what`` is the
# command's own help text of the option.
#: Help of the positional ``file`` of a command that reads a netlist (``add_command(file=)``).
NETLIST_FILE = "netlist file (.mcir)"


def add_plot_option(p, what: str) -> None:
    """``--plot IMAGE``: draw ``what`` into an image file, its format by its extension."""
    p.add_argument("--plot", metavar="IMAGE", help=what)


def add_output_option(p, what: str, metavar: str = "CSV", **options) -> None:
    """``-o/--output``: write ``what`` to a file (``metavar``: its kind; ``options``: more of
    argparse's, as ``dest``)."""
    p.add_argument("-o", "--output", metavar=metavar, help=what, **options)


def add_method_option(p, what: str) -> None:
    """``--method auto|sp|nodal``: how K is evaluated (series–parallel tree or nodal analysis)."""
    p.add_argument("--method", choices=("auto", "sp", "nodal"), default="auto", help=what)


def add_unit_option(p, what: str | None = None) -> None:
    """``--unit rad/s|Hz|rpm``: the unit of the frequencies a command shows (``what``: which,
    when not every one)."""
    p.add_argument("--unit", choices=tuple(FREQUENCY_UNITS), default="rad/s",
                   help=what or "show frequencies in rad/s (omega, the default), Hz (f = "
                                "omega/2 pi) or rpm (n = 60 omega/2 pi): tables, CSV columns "
                                "and plot axes (--json stays in rad/s)")


def frequency_text(omega: float, unit: str = "rad/s", digits: int = 6) -> str:
    """``omega = 300 rad/s (47.7465 Hz)``, or in ``unit`` of --unit: ``f = 47.7465 Hz``."""
    hz = f" ({in_unit(omega, 'Hz'):.6g} Hz)" if unit == "rad/s" else ""     # f beside omega
    return f"{FREQUENCY_UNITS[unit][0]} = {in_unit(omega, unit):.{digits}g} {unit}{hz}"


def frequency_symbol(unit: str) -> str:
    """The symbol of a frequency shown in ``unit`` of --unit: ω (rad/s), f (Hz) or n (rpm)."""
    return {"rad/s": "ω"}.get(unit, FREQUENCY_UNITS[unit][0])


#: The largest angular frequency the command line accepts [rad/s] (ω² stays finite).
MAX_OMEGA = 1e100
#: The largest length the command line accepts (products of four stay finite).
MAX_LENGTH = 1e50


def own_units(circuit) -> dict[str, str]:
    """``"  [N·m, rad/s]"`` (force, velocity) for each element whose kind, rotary or not
    (:meth:`mechcirc.circuit.Circuit.rotational`), is not the drive's: a table's row
    of it is in those units, not its header's (a rotary stage behind a lever)."""
    from ..circuit import units_of

    drive = circuit.drive is not None and circuit.drive.rotational
    return {e.name: "  [{Q}, {v}]".format(**units_of(rot)) for e in circuit.elements
            if (rot := circuit.rotational(e)) != drive}


def fields_of(obj, names: str) -> dict:
    """``{name: obj.name}`` for each of the space-separated attribute ``names``, in order
    (a record of ``--json``)."""
    return {name: getattr(obj, name) for name in names.split()}


def _jsonable(obj):
    if isinstance(obj, float):
        return obj
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if getattr(obj, "dtype", None) is not None and obj.dtype.kind in "iuf" and obj.ndim:
        return obj.tolist()               # no per-number recursion (10⁶ points: 120 s)
    if hasattr(obj, "tolist"):
        return _jsonable(obj.tolist())
    if isinstance(obj, complex):
        return {"re": _jsonable(obj.real), "im": _jsonable(obj.imag)}
    return obj


def _longest_list(obj, depth: int = 0) -> int:
    if depth > 4:
        return 0
    if isinstance(obj, dict):
        return max((_longest_list(v, depth + 1) for v in obj.values()), default=0)
    if isinstance(obj, list):
        return max([len(obj), *(_longest_list(v, depth + 1) for v in obj[:3])])
    return 0


def print_json(document) -> int:
    """Print one JSON document on stdout (non-finite floats as Infinity, -Infinity, NaN);
    return :data:`EXIT_OK`, so a handler's ``--json`` branch ends ``return print_json(doc)``.

    The bare tokens are the --json convention for non-finite numbers (docs/cli.md):
    Python's json module writes and reads them, ``json.loads`` and
    ``pandas.read_json`` give floats, so numeric arrays stay numeric.  (Strict
    RFC 8259 readers such as jq need ``sub("NaN"; "null")``-style preprocessing.)
    """
    import json         # here: a command that prints no JSON does not load it

    doc = _jsonable(document)
    # json.dump and indented output go through json's pure-Python encoder, one
    # write per number; a long document is encoded compact in one go by the C
    # encoder (10⁶ sweep points: 120 s before).
    if _longest_list(doc) > 10_000:
        sys.stdout.write(json.dumps(doc, allow_nan=True, separators=(",", ":")))
    else:
        json.dump(doc, sys.stdout, indent=2, allow_nan=True)
    sys.stdout.write("\n")
    return EXIT_OK


#: Image formats the plots can be written in (by file extension).
PLOT_FORMATS = ("png", "svg", "pdf", "eps", "ps", "jpg", "jpeg", "tif", "tiff", "webp")


def check_output_paths(*paths, plots=(), reads=(), table: str | None = None,
                       option: str = "-o", drawn_by: str | None = None) -> None:
    """Refuse, before any work, outputs that cannot or must not be written.

    An output into a missing folder (a dangling link's included), onto a
    folder, block device or socket, one named twice, one that is a file the
    command reads (``reads``: its input files), or a plot in an unknown format.
    Links are followed and FIFOs and character devices written in place
    (:func:`mechcirc.outputs.output_target`).  With ``table`` (what the
    option ``option`` writes, for the message) the first path is that option's:
    refused if named like an image (``-o K.png`` would write CSV text into
    K.png: the image is the drawing option's, ``drawn_by``, by default ``--plot``
    when ``plots`` are given) or a JSON document (``--json``'s, on stdout).
    """
    from ..outputs import output_target

    if "" in (*paths, *plots):      # -o "$OUT" with OUT unset would write nothing, silently
        raise MechcircError("an output file name is empty; give a file name")
    given = [p for p in (*paths, *plots) if p]
    resolved = [output_target(p)[0] for p in given]
    for i, path in enumerate(resolved):
        if path in resolved[:i]:
            raise MechcircError(f"{given[i]}: named for two outputs; each output needs "
                                "its own file")
    for source in (r for r in reads if r):
        for out, path in zip(given, resolved):
            same = path == Path(os.path.realpath(source))
            with contextlib.suppress(OSError):
                same = same or os.path.samefile(path, source)
            if same:
                raise MechcircError(f"{out}: is also this command's input {source}; "
                                    "writing it would replace the input: give the output "
                                    "another name")
    for path in plots:
        if path and Path(path).suffix.lstrip(".").lower() not in PLOT_FORMATS:
            raise MechcircError(
                f"{path}: unsupported plot format {Path(path).suffix or '(none)'!r} "
                f"(expected one of {', '.join('.' + f for f in PLOT_FORMATS)})")
    suffix = Path(paths[0]).suffix.lower() if table and paths and paths[0] else ""
    if suffix.lstrip(".") in PLOT_FORMATS:
        drawn_by = drawn_by or ("--plot IMAGE" if plots else None)
        raise MechcircError(f"{paths[0]}: {option} writes {table}, not an image (" + (
            f"the drawing is written by {drawn_by})" if drawn_by else "this command draws none)"))
    if suffix == ".json":
        raise MechcircError(f"{paths[0]}: {option} writes {table}, not JSON; --json prints the "
                            f"JSON document (--json > {paths[0]})")


def save_figure(fig, path, into=None, tight: bool = True) -> None:
    """Save a matplotlib figure; the format follows ``path``'s extension.

    Without ``into`` the file is written atomically (temporary file, rename);
    with ``into`` (a temporary path from an :class:`~mechcirc.outputs.OutputSet`)
    it is written there and the set renames it.  ``tight`` crops to what is
    drawn (one more draw of the figure); False for a figure laid out to hold
    its labels.
    """
    from ..outputs import atomic_path

    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    if fmt not in PLOT_FORMATS:     # commands check first; this guards any that forget
        check_output_paths(plots=(path,))
    from matplotlib.backend_bases import FigureCanvasBase

    if fmt == "png" and type(fig.canvas) is FigureCanvasBase:
        # The Agg canvas at once (no pyplot, no backend switch): a command's figure
        # is a bare Figure, saved once.
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    # PNG: zlib level 3, not PIL's 6: the same pixels, encoded in about half the
    # time (a sweep's figure: 27 against 47 ms) for an 11 % larger file.
    options = {"pil_kwargs": {"compress_level": 3}} if fmt == "png" else {}
    with contextlib.nullcontext(into) if into is not None else atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=120, bbox_inches="tight" if tight else None,
                    **options)


def write_outputs(args, columns, plot=None, comment: str | None = None,
                  fmt: str = "%.17g") -> None:
    """``-o CSV`` (a ``comment`` line when given, the column names, then one row per
    index, each value as ``fmt``) and ``--plot`` (the figure ``plot()`` makes), all or
    none written.

    Parameters
    ----------
    args : argparse.Namespace
        With ``output`` and ``plot`` (either may be None).
    columns : iterable of (str, array_like)
        The columns (equal lengths), each with its name, in order (a result's
        ``columns().items()``; a name may repeat).
    plot : callable, optional
        Makes the figure, called only for ``--plot``.
    comment : str, optional
        The first line, ``#`` included.
    fmt : str
        The printf format of a value (the default, 17 significant digits, reads back
        exactly).
    """
    import numpy as np

    from ..outputs import OutputSet

    with OutputSet() as out:
        if args.output:
            with open(out.path(args.output), "w", encoding="utf-8", newline="") as fh:
                names, cols = zip(*columns)
                np.savetxt(fh, np.column_stack(cols), delimiter=",", fmt=fmt, comments="",
                           header=(comment + "\n" if comment else "") + ",".join(names))
        if plot is not None and args.plot:
            save_figure(plot(), args.plot, out.path(args.plot))


def print_written(*outputs, notes=(), indent: str = "  ") -> None:
    """``  note: NOTE`` for each of ``notes`` (``indent`` before it), then ``  LABEL written
    to PATH`` for each ``(label, path)`` of ``outputs`` given a path."""
    for note in notes:
        print(f"{indent}note: {note}")
    for label, path in outputs:
        if path:
            print(f"  {label} written to {path}")


def write_text(path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path``, whole or not at all (:func:`mechcirc.outputs.atomic_open`).

    Parameters
    ----------
    path : str
        The output file (replaced atomically).
    text : str
        Its content.
    """
    from ..outputs import atomic_open

    with atomic_open(path, "w", encoding="utf-8") as fh:
        fh.write(text)


def load_with_warnings(path):
    """Load and reduce a netlist, returning the circuit and the warnings raised."""
    from ..circuit import units_of
    from ..netlist import load

    with warnings.catch_warnings(record=True, action="always") as caught:
        circuit = load(path)
        try:
            _ = circuit.tree    # reduce now, so topology errors and warnings surface here
        except NotSeriesParallelError:
            _ = circuit.nodal   # nodal analysis takes over; its own errors surface here
    messages, x = [str(w.message) for w in caught], units_of(circuit.drive)["x"]
    messages += [f"spring {e.name!r} has backlash={e.backlash:g} {x}: the frequency domain takes "
                 "its contact as closed (linearised); 'mechcirc transient' integrates the gap"
                 for e in circuit.elements if e.kind == "spring" and e.backlash >= 1e-10]
    d = circuit.drive
    if d.amplitude == 0:        # a value not filled in: everything but K would read 0
        messages.append(f"{path}:{d.line}:{d.col}: drive {d.name!r} has amplitude 0: Q0, v0 "
                        "and every element force are 0 at every frequency (K does not depend on it)")
    return circuit, messages


#: Names listed in the message of :func:`check_names`.
SHOWN_NAMES = 20


def scene_theta(args, scene, alternative: str = "") -> float:
    """The crank rotation [deg] of ``--theta``, or of the scene file's ``[analysis] theta_deg``.

    Parameters
    ----------
    args : argparse.Namespace
        With ``file`` and ``theta``.
    scene : Scene
        The scene read from ``args.file``.
    alternative : str
        Another option the error message offers (``" or --cycle"``).

    Returns
    -------
    float

    Raises
    ------
    MechcircError
        Neither gives a finite angle.
    """
    theta = args.theta if args.theta is not None else scene.analysis.theta_deg
    if theta is None or not math.isfinite(theta):
        raise MechcircError(f"{args.file}: give --theta DEG{alternative} (a finite crank "
                            "rotation from the pose; the file has no [analysis] theta_deg)")
    return theta


def set_values(items, not_numbers: dict | None = None, texts: bool = False,
               roles: dict | None = None) -> dict:
    """``--set NAME=VALUE`` options as ``{NAME: value}``, each value a finite number in SI
    units or with a unit (``omega=3000rpm``), at most 1e100 in magnitude.

    Parameters
    ----------
    items : list of str
        The options' texts.
    not_numbers : dict, optional
        Names that are not numbers, each with what to use instead.
    texts : bool
        Give each value as typed (checked all the same), for a reader that checks its unit.
    roles : dict, optional
        The names there are, each with the unit role (:data:`mechcirc.units.ROLES`) its
        value is read in; None: any name, any unit.

    Returns
    -------
    dict[str, float], or dict[str, str] with ``texts``

    Raises
    ------
    MechcircError
        A text without ``=``, a name of ``not_numbers`` or not of ``roles``, or a value
        that is not such a number (in its role's unit).
    """
    out, words = {}, not_numbers or {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not (sep and name):
            raise MechcircError(f"--set expects NAME=VALUE, got {item!r}")
        if name in words:
            raise MechcircError(f"--set {name}: not a numeric parameter; {words[name]}")
        if roles is not None and name not in roles:
            raise MechcircError(f"--set {name}: no such parameter{did_you_mean(name, roles)} "
                                f"(there are {', '.join(sorted(roles))})")
        try:
            v = parse_quantity(value, roles[name] if roles else None, what=name)
        except UnitError as exc:
            raise MechcircError(f"--set {name}: {exc.message} (expected {exc.expected})") \
                from None
        if not (math.isfinite(v) and abs(v) <= 1e100):    # C2 = 1e308 overflowed
            raise MechcircError(f"--set {name}: must be finite and at most 1e+100 in "
                                f"magnitude, got {value!r}")
        out[name] = value.strip() if texts else v
    return out


@dataclass(frozen=True)
class Default:
    """The registered default of an option :func:`refuse_ignored` governs: it marks the
    option as not given, and ``value`` is what the option then is (the one place the
    default is written, next to its help).  False when its value is (for tests of
    ``args.opt`` before the rules are applied); equal when the values are."""

    value: object

    def __bool__(self) -> bool:
        return bool(self.value)


def refuse_ignored(args, rules) -> None:
    """Refuse an option given where its value would not be read; default the others.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options; an option is given when it is neither None nor the
        :class:`Default` it was registered with (which is replaced by its value here).
    rules : dict
        ``"--opt": (applies, to_what, hint)``: whether the option is read with the
        other options and the input given; to what it applies, and how to make it
        apply ("" for no way) for the message.  ``"--no-opt"`` is the off side of
        the on/off flag ``--opt`` (dest ``opt``): its ``applies`` must hold when
        the value given is on.

    Raises
    ------
    InputError
        "--tol applies to --adaptive sweeps (leave --tol out, or add --adaptive)".
    """
    for option, (applies, to_what, hint) in rules.items():
        dest = option[2:].removeprefix("no-").replace("-", "_")
        value = getattr(args, dest)
        if isinstance(value, Default):
            setattr(args, dest, value.value)
        elif value is not None and not applies:
            raise InputError(f"{option} applies to {to_what} (leave {option} out"
                             f"{', or ' + hint if hint else ''})")


def check_names(names, known, kind: str = "element", option: str = "--element") -> None:
    """Refuse a name of ``names`` not in ``known``, with "did you mean", before the work.

    A typo in a name given on the command line is told at once, not after a
    long computation that the name is only looked up at the end of.

    Parameters
    ----------
    names : sequence of str or None
        The names given (None: none).
    known : sequence of str
        The names that exist, in the order to list them.
    kind : str
        What they name, for the message ("element", "node").
    option : str
        The command-line option that gave them.

    Raises
    ------
    MechcircError
        Naming the first unknown name, the nearest known one and at most
        :data:`SHOWN_NAMES` of the known names.
    """
    known = list(known)
    if bad := [n for n in names or () if n not in known]:
        more = f", ... ({len(known)} in all)" if len(known) > SHOWN_NAMES else ""
        raise MechcircError(f"unknown {kind} {bad[0]!r}{did_you_mean(bad[0], known)} "
                            f"(given to {option}; the netlist has "
                            f"{', '.join(known[:SHOWN_NAMES])}{more})")
