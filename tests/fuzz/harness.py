"""Generators and properties for fuzzing mechcirc's inputs.

Every generator takes a :class:`random.Random`, so one implementation serves
both hypothesis (``st.randoms()``, which shrinks failing inputs) and the long
run (plain seeded ``Random``, fast and reproducible).

The property checked by :func:`run_target` is the one issue 8 states: every
input ends in a result or in :class:`~mechcirc.errors.MechcircError` (with a
line and column inside the text when one is given) — no other exception,
and no hang (a per-input bound on CPU time enforced with ``SIGPROF``).
"""

from __future__ import annotations

import contextlib
import copy
import functools
import io
import math
import os
import random
import signal
import string
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import mechcirc
from mechcirc.errors import MechcircError, NetlistError

ROOT = Path(__file__).resolve().parents[2]
NETLIST_SEEDS = sorted((ROOT / "netlists").glob("*.mcir"))
#: Linkage files seed the linkage property; scene files (a [drive] table) the scene
#: reader and the CLI.  The docs' examples too (sliders with a ``stroke``, rocker
#: drives, their deliberately wrong files), after examples/ (SCENE_SEEDS[0] stays).
_DOCS_TOML = sorted((ROOT / "docs" / "examples").glob("*.toml"))
SCENE_SEEDS = sorted(p for p in (ROOT / "examples").glob("*.toml")
                     if "\n[drive]" in p.read_text()) + \
    [p for p in _DOCS_TOML if "\n[drive]" in p.read_text()]
TOML_SEEDS = sorted(p for p in (ROOT / "examples").glob("*.toml") if p not in SCENE_SEEDS) + \
    [p for p in _DOCS_TOML if p not in SCENE_SEEDS and "\n[points]" in p.read_text()]


@functools.lru_cache(maxsize=None)
def _read(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def seed_texts(paths) -> list[str]:
    return [_read(p) for p in paths]


# ---------------------------------------------------------------- time bound
class Hang(BaseException):
    """Raised by the alarm when one input exceeds its time bound.

    A ``BaseException`` so that no ``except Exception`` in the code under test
    can swallow it.
    """


@contextlib.contextmanager
def time_bound(seconds: float):
    """Raise :class:`Hang` if the block uses more than ``seconds`` of CPU time (main thread only).

    CPU time of the process (``ITIMER_PROF``), not the wall clock: a loaded
    machine slows every input down without making it more work, while a hang
    (an endless loop, an exponential blow-up) uses CPU until the bound.
    """
    def on_alarm(signum, frame):
        raise Hang(f"no result after {seconds} s of CPU time")

    old = signal.signal(signal.SIGPROF, on_alarm)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, old)


# ---------------------------------------------------------------- text mutation
#: Tokens that stress the netlist and expression grammars.
NETLIST_TOKENS = [
    "mass", "spring", "damper", "lever", "drive", ".param", "0", "a", "b", "T", "M",
    "velocity=", "force=", "ratio=", "eta=", "=", "{", "}", "(", ")", "**", "^", "*", "/",
    "+", "-", "1e308", "1e-308", "1e309", "4.9e-324", "-0", "0.0", "nan", "inf", "pi",
    "sqrt(", "log(", "exp(", "9**9**9", "1e999", "..", "1.2.3", "1e", "e5", "#", ";",
    "\t", " ", "\n", "\r\n", "\x00", "\ufeff", "é", "\u2212", "kg", "N/mm", "g", "N*s/m",
    "mm", "N", "rad/s", "deg", "1/0", "0**-1", "(-1)**0.5", "x" * 40, "9" * 400,
]

TOML_TOKENS = [
    "[points]", "[ground]", "[links]", "[[cranks]]", "points", "link", "pivot", "omega",
    "=", "[", "]", "\"", "'", ",", "1e400", "nan", "inf", "-inf", "0", "0.0", "true",
    "{}", "[]", "[1, 2]", "[1, 2, 3]", "\"O1\"", "\"A\"", "\"ground\"", "crank1",
    "name", "units", "\n", "#", "\x00", "é", "1979-05-27", "{a = 1}", "[[points]]",
    "3", "-30.0", "[\"O1\", \"O1\"]", "[\"A\"]", "[[\"A\"]]",
]


def mutate(rng: random.Random, text: str, tokens: list[str], max_ops: int = 6) -> str:
    """Apply 1..max_ops random edits to ``text`` (deletions, insertions, swaps, repeats)."""
    s = text
    for _ in range(rng.randint(1, max_ops)):
        op = rng.randrange(8)
        n = len(s)
        i = rng.randint(0, n)
        if op == 0 and n:                                   # delete a span
            j = min(n, i + rng.randint(1, 12))
            s = s[:i] + s[j:]
        elif op == 1:                                        # insert a token
            s = s[:i] + rng.choice(tokens) + s[i:]
        elif op == 2:                                        # insert random characters
            alphabet = string.printable + "\u00e9\u2212\u03c9\x00\ufeff"
            s = s[:i] + "".join(rng.choice(alphabet) for _ in range(rng.randint(1, 5))) + s[i:]
        elif op == 3 and n:                                  # replace one character
            j = min(n - 1, i)
            s = s[:j] + rng.choice(tokens + list("0123456789=.{}()-+ ")) + s[j + 1:]
        elif op == 4:                                        # shuffle or repeat lines
            lines = s.split("\n")
            if rng.random() < 0.5:
                rng.shuffle(lines)
            else:
                k = rng.randrange(len(lines))
                lines.insert(k, lines[k])
            s = "\n".join(lines)
        elif op == 5:                                        # drop a line
            lines = s.split("\n")
            if len(lines) > 1:
                del lines[rng.randrange(len(lines))]
            s = "\n".join(lines)
        elif op == 6:                                        # replace a number
            nums = [m for m in _number_spans(s)]
            if nums:
                a, b = rng.choice(nums)
                s = s[:a] + rng.choice(_WILD_NUMBERS) + s[b:]
        else:                                                # truncate
            s = s[:i]
    return s


_WILD_NUMBERS = ["0", "-1", "1e-300", "1e300", "1e308", "1e-320", "5e-324", "1e309",
                 "nan", "inf", "-0.0", "1" + "0" * 400, "0." + "0" * 400 + "1", "2.5",
                 "1e6", "1e-6", "0.999999999999", "{1/0}", "{-1}", "{sqrt(-1)}"]


def _number_spans(s: str):
    import re

    return [(m.start(), m.end()) for m in re.finditer(r"\d+\.?\d*(?:[eE][+-]?\d+)?", s)]


# ---------------------------------------------------------------- generated netlists
def random_value(rng: random.Random) -> str:
    """A value field: mostly sane, sometimes extreme or an expression."""
    r = rng.random()
    if r < 0.6:
        return repr(10.0 ** rng.uniform(-3, 6))
    if r < 0.75:
        return rng.choice(_WILD_NUMBERS)
    if r < 0.9:
        return "{" + random_expression(rng, depth=3) + "}"
    return repr(10.0 ** rng.uniform(-300, 300))


