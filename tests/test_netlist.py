"""Netlist parsing: the language, and a located error for every kind of bad input."""

import pytest

import mechcirc
from mechcirc.errors import NetlistError, TopologyError

GOOD = """\
# a comment
.param m=2 k={m * 400}   ; later params use earlier ones
mass   m1 a 0 m
spring k1 a 0 k eta={1/2}
damper c1 a b .5
spring 7 b 0 2.
drive  V a 0 velocity=0.1
"""


def test_good_netlist():
    c = mechcirc.parse(GOOD, source="good.mcir")
    assert c.name == "good"
    assert [e.name for e in c.elements] == ["m1", "k1", "c1", "7"]
    assert c.element("k1").value == 800.0 and c.element("k1").eta == 0.5
    assert c.params == {"m": 2.0, "k": 800.0}
    assert c.drive.kind == "velocity" and c.drive.amplitude == 0.1
    assert str(c.tree) == "m1 | k1 | (c1 + 7)"


def test_keywords_case_insensitive_and_integer_nodes_normalised():
    c = mechcirc.parse("MASS m 01 0 1\nDrive V 1 00 velocity=1\n")
    assert c.element("m").n1 == "1" and c.drive.n2 == "0"


def test_integer_names_of_any_length_are_normalised_not_refused():
    # Python's int() refuses more than 4300 digits: a long integer name is still a name
    # (both paths: the plain line and the general one, here made general by eta={1})
    long = "0" + "7" * 5000
    for eta in ("", " eta={1}"):
        c = mechcirc.parse(f"mass {long} {long} 0 1{eta}\nspring k 00{long} 0 2{eta}\n"
                           f"drive V {long} 0 velocity=1\n")
        assert [e.name for e in c.elements] == [long[1:], "k"]
        assert c.elements[0].n1 == c.elements[1].n1 == c.drive.n1 == long[1:]
        assert str(c.tree) == f"{long[1:]} | k"


def _error(text):
    with pytest.raises(NetlistError) as info:
        mechcirc.parse(text, source="bad.mcir")
    return info.value


D = "drive V a 0 velocity=1\n"


@pytest.mark.parametrize("text, line, col, fragment", [
    ("masss m a 0 1\n" + D, 1, 1, "unknown keyword"),
    ("mass m a 0\n" + D, 1, 11, "missing VALUE"),
    ("mass m a\n" + D, 1, 9, "missing N2"),
    ("mass m a 0 1.2.3\n" + D, 1, 12, "malformed number '1.2.3'"),
    ("mass m a 0 1e\n" + D, 1, 12, "malformed number '1e'"),
    ("mass m a 0 2kgx\n" + D, 1, 12, "malformed number '2kgx'"),   # 2kg is 2 kg now
    ("mass m a 0 mm\n" + D, 1, 12, "undefined parameter 'mm'"),
    (".param a={b+1} b=2\nmass m a 0 a\n" + D, 1, 11, "used before it is defined"),
    (".param a={1/0}\n" + D, 1, 12, "division by zero"),
    ("mass m a 0 -2\n" + D, 1, 12, "must be > 0 kg, got -2"),
    ("spring k a 0 0\n" + D, 1, 14, "must be > 0 N/m"),
    ("damper c a 0 {-1}\n" + D, 1, 14, "must be > 0 N·s/m"),
    ("mass m a 0 1 eta=0\n" + D, 1, 18, "eta of 'm' must be > 0"),
    ("mass m a 0 1\nmass m a 0 2\n" + D, 2, 6, "already used on line 1"),
    ("mass m a a 1\n" + D, 1, 10, "both ends"),
    ("mass m a 0 1\n", 0, 0, "no drive"),
    ("mass m a 0 1\n" + D + "drive W a 0 velocity=2\n", 3, 1, "a second drive"),
    ("mass m a 0 1 etta=2\n" + D, 1, 14, "unknown option 'etta'"),
    ("mass m a 0 {1 + 2\n" + D, 1, 12, "'{' is never closed"),
    ("mass m a 0 1 + 2\n" + D, 1, 14, "unexpected '+': mass takes 4 fields"),
    ("mass m a 0 1}\n" + D, 1, 13, "'}' without"),
    ("", 0, 0, "empty"),
    ("# only a comment\n\n", 0, 0, "no statements"),
    ("mass m a 0 1 2\n" + D, 1, 14, "takes 4 fields"),
    ("mass m- a 0 1\n" + D, 1, 6, "not a valid element name"),
    ("drive V a 0\nmass m a 0 1\n", 1, 12, "exactly one of velocity"),
    ("drive V a 0 velocity=1 force=2\nmass m a 0 1\n", 1, 24, "exactly one of velocity"),
    (".param pi=3\n" + D, 1, 8, "built-in"),
    (".param x\n" + D, 1, 8, "not NAME=EXPR"),
    ("lever L a 0 b 0\n" + D, 1, 15, "needs ratio"),
    ("lever L a 0 b 0 ratio=-1\n" + D, 1, 23, "ratio of lever 'L' must be > 0"),
])
def test_bad_input_is_located(text, line, col, fragment):
    err = _error(text)
    assert fragment in err.message
    assert (err.line, err.col) == (line, col)
    assert str(err).startswith(f"bad.mcir:{line}:{col}: error:" if line else "bad.mcir: error:")


