"""Linkage TOML files (mechcirc.kinematics.linkage): bugs the fuzz harness found, one test each.

Values of the wrong kind are located user errors; crank speeds and locking
positions that made the solver hang are refused quickly.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from mechcirc.errors import GeometryError, NetlistError
from mechcirc.kinematics.linkage import load_linkage, parse_linkage


FNF = """
[points]
O1 = [124.0, -27.0]
A  = [124.0, -2.0]
O2 = [76.0, -22.0]
B  = [76.0, -2.0]
C  = [74.0, 85.0]
E  = [126.0, 85.0]
K  = [100.0, 130.0]
O6 = [30.0, 130.0]
[ground]
points = ["O1", "O2", "O6"]
[links]
crank1   = ["O1", "A"]
crank2   = ["O2", "B"]
coupler3 = ["A", "C"]
link4    = ["C", "E", "K"]
coupler5 = ["B", "E"]
output6  = ["O6", "K"]
[[cranks]]
link = "crank1"
omega = 20.0
[[cranks]]
link = "crank2"
omega = -30.0
"""


def test_fnf_text_is_valid():
    assert parse_linkage(FNF).solve(0.3).theta == 0.3


@pytest.mark.parametrize("table, replacement", [
    ("[points]", "points = 3"), ("[ground]", 'ground = "A"'), ("[links]", "links = [1.0, 2.0]"),
])
def test_table_of_the_wrong_kind_is_a_located_error(table, replacement):
    body = FNF.replace(table + "\n", "[unused_" + table[1:] + "\n")
    with pytest.raises(NetlistError) as err:
        parse_linkage(replacement + "\n" + body, "fnf.toml")
    name = table.strip("[]")
    assert err.value.message.startswith(f"{name!r} must be a {table} table, got ")
    assert (err.value.line, err.value.col) == (1, 1)


@pytest.mark.parametrize("old, new, line, fragment", [
    ('points = ["O1", "O2", "O6"]', 'points = ["O1", "O2", [1.0]]', 12, "in [ground]"),
    ('points = ["O1", "O2", "O6"]', 'points = ["O1", "O2", {a = 1}]', 12, "in [ground]"),
    ('B  = [76.0, -2.0]', 'B  = [1' + '0' * 400 + ', -2.0]', 6, "must be [x, y]"),
    ('omega = 20.0', 'omega = 1' + '0' * 400, 22, "omega must be a nonzero number"),
    ('link = "crank1"', 'link = ["crank1"]', 21, "unknown link"),
])
def test_linkage_value_of_the_wrong_kind_is_a_located_error(old, new, line, fragment):
    text = FNF.replace(old, new, 1)
    assert text != FNF
    with pytest.raises(NetlistError) as err:
        parse_linkage(text, "fnf.toml")
    assert fragment in err.value.message
    assert len(err.value.message) < 200           # huge values are cut short
    assert err.value.line == line and err.value.col >= 1


def test_cranks_must_be_tables():
    text = FNF.split("[[cranks]]")[0].replace("[points]", "cranks = [1, 2]\n[points]")
    with pytest.raises(NetlistError) as err:
        parse_linkage(text, "fnf.toml")
    assert err.value.message == "'cranks' must be a [[cranks]] table, got [1, 2]"
    assert err.value.line == 2


def test_integer_beyond_python_digit_limit_is_a_located_error():
    text = FNF.replace("omega = 20.0", "omega = " + "1" * 5000)
    with pytest.raises(NetlistError, match="thousands of digits") as err:
        parse_linkage(text)
    assert (err.value.line, err.value.col) == (22, 9)


def test_linkage_file_not_utf8_is_located(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_bytes(b'name = "x"\nunits = "\xff"\n')
    with pytest.raises(NetlistError, match="not valid UTF-8") as err:
        load_linkage(path)
    assert (err.value.line, err.value.col) == (2, 10)


def test_tiny_first_crank_speed_is_refused_quickly_not_a_hang():
    lk = parse_linkage(FNF.replace("omega = 20.0", "omega = 1e-300"))
    with pytest.raises(GeometryError, match="continuation steps.*the limit is 100000"):
        lk.solve(0.3)


def test_locking_linkage_is_reported_quickly():
    """Long-run seed 1009246 (O1 moved to y = 327): 3.7 s to find the lock, now well under 2 s.

    Newton gives up as soon as its residual grows, instead of iterating 30
    times at every halving of the step; the lock angle is unchanged.  CPU time,
    after the kernels are compiled (a fresh environment's first solve compiles).
    """
    from bounds import cpu_seconds_below

    parse_linkage(FNF).solve(0.3)
    lk = parse_linkage(FNF.replace("O1 = [124.0, -27.0]", "O1 = [124.0, 327.0]"))
    with cpu_seconds_below(2.0), \
            pytest.raises(GeometryError, match=r"locks near θ = 14\.4171°"):
        lk.solve(0.3)


QUICK = (Path(__file__).resolve().parents[2] / "examples" / "quick_return.toml").read_text(
    encoding="utf-8")


@pytest.mark.parametrize("old, new, needle, fragment", [
    ('crank  = ["O2", "A"]', 'crank  = ["O2", "A", "A"]', 'crank  = ["O2", "A", "A"]',
     "link 'crank' lists a point twice"),
    ('ram    = ["D"]', 'ram    = ["D"]\nground = ["O2", "A"]', 'ground = ["O2", "A"]',
     "'ground' is reserved for the frame"),
    ('G2 = [100.0, 125.0]', 'G2 = [100.0, 125.0]\nH = [1.0, 2.0]', "H = [1.0, 2.0]",
     "point 'H' belongs to no link and is not a ground pivot"),
    ('link = "crank"\nomega', 'link = "link"\nomega', 'link = "link"',
     "crank 'link' needs exactly one ground pivot among its points (found none); name it with "
     'pivot = "…"'),
    ("omega = 10.0", 'omega = 10.0\n[[cranks]]\nlink = "crank"  # again\nomega = 5.0',
     'link = "crank"  # again', "link 'crank' is driven twice"),
    ("[[cranks]]", '[[sliders]]\nlink = "ram"  # again\nguide = "ground"\nline = ["G1", "G2"]\n'
     "[[cranks]]", 'link = "ram"  # again', "link 'ram' slides twice"),
    ("G2 = [100.0, 125.0]", "G2 = [-100.0, 125.0]", 'line = ["G1", "G2"]',
     "slider 'ram': the line's points 'G1' and 'G2' coincide"),
    ("D  = [59.791303715507, 125.0]    # |BD| = 60", "D  = [59.791303715507, 125.0]\n"
     "E  = [59.791303715507, 125.0]", 'linkx = ["D", "E"]',
     "link 'linkx' has all its points at the same place [59.791303715507, 125.0] (expected "
     "points at two places)"),
])
def test_bad_linkage_tables_exit_2_at_their_line(old, new, needle, fragment, tmp_path, capsys):
    """kinematics/linkage's refusals (run by no test) through `mechcirc linkage`: exit 2,
    one line at file:line:col of the offending key (found here), what is wrong and what
    would be right.  A link with all its points at one place was a GeometryError naming
    only the file; it is now located at the link."""
    from cli_helpers import assert_user_error

    text = QUICK.replace(old, new, 1)
    if "linkx" in needle:
        text = text.replace('link   = ["B", "D"]', 'link   = ["B", "D"]\nlinkx = ["D", "E"]')
    assert text != QUICK
    line = next(n for n, ln in enumerate(text.splitlines(), 1) if needle in ln)
    f = tmp_path / "l.toml"
    f.write_text(text, encoding="utf-8")
    assert_user_error(["linkage", f], capsys, f"l.toml:{line}:", ": error: ", fragment)


def test_a_key_of_an_inline_table_and_a_missing_key_are_located():
    # Each was placed nowhere (file: error) before the readers placed errors as the
    # study reader does (mechcirc.sources.locate_path).
    text = 'ground = { points = ["O1", "O2", "O9"] }\n' + \
        FNF.replace('[ground]\npoints = ["O1", "O2", "O6"]\n', '')
    with pytest.raises(NetlistError, match="unknown point 'O9' in") as err:
        parse_linkage(text, "fnf.toml")
    assert (err.value.line, err.value.col) == (1, 12)           # at points
    with pytest.raises(NetlistError, match="unknown point 'O9' in") as err:
        parse_linkage(text.replace('ground = { points =', 'ground.points =').replace(' }', '', 1),
                      "fnf.toml")
    assert (err.value.line, err.value.col) == (1, 8)            # the dotted key's points
    text = FNF.replace('[[cranks]]\nlink = "crank2"\n', '[[cranks]]\n')
    with pytest.raises(NetlistError, match=r"\[\[cranks\]\] #2 has no link") as err:
        parse_linkage(text, "fnf.toml")
    assert (err.value.line, err.value.col) == (23, 3)           # the second [[cranks]]
    assert text.splitlines()[22] == "[[cranks]]"