def random_netlist(rng: random.Random) -> str:
    """A netlist from the grammar: random topology (ladders, bridges, levers, floating parts)."""
    n_nodes = rng.randint(1, 7)
    nodes = ["0"] + [f"n{i}" for i in range(1, n_nodes + 1)]
    lines = []
    if rng.random() < 0.3:
        lines.append(f".param p1={random_value(rng)} p2={{p1*2}}")
    kinds = ["mass", "spring", "damper"]
    for k in range(rng.randint(1, 12)):
        a, b = rng.sample(nodes, 2) if len(nodes) > 1 else (nodes[0], nodes[0])
        kind = rng.choice(kinds)
        value = random_value(rng) if rng.random() < 0.9 else "p1"
        eta = f" eta={random_value(rng)}" if rng.random() < 0.15 else ""
        lines.append(f"{kind} e{k} {a} {b} {value}{eta}")
    for k in range(rng.choice([0, 0, 0, 1, 1, 2])):
        p = rng.sample(nodes, 2)
        s = rng.sample(nodes + [f"s{k}a", f"s{k}b"], 2)
        ratio = rng.choice(["1", "2.5", "0.5", "1e-9", "1e9", "1e-300", "1e300", "0", "-1"])
        lines.append(f"lever L{k} {p[0]} {p[1]} {s[0]} {s[1]} ratio={ratio}")
        if rng.random() < 0.7:
            lines.append(f"mass ms{k} {s[0]} {s[1]} 1.0")
    a, b = rng.sample(nodes, 2)
    kind = rng.choice(["velocity", "force"])
    lines.append(f"drive V {a} {b} {kind}={rng.choice(['0.1', '1', '1e-300', '1e300', '0'])}")
    rng.shuffle(lines)
    return "\n".join(lines) + "\n"


def random_expression(rng: random.Random, depth: int = 4) -> str:
    """An expression from the grammar, with hostile numbers and operators."""
    if depth <= 0 or rng.random() < 0.3:
        return rng.choice(["1", "2", "0", "9", "pi", "x", "y", "undefined", "1e308",
                           "1e-308", "0.5", "1e999", "3.", ".5", "1e-400"])
    r = rng.random()
    if r < 0.5:
        op = rng.choice(["+", "-", "*", "/", "**", "^"])
        return f"{random_expression(rng, depth - 1)} {op} {random_expression(rng, depth - 1)}"
    if r < 0.65:
        return f"-{random_expression(rng, depth - 1)}"
    if r < 0.85:
        return f"({random_expression(rng, depth - 1)})"
    fn = rng.choice(["sqrt", "sin", "cos", "tan", "exp", "log", "radians", "degrees", "nope"])
    return f"{fn}({random_expression(rng, depth - 1)})"


def expression_input(rng: random.Random) -> str:
    r = rng.random()
    if r < 0.5:
        return random_expression(rng, depth=rng.randint(1, 6))
    if r < 0.8:
        return mutate(rng, random_expression(rng, depth=4),
                      ["(", ")", "**", "^", "e", ".", "-", "+", "1e309", "9**9**9", " ", "_"])
    return "".join(rng.choice("0123456789.eE+-*/^() pix") for _ in range(rng.randint(0, 40)))


def netlist_input(rng: random.Random) -> str:
    r = rng.random()
    if r < 0.45:
        return mutate(rng, rng.choice(seed_texts(NETLIST_SEEDS)), NETLIST_TOKENS)
    if r < 0.9:
        return random_netlist(rng)
    return mutate(rng, random_netlist(rng), NETLIST_TOKENS, max_ops=3)


def toml_input(rng: random.Random) -> str:
    """Half text mutations (mostly TOML syntax errors), half structural changes
    (valid TOML whose tables, lists and values have the wrong kinds or extremes)."""
    if rng.random() < 0.5:
        return mutate(rng, rng.choice(seed_texts(TOML_SEEDS)), TOML_TOKENS, max_ops=4)
    import tomllib

    doc = tomllib.loads(rng.choice(seed_texts(TOML_SEEDS)))
    for _ in range(rng.randint(1, 3)):
        _mutate_tree(rng, doc)
    return dump_toml(doc)


_TOML_VALUES = [0, -1, 3, 10**400, -(10**400), 1e-300, 1e300, 5e-324, float("nan"),
                float("inf"), 0.0, True, "O1", "A", "crank1", "ground", "", "é", [], {},
                [1.0], [1.0, 2.0, 3.0], ["O1"], ["O1", "O1"], [["A", "B"]], {"a": 1},
                [{"link": "crank1"}], ["A", 1]]


def _mutate_tree(rng: random.Random, node) -> None:
    """Replace, delete or add one entry somewhere in the parsed TOML tree."""
    path = []
    while isinstance(node, (dict, list)) and node and rng.random() < 0.7:
        key = rng.choice(list(node)) if isinstance(node, dict) else rng.randrange(len(node))
        child = node[key]
        if not isinstance(child, (dict, list)) or not child:
            break
        path.append(key)
        node = child
    if isinstance(node, dict):
        keys = list(node)
        r = rng.random()
        if keys and r < 0.6:
            node[rng.choice(keys)] = copy.deepcopy(rng.choice(_TOML_VALUES))
        elif keys and r < 0.8:
            del node[rng.choice(keys)]
        else:
            node[rng.choice(["omega", "pivot", "link", "X", "points", "name"])] = \
                copy.deepcopy(rng.choice(_TOML_VALUES))
    elif isinstance(node, list) and node:
        node[rng.randrange(len(node))] = copy.deepcopy(rng.choice(_TOML_VALUES))