def test_drive_terminals_not_connected_names_the_drive_line():
    c = mechcirc.parse("mass m a 0 1\ndrive V b 0 velocity=1\n")
    with pytest.raises(TopologyError, match=r"'b' and '0' \(line 2\) are not connected"):
        c.tree


def test_missing_file(tmp_path):
    with pytest.raises(NetlistError, match="no such file"):
        mechcirc.load(tmp_path / "nope.mcir")


def test_not_utf8(tmp_path):
    path = tmp_path / "latin1.mcir"
    path.write_bytes(b"mass m a 0 1\nmass \xe9 a 0 1\n")
    with pytest.raises(NetlistError) as info:
        mechcirc.load(path)
    assert (info.value.line, info.value.col) == (2, 6)
    assert "not valid UTF-8" in info.value.message


def test_long_line_is_refused_quickly():
    with pytest.raises(NetlistError, match="limit"):
        mechcirc.parse("mass m a 0 " + "1" * 200_000 + "\n" + D)


def test_too_many_statements_are_refused():
    from mechcirc.netlist import MAX_STATEMENTS

    # One line repeated (0.01 s to build against 0.24 s for a million distinct names): the
    # limit is checked on the count of statements before any line is read, so a duplicate
    # name, refused later with another message, would fail the match below if it were not.
    text = "drive V n0 0 velocity=1\n" + "mass m n1 0 1\n" * MAX_STATEMENTS
    with pytest.raises(NetlistError, match=f"the limit is {MAX_STATEMENTS}"):
        mechcirc.parse(text)


# Common slips (issue 17 §5): each names the slip and the fix, at FILE:LINE:COL.
@pytest.mark.parametrize("text, line, col, fragment, fix", [
    ("mass m a 0 1\ndrive V a 0 velocity = 0.1\n", 2, 22, "spaces around '='",
     "velocity=0.1"),
    ("mass m a 0 1 eta = 0.5\n" + D, 1, 18, "spaces around '='", "eta=0.5"),
    ("mass m a 0 1 eta= 0.5\n" + D, 1, 14, "spaces around '='", "NAME=VALUE"),
    (".param k =5\nmass m a 0 1\n" + D, 1, 10, "spaces around '='", "NAME=VALUE"),
    ("damper c a 0 2e\u22126\n" + D, 1, 16, "Unicode minus", "2e-6"),
    ("mass m a 0 1,5\n" + D, 1, 13, "decimal comma", "1.5"),
    ("spring k a 0 3k\n" + D, 1, 14, "malformed number '3k'", "3e3"),
    ("spring k a 0 2meg\n" + D, 1, 14, "malformed number '2meg'", "no SPICE suffixes"),
    ("* a SPICE comment\nmass m a 0 1\n" + D, 1, 1, "'*' does not start a comment", "'#'"),
    ("spring k a 0 3m\n" + D, 1, 15, "unit 'm' is a length", "no SPICE suffixes"),
])
def test_common_slips_name_the_fix(text, line, col, fragment, fix):
    err = _error(text)
    assert fragment in err.message, err.message
    assert fix in (err.expected or ""), err.expected
    assert (err.line, err.col) == (line, col)
    assert str(err).startswith(f"bad.mcir:{line}:{col}: error:")


