"""A value whose conversion to SI overflows float64 is refused at its unit, not read as inf.

``mass m a 0 1e306 Mg`` was a mass of inf kg (``check`` printed "inf kg", exit 0) and
``.param a=1e306 km`` a parameter of inf, reported only where a later line used it."""

import math

import pytest

import mechcirc
from mechcirc.errors import NetlistError, UnitError
from mechcirc.units import parse_quantity

DRIVE = "drive D a 0 velocity=1\n"


@pytest.mark.parametrize("line, col", [
    ("mass m a 0 1e306 Mg\nspring k a 0 1\n", 18),            # the fast path's line
    ("mass m a 0 1e306 Mg eta=2 # c\nspring k a 0 1\n", 18),
    (".param a=1e306 km\nmass m a 0 1\nspring k a 0 1\n", 16),  # unused: still refused
    ("mass m a 0 {2*3} Mg\nspring k a 0 1e305 MN/m\n", 20),
])
def test_overflowing_value_refused_at_its_unit(line, col):
    with pytest.raises(NetlistError, match=r"is inf in SI units \(float64 ends at 1\.8e308\)"
                       ) as err:
        mechcirc.parse(DRIVE + line)
    assert (err.value.line, err.value.col) == (2 + line.startswith("mass m a 0 {") * 1, col)


def test_parse_quantity_refuses_overflow_keeps_the_largest_finite():
    with pytest.raises(UnitError, match="is inf in SI units"):
        parse_quantity("1e306 km")
    with pytest.raises(UnitError, match="is inf in SI units"):
        parse_quantity("1e306 km", "length")
    assert parse_quantity("1e305 km", "length") == pytest.approx(1e308)
    assert math.isinf(parse_quantity("1e400"))       # no unit: the number as written


def test_cli_exit_2_at_the_line(tmp_path, capsys):
    from mechcirc.cli import main
    f = tmp_path / "ovf.mcir"
    f.write_text(DRIVE + "mass m a 0 1e306 Mg\nspring k a 0 1\n")
    assert main(["check", str(f)]) == 2
    err = capsys.readouterr().err
    assert f"ovf.mcir:2:18: error: 1e+306 Mg is inf in SI units" in err