def dump_toml(doc: dict) -> str:
    """A small TOML writer (tables, arrays of tables, inline values) for the fuzz."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int):
            return str(v)
        if isinstance(v, float):
            if math.isnan(v):
                return "nan"
            if math.isinf(v):
                return "inf" if v > 0 else "-inf"
            return repr(v)
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{_key(k)} = {value(x)}" for k, x in v.items()) + "}"
        raise TypeError(type(v))

    out, tables = [], []
    for k, v in doc.items():
        if isinstance(v, dict):
            tables.append((k, v, False))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((k, v, True))
        else:
            out.append(f"{_key(k)} = {value(v)}")
    for k, v, many in tables:
        for t in (v if many else [v]):
            out.append(f"[[{_key(k)}]]" if many else f"[{_key(k)}]")
            out.extend(f"{_key(kk)} = {value(vv)}" for kk, vv in t.items())
    return "\n".join(out) + "\n"


def _key(k: str) -> str:
    import re

    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else '"' + k.replace('"', '\\"') + '"'


# ---------------------------------------------------------------- properties
@dataclass
class Tally:
    """Outcome counts of a fuzz run."""

    results: int = 0
    errors: int = 0
    failures: list = field(default_factory=list)

    @property
    def total(self) -> int:
        return self.results + self.errors + len(self.failures)


class PropertyFailure(AssertionError):
    pass


def _check_location(exc: NetlistError, text: str | None, *, one_line: bool = False) -> None:
    """A NetlistError that names a line must name one inside the text.

    ``one_line``: the text is a single field (an expression), so the column
    counts every character, line separators included.
    """
    if text is None or not exc.line:
        return
    from mechcirc.sources import split_lines      # lines as editors and wc -l count them

    lines = [text] if one_line else (split_lines(text) or [""])
    if not 1 <= exc.line <= len(lines):
        raise PropertyFailure(f"line {exc.line} outside the text ({len(lines)} lines): {exc}")
    if not 1 <= exc.col <= len(lines[exc.line - 1]) + 2:
        raise PropertyFailure(f"column {exc.col} outside line {exc.line} "
                              f"(length {len(lines[exc.line - 1])}): {exc}")


def run_target(fn, text: str | None, *, seconds: float = 5.0, one_line: bool = False):
    """Run ``fn()``; return ``"result"`` or ``"error"``, or raise :class:`PropertyFailure`."""
    try:
        with time_bound(seconds), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fn()
    except MechcircError as exc:
        if isinstance(exc, NetlistError):
            _check_location(exc, text, one_line=one_line)
        if not str(exc).strip():
            raise PropertyFailure(f"{type(exc).__name__} with an empty message") from exc
        return "error"
    except Hang as exc:
        raise PropertyFailure(f"hang: {exc}") from None
    except Exception as exc:  # noqa: BLE001 - this is what we look for
        raise PropertyFailure(f"{type(exc).__name__}: {exc}") from exc
    return "result"


OMEGA_PROBE = np.array([0.0, 1e-3, 1.0, 37.0, 1e3, 1e6, 1e300])


def netlist_property(text: str) -> str:
    """Parse, reduce, sweep (ω = 0 and extremes included) and find resonances."""
    def go():
        c = mechcirc.parse(text)
        s = c.sweep(OMEGA_PROBE)
        flags = s.flags
        bad = ~np.isfinite(s.K) | ~np.isfinite(s.Q0) | ~np.isfinite(s.v0)
        if np.any(bad & (flags == 0)):
            raise PropertyFailure(f"non-finite K/Q0/v0 without a flag at ω = "
                                  f"{s.omega[bad & (flags == 0)]}")
        _ = s.error
        for r in c.resonances():
            if not (math.isfinite(r.omega) and r.omega >= 0):
                raise PropertyFailure(f"resonance at ω = {r.omega}")
    return run_target(go, text)


def expression_property(text: str) -> str:
    from mechcirc.expressions import evaluate, parse_expression

    def go():
        tree = parse_expression(text, line=1)
        value = evaluate(tree, {"x": 2.0, "y": -0.5}, line=1)
        if not isinstance(value, float):
            raise PropertyFailure(f"evaluate returned {type(value).__name__} {value!r}")
    return run_target(go, text, one_line=True)


def linkage_property(text: str) -> str:
    from mechcirc.kinematics.linkage import parse_linkage

    def go():
        lk = parse_linkage(text, "fuzz.toml")
        lk.solve(0.3)
    return run_target(go, text)


# ---------------------------------------------------------------- CLI argv
@functools.lru_cache(maxsize=None)
def cli_commands():
    """``{name: subparser}`` of every registered sub-command (built once, read only)."""
    import argparse

    from mechcirc.cli import build_parser

    parser = build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


#: Commands whose inputs the CLI fuzz drives (others are owned elsewhere and
#: may be added by the long run's --all-commands).
CLI_COMMANDS = ("check", "sweep", "resonances", "fourbar", "synth", "linkage", "simulate",
                "crosscheck")

_WILD_ARGS = ["0", "-1", "1", "2.5", "1e308", "1e-308", "nan", "inf", "-inf", "1e400",
              "", "abc", "3", "7", "10", "100", "1e6", "-0", "all", "x=1", "clearance=0.002",
              "clearance=nan", "=", "1e-300"]


def _value_for(rng: random.Random, action, workdir: Path, files: list[str]) -> str:
    meta = (action.metavar or action.dest or "").upper()
    if action.choices is not None and rng.random() < 0.85:
        return str(rng.choice(list(action.choices)))
    if meta in ("CSV", "IMAGE", "S1P", "FILE", "OUT", "JSON") or "output" in action.dest \
            or action.dest in ("plot", "netlist", "touchstone", "export"):
        ext = rng.choice([".csv", ".png", ".svg", ".txt", "", ".s1p", ".xyz", ".mcir"])
        if rng.random() < 0.1:
            return str(workdir / "missing" / f"out{ext}")
        return str(workdir / f"out{rng.randrange(3)}{ext}")
    if action.dest == "points":
        return str(rng.choice([1, 2, 3, 10, 50, 0, -5, 20_000_001]))
    if action.dest == "revolutions":
        return str(rng.choice([1, 2, 0, -1, 10**9]))
    if action.dest in ("limit",):
        return str(rng.choice([1, 3, 0, -1]))
    return rng.choice(_WILD_ARGS + files[:2])


def cli_argv(rng: random.Random, workdir: Path, files: list[str],
             commands=CLI_COMMANDS) -> list[str]:
    """A random argv for one sub-command: its options with random (often bad) values."""
    import argparse

    subs = cli_commands()
    name = rng.choice([c for c in commands if c in subs])
    sub = subs[name]
    argv = [name]
    for action in sub._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        required = action.required or not action.option_strings
        if not required and rng.random() < 0.6:
            continue
        if not action.option_strings:            # positional: a file
            argv.append(rng.choice(files))
            continue
        argv.append(rng.choice(action.option_strings))
        if action.nargs == 0:
            continue
        # Keep the costly knobs of the time-domain and synthesis commands small.
        if name in ("simulate",) and action.dest == "points":
            argv.append(rng.choice(["36", "0", "-1", "abc"]))
        elif name == "simulate" and action.dest == "variant":
            argv.append(rng.choice(["1", "3", "7", "0", "8", "x"]))
        elif name == "simulate" and action.dest == "revolutions":
            argv.append(rng.choice(["1", "2", "0", "-1"]))
        elif name == "simulate" and action.dest in ("steps_per_period", "rtol"):
            argv.append(rng.choice(["5", "50", "0", "-1", "nan", "1e-3", "inf"]))
        else:
            argv.append(_value_for(rng, action, workdir, files))
    if rng.random() < 0.1:
        argv.insert(rng.randrange(len(argv) + 1), rng.choice(["--bogus", "-x", "--", "--json"]))
    if name == "simulate" and "--method" in argv:
        i = argv.index("--method")
        if i + 1 < len(argv) and argv[i + 1] in ("DOP853", "RK45", "LSODA"):
            argv[i + 1] = "rk4"      # the scipy integrators take seconds per variant
    return argv


def api_network(seed: int) -> str:
    """A valid random network (:func:`reference.mp_nodal.random_network`: meshes, levers,
    values over 1–10 decades), with a force drive or a ``.param`` now and then."""
    from reference import mp_nodal

    rng = np.random.default_rng(seed)
    text, _, _ = mp_nodal.random_network(
        rng, n_nodes=int(rng.integers(2, 7)), damped=bool(rng.random() < 0.6),
        levers=int(rng.integers(0, 3)), decades=float(rng.uniform(1, 10)))
    if rng.random() < 0.3:
        text = text.replace("drive V n1 0 velocity=1", "drive F n1 0 force=2")
    if rng.random() < 0.3:                  # the first element's value as a .param
        lines = text.splitlines()
        words = lines[1].split()
        lines[1:2] = [f".param p0={words[4]}", " ".join(words[:4] + ["{p0}"])]
        text = "\n".join(lines) + "\n"
    return text


def api_property(text: str) -> str:
    """Every public analysis of a valid network ends in a result or a MechcircError:
    sweeps (both methods, unrefined, with bounds), element forces and velocities,
    resonances, modes, the three kinds of peak, the adaptive sweep, sensitivities,
    ``unloaded``, scikit-rf, simplify, a two-port, and designs of a ``.param``."""
    from mechcirc.modes import sweep_sensitivity

    c = mechcirc.parse(text)
    scale = np.sqrt(np.median([e.value for e in c.elements if e.kind == "spring"] or [1.0]) /
                    np.median([e.value for e in c.elements if e.kind == "mass"] or [1.0]))
    lo, hi = scale / 1e3, scale * 1e3
    w = np.geomspace(lo, hi, 50)
    last = c.elements[-1]
    calls = [
        lambda: c.sweep(w), lambda: c.sweep(w, method="nodal", refine=False),
        lambda: c.sweep(w, error=True).error,
        lambda: [(s.force(e.name), s.velocity(e.name))
                 for s in [c.sweep(w[:3])] for e in c.elements],
        lambda: c.resonances(hi), lambda: c.modes(hi), lambda: c.unloaded,
        *(functools.partial(mechcirc.peak, c, lo, hi, q) for q in (None, "K", "S")),
        lambda: mechcirc.adaptive_sweep(c, lo, hi, max_points=400),
        lambda: sweep_sensitivity(c, w[:5]), lambda: c.sweep(w[:5]).to_skrf(),
        lambda: mechcirc.simplify(c, (lo * 10, hi / 10), 0.01),
        lambda: c.two_port("n1", "0", last.n1, last.n2 if last.n2 != last.n1 else "0", w[:5]),
    ]
    if c.params:
        calls.append(lambda: mechcirc.designs(c, {"p0": np.array([1.0, 2.0]) * c.params["p0"]})
                     .sweep(w[:5]))
    outcomes = [run_target(call, None, seconds=30.0) for call in calls]
    return "error" if "error" in outcomes else "result"


def cli_property(argv: list[str], *, seconds: float = 20.0) -> str:
    """``main(argv)`` ends with exit 0 or 2 (argparse's own exits included), never 1 or a traceback."""
    from mechcirc.cli import main

    out, err = io.StringIO(), io.StringIO()
    try:
        with time_bound(seconds), warnings.catch_warnings(), \
                contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            # Warnings shown as a user would see them: a RuntimeWarning line
            # before a user error's message is a failure (issue 16 §2).
            warnings.simplefilter("always", RuntimeWarning)
            try:
                status = main(argv)
            except SystemExit as exc:        # argparse: usage errors (2) and --help (0)
                status = exc.code if isinstance(exc.code, int) else 2
    except Hang:
        raise PropertyFailure(f"hang: {argv}") from None
    except Exception as exc:  # noqa: BLE001
        raise PropertyFailure(f"{type(exc).__name__} escaped main({argv}): {exc}") from exc
    text = err.getvalue()
    # 3: a crosscheck found the two domains disagreeing (a verdict, not a failure)
    ok = (0, 2, 3) if argv and argv[0] == "crosscheck" else (0, 2)
    if status not in ok or "Traceback" in text or "internal error" in text:
        raise PropertyFailure(f"main({argv}) -> {status}: {text.strip()[:500]}")
    if status == 2 and "RuntimeWarning" in text:
        raise PropertyFailure(f"main({argv}) -> 2 after a RuntimeWarning: {text.strip()[:500]}")
    if status == 2 and not (text.strip() or out.getvalue().strip()):
        raise PropertyFailure(f"main({argv}) -> 2 with no message")
    return {0: "result", 3: "verdict"}.get(status, "error")


def cli_files(workdir: Path, rng: random.Random | None = None) -> list[str]:
    """Input files for the CLI fuzz: the bundled ones, mutated copies, and bad paths."""
    rng = rng or random.Random(0)
    files = [str(p) for p in NETLIST_SEEDS + TOML_SEEDS + SCENE_SEEDS]
    for k in range(4):
        p = workdir / f"mut{k}.mcir"
        p.write_text(netlist_input(rng), encoding="utf-8", errors="surrogatepass")
        files.append(str(p))
        q = workdir / f"mut{k}.toml"
        q.write_text(toml_input(rng), encoding="utf-8", errors="surrogatepass")
        files.append(str(q))
    (workdir / "bad_utf8.mcir").write_bytes(b"mass m1 a 0 2\xff\ndrive V a 0 velocity=1\n")
    (workdir / "bad_utf8.toml").write_bytes(b"name = \"\xff\"\n")
    files += [str(workdir / "bad_utf8.mcir"), str(workdir / "bad_utf8.toml"),
              str(workdir / "nope.mcir"), str(workdir), os.devnull]
    return files


# ---------------------------------------------------------------- files of every kind (issue 16)
STUDY_SEED = ROOT / "examples" / "study_stb.toml"

#: Characters that str.splitlines() takes for line breaks and editors do not.
LINE_BREAKERS = ["\x0c", "\x0b", "\r", "\x85", "\u2028", "\u2029", "\x1c", "\x1d", "\x1e",
                 "\r\n", "\n\r"]

#: Values that belong nowhere a name or a number is expected.
HOSTILE_VALUES = [[-12], ["M"], ["crank"], [["A"]], {"x": 1}, 10**400, -(10**400),
                  int("9" * 300), 10**5000 // 10**4990, float("nan"), float("inf"), True, "",
                  "\x00", "é" * 3, [], {}]


def _pickle_bytes(rng: random.Random) -> bytes:
    """A pickle (harmless payload) — a data file must never be unpickled."""
    import pickle

    obj = rng.choice([{"a": 1}, [1.0, 2.0], "text", (1, "x"), np.arange(3)])
    return pickle.dumps(obj, protocol=rng.randint(0, pickle.HIGHEST_PROTOCOL))


def binary_bytes(rng: random.Random) -> bytes:
    """Bytes that are not the expected text: pickles, PNG/zip/npz headers, noise, non-UTF-8."""
    r = rng.random()
    if r < 0.25:
        return _pickle_bytes(rng)
    if r < 0.4:
        return rng.choice([b"\x89PNG\r\n\x1a\n", b"PK\x03\x04", b"\x93NUMPY\x01\x00",
                           b"\x7fELF\x02\x01", b"%PDF-1.4\n"]) + rng.randbytes(rng.randint(0, 200))
    if r < 0.6:
        return rng.randbytes(rng.randint(0, 400))
    text = rng.choice(seed_texts(NETLIST_SEEDS + TOML_SEEDS)).encode("utf-8")
    i = rng.randint(0, len(text))
    bad = rng.choice([b"\xff", b"\xfe\xff", b"\xc3", b"\xed\xa0\x80", b"\x80", b"\xf8\x88"])
    return text[:i] + bad + text[i:]


def with_line_breakers(rng: random.Random, text: str) -> str:
    """``text`` with characters that ``str.splitlines`` (not wc -l) takes for line ends."""
    for _ in range(rng.randint(1, 4)):
        i = rng.randint(0, len(text))
        text = text[:i] + rng.choice(LINE_BREAKERS) + text[i:]
    return text


def _hostile_tree(rng: random.Random, doc: dict) -> dict:
    """The parsed document with one scalar, name or table replaced by a hostile value."""
    doc = copy.deepcopy(doc)
    for _ in range(rng.randint(1, 2)):
        node = doc
        while True:
            if isinstance(node, dict) and node:
                key = rng.choice(list(node))
            elif isinstance(node, list) and node:
                key = rng.randrange(len(node))
            else:
                break
            child = node[key]
            if isinstance(child, (dict, list)) and child and rng.random() < 0.75:
                node = child
                continue
            node[key] = copy.deepcopy(rng.choice(HOSTILE_VALUES))
            break
    return doc


def toml_file_input(rng: random.Random, seed_path: Path) -> bytes:
    """Bytes for a TOML input (scene, study, linkage): structural, text, line-break or binary."""
    import tomllib

    text = _read(seed_path)
    r = rng.random()
    if r < 0.45:
        out = dump_toml(_hostile_tree(rng, tomllib.loads(text)))
    elif r < 0.7:
        out = mutate(rng, text, TOML_TOKENS, max_ops=3)
    elif r < 0.9:
        out = with_line_breakers(rng, mutate(rng, text, TOML_TOKENS, max_ops=1))
    else:
        return binary_bytes(rng)
    return out.encode("utf-8", errors="surrogatepass")


def touchstone_input(rng: random.Random) -> bytes:
    """Touchstone one-port text with hostile option lines and data, or binary."""
    if rng.random() < 0.15:
        return binary_bytes(rng)
    unit = rng.choice(["Hz", "kHz", "MHz", "GHz", "THz", "rpm", ""])
    fmt = rng.choice(["RI", "MA", "DB", "XY", ""])
    param = rng.choice(["Z", "Y", "S", "H", ""])
    R = rng.choice(["1", "50", "-50", "0", "nan", "inf", "1e-320", "x", ""])
    lines = [f"# {unit} {param} {fmt} R {R}".replace("  ", " ")] if rng.random() < 0.9 else []
    f = 1.0
    for _ in range(rng.randint(0, 8)):
        f = rng.choice([f * 2, -f, float("nan"), f, 0.0, 1e308, f + 1])
        a = rng.choice(["1", "0", "-1", "1e308", "1e-320", "nan", "inf", "1e400", "300"])
        b = rng.choice(["0", "90", "-1e308", "nan", "2"])
        lines.append(" ".join([repr(f), a, b][:rng.choice([3, 3, 3, 2, 4])]))
    text = "\n".join(lines) + "\n"
    if rng.random() < 0.2:
        text = with_line_breakers(rng, text)
    return text.encode("utf-8")


def netlist_file_input(rng: random.Random) -> bytes:
    r = rng.random()
    if r < 0.6:
        return netlist_input(rng).encode("utf-8", errors="surrogatepass")
    if r < 0.85:
        return with_line_breakers(rng, netlist_input(rng)).encode("utf-8", errors="surrogatepass")
    return binary_bytes(rng)


def blowup_netlist(rng: random.Random, n: int | None = None) -> str:
    """Long parallel or series runs (quadratic reductions showed here: 16k parallel, 264 s)."""
    n = n or rng.choice([100, 1000, 4000])
    if rng.random() < 0.5:                     # n elements in parallel between a and 0
        lines = [f"{rng.choice(['spring', 'damper', 'mass'])} e{i} a 0 {1 + i % 7}"
                 for i in range(n)]
    else:                                      # a series chain of n springs and dampers
        lines = [f"{rng.choice(['spring', 'damper'])} e{i} n{i} n{i + 1} {1 + i % 7}"
                 for i in range(n)] + [f"mass m n{n} 0 1"]
        lines.append("drive V n0 0 velocity=1")
        return "\n".join(lines) + "\n"
    lines.append("drive V a 0 velocity=1")
    return "\n".join(lines) + "\n"


FILE_KINDS = ("netlist", "linkage", "scene", "study", "touchstone")


def file_input(rng: random.Random, kind: str) -> bytes:
    if kind == "netlist":
        return netlist_file_input(rng)
    if kind == "linkage":
        return toml_file_input(rng, rng.choice(TOML_SEEDS))
    if kind == "scene":
        return toml_file_input(rng, rng.choice(SCENE_SEEDS))
    if kind == "study":
        return toml_file_input(rng, STUDY_SEED)
    return touchstone_input(rng)


def file_property(kind: str, data: bytes, workdir: Path, *, seconds: float = 10.0) -> str:
    """Load ``data`` as a file of ``kind`` through the public reader (and one analysis).

    The reader must end in a result or a located ``MechcircError``; a pickle
    must never be loaded (checked by the harness's ``pickle.load`` guard).
    """
    import pickle

    suffix = {"netlist": ".mcir", "linkage": ".toml", "scene": ".toml", "study": ".toml",
              "touchstone": ".s1p"}[kind]
    folder = workdir / "specs" if kind == "study" else workdir
    folder.mkdir(exist_ok=True)
    path = folder / f"fuzz_{kind}{suffix}"
    path.write_bytes(data)
    if kind == "study":       # the spec's ../netlists/stb_heald.mcir
        (workdir / "netlists").mkdir(exist_ok=True)
        target = workdir / "netlists" / "stb_heald.mcir"
        if not target.exists():
            target.write_text(_read(NETLIST_SEEDS[0]))
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError:
        text = None

    def go():
        if kind == "netlist":
            c = mechcirc.load(path)
            c.sweep(OMEGA_PROBE[1:5]).flags
        elif kind == "linkage":
            from mechcirc.kinematics.linkage import load_linkage

            load_linkage(path).solve(0.3)
        elif kind == "scene":
            from mechcirc.scene import build, load_scene

            build(load_scene(path), 0.3)
        elif kind == "study":
            from mechcirc.study import load_spec

            load_spec(path)
        else:
            from mechcirc.interop.touchstone import read_touchstone_one_port

            read_touchstone_one_port(path)

    real_loads, real_load = pickle.loads, pickle.load

    # Only the fuzzed file is guarded: numba loads the index of its own cache of
    # mechcirc's compiled kernels with pickle.load, which is not a user's file.
    def refuse_load(f, *a, **k):
        name = str(getattr(f, "name", ""))
        if not name or Path(name).resolve() == path.resolve():
            raise PropertyFailure(f"{kind}: a data file was unpickled")
        return real_load(f, *a, **k)

    def refuse_loads(b, *a, **k):
        if bytes(b)[:64] in data:
            raise PropertyFailure(f"{kind}: a data file was unpickled")
        return real_loads(b, *a, **k)

    pickle.loads, pickle.load = refuse_loads, refuse_load
    try:
        return run_target(go, text, seconds=seconds)
    finally:
        pickle.loads, pickle.load = real_loads, real_load


#: Time bound of a blow-up netlist (issue 16 §3: no input within the statement
#: limit may take more than a few seconds).
BLOWUP_SECONDS = 20.0


def netlist_blowup_property(text: str) -> str:
    """Parse, reduce and sweep 50 points of a long parallel or series run, in bounded time."""
    def go():
        c = mechcirc.parse(text)
        c.sweep(np.geomspace(1.0, 1e4, 50)).flags
    return run_target(go, text, seconds=BLOWUP_SECONDS)


# ---------------------------------------------------------------- this round's inputs (issue 23)
#: The motion laws a netlist's ``drive ... motion=LAW`` and ``cam --law`` accept.
MOTION_LAWS = ("harmonic", "cycloidal", "modified_sine", "modified_trapezoid", "polynomial_345")
CAM_SEED = ROOT / "docs" / "examples" / "cam_drive.mcir"
LIFT_SEED = ROOT / "docs" / "examples" / "lift.csv"

#: Which input each ``round_argv`` kind builds: periodic drives (a law, a table),
#: the cam command, resonances with modes and sensitivities, the sweep's
#: sensitivity, node and element columns, a study's sample file, crosscheck.
ROUND_KINDS = ("periodic_law", "periodic_table", "cam", "resonances", "sweep_sensitivity",
               "study_sample", "crosscheck")

_ROUND_NUMBERS = _WILD_NUMBERS + ["-5", "360", "361", "720", "1e-9", "abc", "", "1.5 rad",
                                  "100 mm", "10 kg", "2 Hz", "0x10", "1_000", "+1", "1e-12"]


def _num(rng: random.Random, sane: str, p_sane: float = 0.6) -> str:
    """``sane`` most of the time, otherwise a bad, non-finite, huge or tiny number."""
    return sane if rng.random() < p_sane else rng.choice(_ROUND_NUMBERS)


def motion_drive_line(rng: random.Random) -> str:
    """``drive V0 T 0 motion=LAW rise= dwell= return= stroke=`` with bad, missing or stray fields."""
    law = rng.choice(MOTION_LAWS) if rng.random() < 0.9 else rng.choice(["bogus", "", "CYCLOIDAL"])
    fields = [f"{key}={sane}" for key, sane in
              (("rise", "120"), ("dwell", "60"), ("return", "120"), ("stroke", "100 mm"))
              if rng.random() < 0.95]
    if rng.random() < 0.5:                                   # one field made wrong at most
        fields = [f.split("=")[0] + "=" + _num(rng, f.split("=", 1)[1], 0.0) if i == 0 else f
                  for i, f in enumerate(rng.sample(fields, len(fields)))]
    if rng.random() < 0.15:
        fields.append(f"return_law={rng.choice(MOTION_LAWS + ('nope',))}")
    if rng.random() < 0.15:          # stray or duplicated options
        fields.append(rng.choice(["velocity=1", "force=1", "motion=cycloidal", "bogus=1",
                                  "rise=10", "eta=2", "stroke=", "=", "motion=lift.csv"]))
    rng.shuffle(fields)
    return f"drive  V0  T 0 motion={law} " + " ".join(fields)


def motion_table(rng: random.Random) -> bytes:
    """A lift table (``angle_deg,displacement``) made wrong in one or more ways."""
    if rng.random() < 0.05:
        return binary_bytes(rng)
    n = rng.choice([2, 3, 8, 37, 73])
    rows = [[360.0 * i / (n - 1), 0.05 * (1 - math.cos(2 * math.pi * i / (n - 1)))]
            for i in range(n)]
    header = ["angle_deg", "displacement"]
    for _ in range(rng.randint(0, 3)):
        op = rng.randrange(9)
        if not rows:                                     # emptied by an earlier edit
            break
        if op == 0 and len(rows) > 2:                    # unsorted
            i, j = rng.sample(range(len(rows)), 2)
            rows[i], rows[j] = rows[j], rows[i]
        elif op == 1:                                    # duplicate angle
            k = rng.randrange(len(rows))
            rows.insert(k, list(rows[k]))
        elif op == 2:                                    # a bad cell
            row = rows[rng.randrange(len(rows))] if rows else []
            if row:
                row[rng.randrange(len(row))] = rng.choice(_ROUND_NUMBERS)
        elif op == 3:                                    # missing or extra column
            if rng.random() < 0.5:
                c = rng.randrange(2)
                header = [h for i, h in enumerate(header) if i != c]
                rows = [[v for i, v in enumerate(r) if i != c] for r in rows]
            else:
                header.append(rng.choice(["extra", "angle_deg", ""]))
                rows = [r + [1.0] for r in rows]
        elif op == 4:                                    # header renamed, reordered or gone
            header = rng.choice([["angle", "displacement"], header[::-1], [], ["a", "b"]])
        elif op == 5:                                    # not one revolution / not closing
            if rows and rows[-1]:
                rows[-1][rng.randrange(len(rows[-1]))] = rng.choice([359.0, 720.0, 0.5, 1e300])
        elif op == 6 and len(rows) > 1:                  # drop or truncate a row
            k = rng.randrange(len(rows))
            rows[k] = rows[k][:1] if rng.random() < 0.5 else rows[k] + [0]
            if rng.random() < 0.5:
                del rows[k]
        elif op == 7:                                    # scale the displacements wildly
            f = rng.choice([1e300, 1e-300, 1e-320, -1.0, 0.0])
            rows = [r[:1] + [v * f if isinstance(v, float) else v for v in r[1:]]
                    for r in rows]
        else:
            rows = rows[:rng.randint(0, 2)]
    text = "# fuzzed lift\n" + ",".join(header) + "\n" + "".join(
        ",".join(str(v) for v in r) + "\n" for r in rows)
    if rng.random() < 0.2:
        text = mutate(rng, text, [",", "\n", "nan", "#", "\"", " ", "1e999", ";"], max_ops=2)
    return text.encode("utf-8", errors="surrogatepass")


def round_files(workdir: Path) -> dict[str, str]:
    """Write the unchanging seeds of :func:`round_argv` into ``workdir`` (once)."""
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / "lift_ok.csv").write_text(_read(LIFT_SEED))
    (workdir / "stb.mcir").write_text(_read(NETLIST_SEEDS[-1]))
    return {"stb": str(workdir / "stb.mcir"), "lift_ok": str(workdir / "lift_ok.csv")}


