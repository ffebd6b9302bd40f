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

    text = "drive V n0 0 velocity=1\n" + "".join(
        f"mass m{i} n{i} 0 1\n" for i in range(MAX_STATEMENTS))
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
