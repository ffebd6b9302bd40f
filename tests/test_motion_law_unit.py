"""A unit after a motion law's name is refused at its column, not silently dropped."""

from __future__ import annotations

import pytest
from cli_helpers import assert_user_error

from mechcirc.errors import NetlistError
from mechcirc.netlist import parse

DRIVE = "drive cam T 0 motion=cycloidal{0} rise=100 dwell=80 return=80{1} stroke=20 mm\n"
REST = "mass m T 0 0.5\nspring k T 0 5e3\n"


@pytest.mark.parametrize("law_unit, ret_unit, key", [
    (" mm", "", "motion=cycloidal"),
    ("", " return_law=harmonic rad", "return_law=harmonic")])
def test_a_unit_after_a_law_name_is_located(law_unit, ret_unit, key):
    text = DRIVE.format(law_unit, ret_unit) + REST
    col = text.index(key) + len(key) + 2                  # the unit's column, 1-based
    with pytest.raises(NetlistError) as info:
        parse(text, source="cam.mcir")
    err = info.value
    assert (err.source, err.line, err.col) == ("cam.mcir", 1, col)
    assert f"{key} is a law's name and takes no unit" in err.message
    assert "stroke=20 mm" in err.expected


def test_the_same_law_without_the_unit_parses():
    c = parse(DRIVE.format("", " return_law=harmonic") + REST)
    assert c.drive.motion.spec.startswith("motion=cycloidal")
    assert c.drive.motion.evaluate(0.0)[0] == 0.0


def test_the_command_line_exits_2_and_writes_nothing(tmp_path, capsys):
    net = tmp_path / "cam.mcir"
    net.write_text(DRIVE.format(" mm", "") + REST, encoding="utf-8")
    out = tmp_path / "out.csv"
    assert_user_error(["periodic", net, "--rpm", "600", "-o", out], capsys,
                      "cam.mcir:1:32:", "takes no unit")
    assert not out.exists()