def _cam_netlist(rng: random.Random, drive: str) -> str:
    lines = _read(CAM_SEED).splitlines()
    lines = [drive if ln.startswith("drive") else ln for ln in lines]
    text = "\n".join(lines) + "\n"
    return mutate(rng, text, NETLIST_TOKENS, max_ops=2) if rng.random() < 0.15 else text


def _opts(rng: random.Random, options: list[tuple[str, list[str]]], p: float = 0.4,
          bad: float = 0.4) -> list[str]:
    """Each option with probability ``p``; its value the list's first (sane) one, or with
    probability ``bad`` any of the list (most of them wrong)."""
    argv = []
    for name, values in options:
        if rng.random() < p:
            if values:
                argv += [name, rng.choice(values) if rng.random() < bad else values[0]]
            else:
                argv.append(name)
    return argv


_STRAY = ["--bogus", "-x", "--", "--json", "--rpm", "--modes", "--sensitivity", "--law"]


def round_argv(rng: random.Random, kind: str, workdir: Path, seeds: dict[str, str]) -> list[str]:
    """A command line of this round's commands and inputs, files written into ``workdir``."""
    W = str(workdir)
    bad = rng.choice([0.0, 0.1, 0.4])        # share of wrong values: none, few, many
    if kind in ("periodic_law", "periodic_table"):
        if kind == "periodic_law":
            drive = motion_drive_line(rng)
        else:
            (workdir / "lift.csv").write_bytes(motion_table(rng))
            target = rng.choice(["lift.csv"] * 8 + ["lift_ok.csv", "missing.csv", "",
                                                    "lift.csv extra=1", W, "/dev/null"])
            drive = f"drive  V0  T 0 motion={target}"
        (workdir / "periodic.mcir").write_text(_cam_netlist(rng, drive), encoding="utf-8",
                                               errors="surrogatepass")
        argv = ["periodic", W + "/periodic.mcir"]
        if rng.random() < 0.6:
            argv += ["--rpm", _num(rng, rng.choice(["60", "600", "3000"]), 1 - bad)]
        else:
            argv += ["--rpm-min", _num(rng, "100", 1 - bad), "--rpm-max", _num(rng, "1200", 1 - bad),
                     "--points", _num(rng, "12", 1 - bad)]      # the default 200 takes seconds
        argv += _opts(rng, [("--points", ["5", "20", "0", "1", "-3", "2", "abc", "1000000000"]),
                            ("--angles", ["36", "360", "0", "1", "nan", "1000000000"]),
                            ("--tol", ["1e-4", "1e-12", "0", "-1", "nan", "1", "1e-300"]),
                            ("--harmonics", ["10", "1", "0", "-1", "1000000000", "x"]),
                            ("--elements", ["k1", "all", "nope", "k1,m2", "", ",", "V0"]),
                            ("--near", ["0.03", "0", "-1", "nan", "1e300"]),
                            ("--method", ["auto", "sp", "nodal", "x"]),
                            ("-o", [W + "/Q.csv", W + "/missing/Q.csv", W + "/periodic.mcir"]),
                            ("--plot", [W + "/Q.png", W + "/Q.xyz"]), ("--json", [])], 0.25, bad)
    elif kind == "cam":
        follower = rng.choice(["roller", "flat", "oscillating"])
        argv = ["cam", "--follower", follower, "--base-radius", _num(rng, "40", 1 - bad)]
        argv += {"roller": ["--roller-radius", "10"], "flat": [],
                 "oscillating": ["--roller-radius", "10", "--arm", "50", "--pivot", "60"]}[follower]
        r = rng.random()
        if r < 0.6:
            argv += ["--law", rng.choice(MOTION_LAWS)]
            argv += [a if a.startswith("-") else _num(rng, a, 1 - bad / 2) for a in
                     ["--rise", "120", "--return", "120", "--stroke", "20"]]
            argv += _opts(rng, [("--dwell", ["60", "0", "1e-320", "300", "nan"]),
                                ("--low-dwell", ["60", "0", "100", "nan"]),
                                ("--return-law", list(MOTION_LAWS) + ["x"])], 0.4, bad)
        elif r < 0.95:
            (workdir / "cam_lift.csv").write_bytes(motion_table(rng))
            argv += ["--motion", rng.choice([W + "/cam_lift.csv"] * 4 + [seeds["lift_ok"]])
                     if rng.random() > bad else rng.choice([W + "/none.csv", W, "/dev/null"])]
            if follower == "oscillating":      # a table of metres read as degrees of the arm
                argv += rng.choice([["--stroke", "20"], []])
        else:
            argv += ["--law", "cycloidal", "--motion", seeds["lift_ok"]]
        argv += _opts(rng, [("--roller-radius", ["10", "0", "100", "-1", "1e-300"]),
                            ("--offset", ["5", "-5", "1e6", "nan", "1e-300"]),
                            ("--arm", ["50", "0", "1e-9", "inf", "1e50"]),
                            ("--pivot", ["60", "1", "1e6", "-3", "1e-300"]),
                            ("--pressure-limit", ["30", "90", "0", "91", "nan"]),
                            ("--points", ["73", "8", "7", "721", "1000001", "x"]),
                            ("-o", [W + "/profile.csv", W + "/missing/p.csv"]),
                            ("--svg", [W + "/profile.svg", W + "/lift_ok.csv"]),
                            ("--json", [])], 0.08, bad)
    elif kind in ("resonances", "sweep_sensitivity", "crosscheck"):
        (workdir / "mut.mcir").write_text(netlist_input(rng), encoding="utf-8",
                                          errors="surrogatepass")
        drive = motion_drive_line(rng) if rng.random() < 0.5 else "drive V0 T 0 velocity=0.1"
        (workdir / "cam.mcir").write_text(_cam_netlist(rng, drive), encoding="utf-8",
                                          errors="surrogatepass")
        others = [seeds["stb"], W + "/mut.mcir", str(NETLIST_SEEDS[0]), W + "/nope.mcir"]
        f = rng.choice([W + "/cam.mcir", str(CAM_SEED)] if rng.random() > bad else others)
        if kind == "resonances":
            argv = ["resonances", f] + _opts(rng, [("--modes", []), ("--sensitivity", [])], 0.7)
            argv += _opts(rng, [("--omega-max", ["1e4", "0", "nan", "-1", "1e300", "1e-300"]),
                                ("--unit", ["rad/s", "Hz", "rpm", "x"]), ("--json", [])], 0.3, bad)
        elif kind == "sweep_sensitivity":
            names = ["m2", "c2", "eta1", "etaB", "V0", "nope", "", "T", "A", "0", "m1", "k1"]
            argv = ["sweep", f, "--omega-min", _num(rng, "10", 1 - bad),
                    "--omega-max", _num(rng, "1e4", 1 - bad), "--points", _num(rng, "20", 1 - bad)]
            argv += _opts(rng, [("--sensitivity", ["k1"] + names), ("--node", ["A"] + names),
                                ("--element", ["c2"] + names), ("--node", ["T"] + names)],
                          0.6, bad)
            argv += _opts(rng, [("--unit", ["rpm", "rpm", "Hz", "rad/s", "x"]), ("--log", []),
                                ("--method", ["auto", "sp", "nodal"]), ("--adaptive", []),
                                ("-o", [W + "/s.csv", f]), ("--json", [])], 0.3, bad)
        else:
            argv = ["crosscheck", f] + _opts(rng, [("--omega-max", ["1e4", "0", "nan", "1e300"]),
                                                   ("--json", [])], 0.3, bad)
    else:                                                # study_sample
        (workdir / "study").mkdir(exist_ok=True)
        table = motion_table(rng).decode("utf-8", "replace")      # numbers made wrong ...
        header = rng.choice(["eta1,eta3"] * 6 + ["eta1", "eta3,eta1", "eta1,nope", "eta1,eta1", "",
                             "eta1,eta3,eta4", "1,2", "eta1;eta3"])
        body = "\n".join(ln for ln in table.splitlines()[2:2 + rng.randint(0, 4)])
        body = body.replace("360.0", "0.9").replace("0.0", "0.8")  # ... as lever ratios
        (workdir / "study" / "designs.csv").write_text(header + "\n" + body + "\n",
                                                       encoding="utf-8", errors="surrogatepass")
        sample = rng.choice(["designs.csv"] * 20 + ["designs.txt", "missing.csv", "../study",
                                                   "designs.parquet", "/etc/passwd", ""])
        count = rng.choice(["2", "1", "0", "nan", '"x"'])
        spec = (f'netlist = "{seeds["stb"]}"\nanalysis = "resonances"\nresonances = {count}\n'
                f'\n[sample]\nfile = "{sample}"\n')
        if rng.random() < 0.15:
            spec += rng.choice(['method = "random"\n', "n = 3\n", "[grid]\neta1 = [1, 2]\n",
                                "[sample.params]\neta1 = [0.5, 1]\n"])
        if rng.random() < 0.1:
            spec = mutate(rng, spec, TOML_TOKENS, max_ops=2)
        (workdir / "study" / "spec.toml").write_text(spec, encoding="utf-8",
                                                     errors="surrogatepass")
        argv = ["study", W + "/study/spec.toml", "-o", W + "/study/out.csv", "--workers", "1"]
    if rng.random() < 0.08:
        argv.insert(rng.randrange(1, len(argv) + 1), rng.choice(_STRAY))
    return argv