@pytest.mark.parametrize("method", ["sp", "nodal"])
def test_statement_errors_from_analysis_name_file_line_col(tmp_path, capsys, method):
    from mechcirc.cli import main

    path = tmp_path / "nc.mcir"
    path.write_text("mass m b 0 1\ndrive V a 0 velocity=1\n")
    assert main(["sweep", str(path), "--omega-min", "1", "--omega-max", "2",
                 "--method", method]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{path}:2:1: error: the drive's nodes 'a' and '0'"), err


def test_lever_topology_errors_name_file_line_col(tmp_path, capsys):
    from mechcirc.cli import main

    path = tmp_path / "lv.mcir"
    path.write_text("mass m a 0 1\nlever L a 0 b c ratio=2\nmass m2 b c 1\n"
                    "drive V a 0 velocity=1\n")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{path}:2:1: error: node(s) b, c have no path to the frame"), err


# -- the fast path for plain element lines (issue 14 §2) -----------------------
# Plain lines (KIND NAME N1 N2 NUMBER [UNIT] [eta=NUMBER]) are built directly by
# netlist._Parser.fast_elements; everything else, and every plain line that fails a
# check, goes through the general tokenizer.  The reference here is the general
# path itself, run on the same text with the fast pattern switched off.

import gc  # noqa: E402
import random  # noqa: E402
import re  # noqa: E402
import warnings  # noqa: E402

from mechcirc import netlist as _nl  # noqa: E402


def _outcome(text, *, fast):
    """(elements, drive, expressions, warnings) or the error text, by either path."""
    saved = _nl._FAST, _nl._FAST_DRIVE
    if not fast:
        _nl._FAST = _nl._FAST_DRIVE = re.compile(r"(?!)")   # matches nothing: all general
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            c = mechcirc.parse(text, source="t.mcir", require_drive=False)
        return (c.elements, c.drive, list(_nl.expressions_of(c).items()),
                [str(w.message) for w in caught])
    except NetlistError as exc:
        return str(exc)
    finally:
        _nl._FAST, _nl._FAST_DRIVE = saved


def _alike_on_both_paths(texts, method: str, size=lambda args: 1) -> int:
    """Assert that each of ``texts`` parses alike on the plain-line path and the general
    one; return how much the plain path's ``_Parser.method`` took (``size`` of each
    call's arguments), so a test can show that path was exercised, not bypassed."""
    taken = 0
    original = getattr(_nl._Parser, method)

    def counting(self, *a):
        nonlocal taken
        taken += size(a)
        return original(self, *a)

    for text in texts:
        setattr(_nl._Parser, method, counting)
        try:
            fast = _outcome(text, fast=True)
        finally:
            setattr(_nl._Parser, method, original)
        assert fast == _outcome(text, fast=False), text
    return taken


def test_random_drive_lines_parse_alike_on_both_paths():
    """Drive lines near the plain drive's shape (good and bad, one or two of them, names
    taken or not): same drive, expressions and warnings, or the same error."""
    rng = random.Random(16)
    fields = [["drive", "DRIVE", "Drive", "driv", "drive\x0b"], ["V", "m", "0", "007", "_v", "1a"],
              ["a", "b", "0", "00", "V"], ["0", "a", "b", "1"],
              ["velocity=1", "force=2.5", "velocity=.5e3", "force=0", "velocity=1e999",
               "Velocity=1", "velocity=1 m/s", "force=2kN", "velocity={1}", "velocity= 1",
               "velocity=1 force=2", "velocity=-1", "force=3 N", "velocity=1,5"]]

    def text():
        lines = ["mass m a 0 1", "spring k a b 1e3", "damper c b 0 2"]
        for _ in range(rng.choice([1, 1, 1, 2])):
            lines.insert(rng.randint(0, len(lines)), rng.choice(["", " ", "\t"]) + " ".join(
                rng.choice(f) for f in fields) + rng.choice(["", " # x", ";y", " \t"]))
        return "\n".join(lines) + "\n"

    fast_drives = _alike_on_both_paths((text() for _ in range(600)), "fast_drive")
    assert fast_drives > 50             # the plain drive's path was exercised (75)


@pytest.mark.parametrize("line, message", [
    # Messages as the general path gave them before the fast path existed.
    ("mass m1 a 0 1\nmass m1 a 0 2",
     "t.mcir:3:6: error: element name 'm1' is already used on line 2 (expected a unique name)"),
    ("spring k1 a a 1",
     "t.mcir:2:13: error: both ends of spring 'k1' are node 'a' (expected two different nodes)"),
    ("damper c1 a 0 0",
     "t.mcir:2:15: error: damper 'c1' must be > 0 N·s/m, got 0 (expected a positive value)"),
    ("mass m1 a 0 5 kgg",
     "t.mcir:2:15: error: unknown unit 'kgg'; did you mean 'kg'? (expected one of kg, g, t, N, "
     "kN, m, mm, cm, s, ms, rad, deg, Hz, rpm, min, h and prefixed g/m/s/N/Hz/rad)"),
    ("mass m1 a 0 5 N/m",
     "t.mcir:2:15: error: unit 'N/m' is a stiffness; a mass value needs mass or moment of "
     "inertia (expected mass (kg, g, t) or moment of inertia (kg*m^2))"),
    ("mass m1 a 0 1e999",
     "t.mcir:2:13: error: number 1e999 is too large for float64 (expected a magnitude below "
     "1.8e308)"),
    ("mass m1 a 0 1 eta=0",
     "t.mcir:2:19: error: eta of 'm1' must be > 0, got 0 (expected a positive value)"),
    ("spring k1 a 0 5 m",
     "t.mcir:2:17: error: unit 'm' is a length; a spring value needs stiffness or torsional "
     "rigidity (expected stiffness (N/m, N/mm, kN/m) or torsional rigidity (N*m/rad); note: "
     "mechcirc has no SPICE suffixes, 'm' is read as a unit)"),
    ("mas m1 a 0 1",
     "t.mcir:2:1: error: unknown keyword 'mas'; did you mean 'mass'? (expected one of .param, .ic, mass, spring, "
     "damper, lever, drive)"),
    ("mass 01 a 0 1\nmass 1 a 0 2",
     "t.mcir:3:6: error: element name '1' is already used on line 2 (expected a unique name)"),
    ("mass m1 a 0 1e-300 Mg\nmass m2 a 0 1e-320 mg",
     "t.mcir:3:13: error: mass 'm2' must be > 0 kg, got 0 (expected a positive value)"),
])
def test_plain_lines_that_fail_keep_their_messages(line, message):
    text = f"drive V a 0 velocity=1\n{line}\n"
    assert _outcome(text, fast=True) == message
    assert _outcome(text, fast=False) == message


def test_fast_path_taken_and_same_objects_as_the_general_path():
    text = ("drive V a 0 velocity=1\nmass m1 a 0 5 kg eta=2\n  Spring k1 a b 1e5 N/mm ; c\n"
            "damper c1 b 0 .5 # x\nmass 7 b 0 3.\nspring kt b 0 2 N*m/rad\n")
    calls = []
    original = _nl._Parser.fast_elements
    _nl._Parser.fast_elements = lambda self, run: (calls.extend(r[0] for r in run),
                                                  original(self, run))
    try:
        fast = _outcome(text, fast=True)
    finally:
        _nl._Parser.fast_elements = original
    assert calls == [2, 3, 4, 5, 6]
    general = _outcome(text, fast=False)
    assert fast == general
    elements, _, exprs, caught = fast
    assert elements[1].value == 1e8 and elements[1].col == 3 and elements[0].eta == 2.0
    assert dict(exprs)[("k1", "value")][1] == 1000.0
    assert len(caught) == 1 and caught[0].startswith("t.mcir:6:17: node 'b' gets a rotational")


def test_random_plain_lines_parse_alike_on_both_paths():
    """Random lines near the fast path's shape (good and bad): same result or same error."""
    rng = random.Random(14)
    # (mostly good, sometimes bad) choices for each field
    names = (["m1", "k1", "c1", "a", "b", "0", "00", "7", "_x"], ["1a", "a-b", "n\u00e9", "a=b"])
    numbers = (["1", "2.5", ".5", "5.", "1e3", "1E-3", "3e-320"],
               ["0", "0.0", "1e999", "-1", "+2", "1e", "1,5", "2\u22123", "{3}", "1_0", "5kg",
                "inf", "2*3"])
    units = (["", " kg", " g", " N/m", " N/mm", " N*s/m", " N·s/m", " kg*m^2", " µg", " N/m²",
              " Mg"], [" kgg", " m", " eta", " 1/s", " N/m\t", " kg kg", " {kg}"])
    etas = (["", " eta=0.5", " eta=2", " #eta=0"],
            [" eta=0", " eta=1e999", " eta={2}", " eta= 2", " eta=2 kg", " damping=3",
             " backlash=1e-3 mm", " eta=1 eta=2"])
    kinds = (["mass", "spring", "damper", "MASS", "Damper"], ["lever", "masss", "*mass"])
    tails = (["", " # note", ";x", "\t", "  "], [" extra", "\x0b", " {"])

    def pick(choices):
        good, bad = choices
        return rng.choice(good if rng.random() < 0.92 else bad)

    def text():
        lines = ["drive V a 0 velocity=1"]
        for _ in range(rng.randint(1, 4)):
            lines.append(rng.choice(["", " ", "\t"]) + " ".join(
                [pick(kinds), pick(names), pick(names), pick(names), pick(numbers)])
                + pick(units) + pick(etas) + pick(tails))
        return "\n".join(lines) + "\n"

    fast_lines = _alike_on_both_paths((text() for _ in range(400)), "fast_elements",
                                      lambda args: len(args[0]))
    assert fast_lines > 200           # the fast path was exercised, not bypassed


def test_parse_restores_the_garbage_collector():
    for enabled in (True, False):
        (gc.enable if enabled else gc.disable)()
        try:
            mechcirc.parse("mass m a 0 1\ndrive V a 0 velocity=1\n")
            assert gc.isenabled() is enabled
            with pytest.raises(NetlistError):
                mechcirc.parse("mass m a 0 -1\ndrive V a 0 velocity=1\n")
            assert gc.isenabled() is enabled
        finally:
            gc.enable()


# ------------------------------------------- error lines that neither leak nor sprawl (issue 23 §6)
@pytest.mark.parametrize("text", [
    "root:x:0:0:hunter2:/root:/bin/bash\nspring s a 0 1\n",          # /etc/passwd-like
    "SHELL=/bin/bash\x00TOKEN=hunter2\x00HOME=/root\x00",           # /proc/self/environ-like
    "time,force\n0,hunter2\n",                                        # a CSV
    "hunter2 is the password\n",                                      # prose
])
def test_a_file_that_is_not_a_netlist_is_never_quoted(text):
    err = _error(text)
    assert str(err).startswith("bad.mcir:1:1: error: not a netlist: its first statement "
                               "does not begin with a netlist keyword")
    assert "hunter2" not in str(err) and "root" not in str(err).split("(expected")[0]


@pytest.mark.parametrize("first", ["masss m a 0 1", "sprnig k a 0 1", "Dirve V a 0 velocity=1"])
def test_a_slip_of_a_keyword_on_the_first_line_is_still_named(first):
    word = first.split()[0]
    assert f"unknown keyword {word!r}" in str(_error(first + "\n" + D))


def test_a_long_token_is_quoted_in_part_with_its_length():
    token = "q" * 90_000
    err = str(_error(f"mass m a 0 1\n{token} k a 0 1\n{D}"))
    assert len(err) < 300
    assert err.startswith("bad.mcir:2:1: error: unknown keyword 'qqqq")
    assert "q…" + "q" * 25 + "' (90,000 characters) (expected one of .param" in err
    quoted = err.split("'")[1]
    assert len(quoted) <= 100


def test_parsed_expressions_are_stored_with_the_circuit():
    # the expressions live in the circuit's own data: a renamed copy and a
    # pickled one keep them; a copy with another element has none (no stale formula)
    import dataclasses
    import pickle

    from mechcirc.netlist import expressions_of

    c = mechcirc.parse(".param k0=2e4\ndrive D 1 0 velocity=1\nspring S 1 2 k0*2\nmass M 2 0 1\n")
    expr, factor = expressions_of(c)[("S", "value")]
    assert expr.names() == {"k0"} and factor == 1.0
    renamed = dataclasses.replace(c, name="x")
    assert renamed.expressions[-1] is c.expressions[-1]       # the one stored table
    assert expressions_of(renamed) == expressions_of(c)
    assert expressions_of(pickle.loads(pickle.dumps(renamed)))[("S", "value")][0] == expr
    edited = dataclasses.replace(c, elements=(dataclasses.replace(c.elements[0], value=1.0),
                                              c.elements[1]))
    assert expressions_of(edited) is None
    assert expressions_of(dataclasses.replace(c, params={"k0": 1.0})) is None
    # not compared: the parsed circuit equals the same circuit built in code
    assert c == mechcirc.Circuit(c.elements, c.drive, c.levers, c.name, c.source)