# ---------------------------------------------------------------- every command (the campaign)
#: Netlists for the time-domain commands: clearances, .ic states, periodic drives.
TRANSIENT_SEEDS = [ROOT / "examples" / "msl_backlash.mcir"] + sorted(
    (ROOT / "docs" / "examples").glob("*.mcir"))
TOUCHSTONE_SEED = ROOT / "docs" / "examples" / "measured.s1p"


def all_files(workdir: Path, rng: random.Random | None = None) -> dict[str, list[str]]:
    """Input files by kind for :func:`all_argv`: bundled, mutated and bad ones (written once)."""
    rng = rng or random.Random(0)
    workdir.mkdir(parents=True, exist_ok=True)
    generic = cli_files(workdir, rng)
    bad = [str(workdir / "nope.mcir"), str(workdir), os.devnull]
    pools: dict[str, list[str]] = {"generic": generic}
    pools["netlist"] = [str(p) for p in NETLIST_SEEDS + TRANSIENT_SEEDS] + [
        f for f in generic if f.endswith(".mcir")]
    (workdir / "measured.s1p").write_text(_read(TOUCHSTONE_SEED))
    pools["touchstone"] = [str(workdir / "measured.s1p")]
    for k in range(3):
        p = workdir / f"mut{k}.s1p"
        p.write_bytes(touchstone_input(rng))
        pools["touchstone"].append(str(p))
        q = workdir / f"scene_mut{k}.toml"
        q.write_bytes(toml_file_input(rng, rng.choice(SCENE_SEEDS)))
        pools.setdefault("scene", []).append(str(q))
    pools["scene"] += [str(p) for p in SCENE_SEEDS]
    pools["linkage"] = [str(p) for p in TOML_SEEDS] + [f for f in generic if f.endswith(".toml")]
    (workdir / "drive.csv").write_text("0,0\n0.01,1\n0.02,0\n0.05,-1\n0.1,0\n")
    (workdir / "drive_bad.csv").write_bytes(motion_table(rng))
    pools["drive_csv"] = [str(workdir / "drive.csv"), str(workdir / "drive_bad.csv")]
    for pool in pools.values():
        pool += bad
    return pools


def help_examples(name: str, workdir: Path, pools: dict[str, list[str]]) -> list[list[str]]:
    """The examples of ``mechcirc NAME --help`` as argv lists: bundled inputs found under
    the repository (``measured.s1p`` in the work folder), outputs written into ``workdir``."""
    import shlex

    sub = cli_commands()[name]
    out = []
    for line in (sub.epilog or "").splitlines():
        words = shlex.split(line.split("mechcirc ", 1)[1]) if "mechcirc " + name in line else []
        if not words:
            continue
        argv = []
        for i, w in enumerate(words):
            if i and not w.startswith("-") and "." in w and "/" in w or w.endswith(".s1p"):
                found = ROOT / w
                w = str(found) if found.exists() else pools["touchstone"][0]
            elif i and words[i - 1] in ("-o", "--plot", "--svg", "--export", "--output"):
                w = str(workdir / Path(w).name)
            argv.append(w)
        out.append(argv)
    return out


_STUDY_METHODS = ("grid", "random", "latin-hypercube", "sobol", "file", "[random]")


def study_spec(rng: random.Random, netlist: str, bad: float) -> str:
    """A study spec by grid, random, Latin hypercube, Sobol or a file, with ``bad`` share of
    wrong values; small (≤ 8 points) so that a study runs in a fraction of a second."""
    analysis = rng.choice(["sweep", "resonances"]) if rng.random() > bad else \
        rng.choice(["", "nope", "1", "transient"])
    spec = f'netlist = "{netlist}"\nanalysis = "{analysis}"\n'
    if analysis == "resonances":
        spec += f"resonances = {_num(rng, '2', 1 - bad)}\n"
    else:
        spec += (f"\n[omega]\nmin = {_num(rng, '10', 1 - bad)}\nmax = {_num(rng, '1e4', 1 - bad)}\n"
                 f"points = {_num(rng, '40', 1 - bad)}\nlog = {rng.choice(['true', 'false'])}\n")
    method = rng.choice(_STUDY_METHODS)
    lo, hi = _num(rng, "0.6", 1 - bad), _num(rng, "1.0", 1 - bad)
    if method == "grid":
        spec += (f"\n[grid]\neta1 = [{lo}, {hi}]\n"
                 f"eta2 = {{min = {_num(rng, '1.0', 1 - bad)}, max = 1.5, "
                 f"num = {_num(rng, '3', 1 - bad)}}}\n")
    elif method == "file":
        spec += '\n[sample]\nfile = "designs.csv"\n'
    else:
        table = "random" if method == "[random]" else "sample"
        spec += f"\n[{table}]\n"
        if table == "sample":
            spec += f'method = "{method if rng.random() > bad else rng.choice(["x", "lhs", ""])}"\n'
        spec += (f"n = {_num(rng, rng.choice(['4', '8']), 1 - bad)}\n"
                 f"seed = {_num(rng, '7', 1 - bad)}\n"
                 f"\n[{table}.params]\neta1 = {{min = {lo}, max = {hi}}}\n"
                 f"eta4 = {{min = 0.5, max = 2.0, log = {rng.choice(['true', 'false', '1'])}}}\n")
    if rng.random() < 0.15:
        spec = mutate(rng, spec, TOML_TOKENS, max_ops=2)
    return spec


def all_argv(rng: random.Random, workdir: Path, pools: dict[str, list[str]]) -> list[str]:
    """A command line of any registered sub-command, its positional files drawn (most of the
    time) from the kind that command reads; costly knobs kept small, studies in-process."""
    subs = cli_commands()
    name = rng.choice(sorted(subs))
    W = str(workdir)
    bad = rng.choice([0.0, 0.1, 0.4])
    if name == "study":
        (workdir / "study").mkdir(exist_ok=True)
        (workdir / "study" / "designs.csv").write_text(rng.choice(
            ["eta1,eta4\n0.7,1\n0.9,1.5\n", "eta1\n0.8\n", "eta1,nope\n1,2\n", ""]))
        (workdir / "study" / "spec.toml").write_text(
            study_spec(rng, rng.choice(pools["netlist"][:2] if rng.random() > bad
                                       else pools["netlist"]), bad),
            encoding="utf-8", errors="surrogatepass")
        argv = ["study", W + "/study/spec.toml", "--workers", "1"]
        return argv + _opts(rng, [("-o", [W + "/study/out.csv", W + "/missing/o.csv"]),
                                  ("--resume", []), ("--json", []),
                                  ("--plot", [W + "/study/p.png", W + "/p.xyz"]),
                                  ("--plot-column", ["Q0_abs_max", "resonance_1", "nope"])],
                            0.3, bad)
    if name == "transient":
        f = rng.choice(pools["netlist"])
        drive = rng.choice(["harmonic:300", "harmonic:50Hz", "step", "impulse", "rest",
                            "csv:" + rng.choice(pools["drive_csv"])] if rng.random() > bad else
                           ["harmonic:", "harmonic:nan", "harmonic:1e308", "csv:", "csv:/nope",
                            "square", "", "harmonic:-3"])
        argv = ["transient", f, "--t-end", _num(rng, rng.choice(["0.05", "0.2", "1"]), 1 - bad)]
        return argv + _opts(rng, [("--dt", ["1e-3", "1e-4", "0", "5e-324", "1e300", "nan"]),
                                  ("--waveform", [drive]),
                                  ("--amplitude", ["1", "0", "-1", "1e308", "nan", "1e-320"]),
                                  ("--rtol", ["1e-6", "1e-3", "1e-10", "1e-13", "0.2", "0"]),
                                  ("-o", [W + "/t.csv", W + "/missing/t.csv", f]),
                                  ("--plot", [W + "/t.png", W + "/t.xyz"]),
                                  ("--element", ["eb", "k1", "nope", ""]), ("--json", [])],
                            0.4, bad)
    pool_of = {"scene": "scene", "simulate": "scene", "linkage": "linkage",
               "crosscheck": rng.choice(["scene", "netlist"])}
    pool = pools[pool_of.get(name, "netlist")] if rng.random() > bad else pools["generic"]
    examples = help_examples(name, workdir, pools)
    if examples and rng.random() < 0.5:        # the --help example, some values made wrong
        argv = list(rng.choice(examples))
        for i in range(1, len(argv)):
            if not argv[i].startswith("-") and rng.random() < bad:
                output = argv[i - 1] in ("-o", "--plot", "--svg", "--export")
                argv[i] = str(workdir / rng.choice(_WILD_ARGS)) if output else \
                    rng.choice(_WILD_ARGS + pool[:3])      # never a bundled file as output
        if rng.random() < 0.3:                 # and some more options
            argv += cli_argv(rng, workdir, pool, commands=(name,))[1:]
    else:
        argv = cli_argv(rng, workdir, pool, commands=(name,))
    if "all" in argv and name == "simulate":   # 14 variants on every core: not in-process
        argv[argv.index("all")] = "3"
    if name == "compare" and len(argv) > 2 and rng.random() > bad:
        argv[2] = rng.choice(pools["touchstone"])
    for flag, sane in (("--points", {"scene": "12", "simulate": "36", "reduce": "200",
                                     "frame": "73"}.get(name)),
                       ("--revolutions", "1" if name == "simulate" else None),
                       ("--harmonics", "3" if name == "scene" else None),
                       ("--variant", "3" if name == "simulate" else None)):
        if sane and flag in argv:                # the costly knobs small, unless made wrong
            i = argv.index(flag)
            if i + 1 < len(argv) and rng.random() > bad:
                argv[i + 1] = sane
    if name in ("simulate", "crosscheck") and "--method" in argv:
        i = argv.index("--method")
        if i + 1 < len(argv) and argv[i + 1] in ("DOP853", "RK45", "LSODA") and rng.random() < 0.9:
            argv[i + 1] = "rk4"
    return argv
