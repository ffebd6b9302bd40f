"""Units in netlists and on the command line: the table, conversions, located errors."""

import math

import pytest

import mechcirc
from mechcirc.errors import NetlistError
from mechcirc.units import ATOMS, UnitError, parse_omega, parse_unit

D = "drive V a 0 velocity=1\n"

# (unit text, pint spelling, SI unit in pint)
TABLE = [
    ("kg", "kg", "kg"), ("g", "g", "kg"), ("t", "metric_ton", "kg"),
    ("N/m", "N/m", "N/m"), ("N/mm", "N/mm", "N/m"), ("kN/m", "kN/m", "N/m"),
    ("N*s/m", "N*s/m", "N*s/m"), ("kg*m^2", "kg*m**2", "kg*m**2"),
    ("kg·m²", "kg*m**2", "kg*m**2"), ("g*cm^2", "g*cm**2", "kg*m**2"),
    ("N*m/rad", "N*m/rad", "N*m/rad"), ("N*m/deg", "N*m/deg", "N*m/rad"),
    ("m", "m", "m"), ("mm", "mm", "m"), ("rad", "rad", "rad"), ("deg", "deg", "rad"),
    ("mm/s", "mm/s", "m/s"), ("kN", "kN", "N"), ("N*m*s/rad", "N*m*s/rad", "N*m*s/rad"),
]


@pytest.fixture(scope="module")
def ureg():
    pint = pytest.importorskip("pint")
    return pint.UnitRegistry()


@pytest.mark.parametrize("text, pint_text, si", TABLE)
def test_factors_agree_with_pint(ureg, text, pint_text, si):
    expected = ureg.Quantity(1.0, pint_text).to(si).magnitude
    assert parse_unit(text).factor == pytest.approx(expected, rel=1e-15)


def test_rational_factors_are_exact():
    assert parse_unit("kg*mm^2").factor == 1e-6
    assert parse_unit("N/mm").factor == 1000.0
    assert parse_unit("g").factor == 0.001


def test_netlist_with_units_equals_the_si_netlist():
    si = mechcirc.parse(".param L=0.12 a={pi/6}\nmass m a 0 0.25\nspring k a 0 5000\n"
                        "damper c a 0 30\nspring kt a b 12\nmass J b 0 0.00004\n"
                        "drive V a 0 velocity=0.1\n")
    units = mechcirc.parse(".param L=120 mm a=30 deg\nmass m a 0 250 g\nspring k a 0 5 N/mm\n"
                           "damper c a 0 30 N*s/m\nspring kt a b 12 N*m/rad\n"
                           "mass J b 0 400 g*cm^2\ndrive V a 0 velocity=100 mm/s\n")
    assert units.elements[:4] == si.elements[:4]
    # 400 g·cm² = 0.4 kg · 1e-4 m²; 1e-7 is not a binary fraction, so within rounding
    assert units.element("J").value == pytest.approx(0.00004, rel=1e-15)
    assert units.drive.amplitude == si.drive.amplitude
    assert units.params["L"] == si.params["L"]
    assert units.params["a"] == pytest.approx(math.pi / 6, rel=1e-15)


def _error(text):
    with pytest.raises(NetlistError) as info:
        mechcirc.parse(text, source="u.mcir")
    return info.value


@pytest.mark.parametrize("text, line, col, fragment", [
    ("spring k a 0 5 kg\n" + D, 1, 16, "unit 'kg' is a mass; a spring value needs stiffness"),
    ("mass m a 0 5 N/m\n" + D, 1, 14, "is a stiffness; a mass value needs"),
    ("damper c a 0 5 N/m\n" + D, 1, 16, "a damper value needs damping"),
    ("mass m a 0 5 kgs\n" + D, 1, 14, "unknown unit 'kgs'"),
    ("spring k a 0 5 N/mmm\n" + D, 1, 18, "unknown unit 'mmm'"),
    ("spring k a 0 5 N//m\n" + D, 1, 18, "unexpected '/'"),
    ("mass m a 0 1 eta=2 mm\n" + D, 1, 20, "a eta value needs a ratio"),
    ("mass m a 0 1\ndrive V a 0 velocity=1 N\n", 2, 24, "is a force; a velocity value"),
    ("mass m a 0 1\ndrive V a 0 force=1 m/s\n", 2, 21, "is a velocity; a force value"),
    ("mass m a 0 2kg\n" + D, 1, 12, "malformed number '2kg'"),
    ("mass m a 0 1 2\n" + D, 1, 14, "takes 4 fields"),
])
def test_unit_errors_are_located(text, line, col, fragment):
    err = _error(text)
    assert fragment in err.message, err.message
    assert (err.line, err.col) == (line, col)


def test_glued_unit_gets_advice():
    err = _error("mass m a 0 2kg\n" + D)
    assert err.expected == "a space between the number and its unit: '2 kg'"
    err = _error("mass m a 0 1.2.3\n" + D)
    assert "a number such as" in err.expected


def test_a_negative_value_with_unit_reports_the_si_value():
    err = _error("mass m a 0 -250 g\n" + D)
    assert "must be > 0 kg, got -0.25" in err.message and err.col == 12


def test_parse_unit_offsets():
    with pytest.raises(UnitError) as info:
        parse_unit("kg*q")
    assert info.value.offset == 3
    assert set(ATOMS) >= {"kg", "g", "t", "N", "kN", "m", "mm", "rad", "deg"}


@pytest.mark.parametrize("text, omega", [
    ("314", 314.0), ("50Hz", 100 * math.pi), ("50 hz", 100 * math.pi),
    ("3000rpm", 100 * math.pi), ("1e3rad/s", 1000.0), ("0", 0.0),
])
def test_parse_omega(text, omega):
    assert parse_omega(text) == pytest.approx(omega, rel=1e-15)


@pytest.mark.parametrize("text", ["50 kHz", "fast", "50Hz3", ""])
def test_parse_omega_rejects(text):
    with pytest.raises(ValueError, match="rad/s"):
        parse_omega(text)


def test_param_overrides_for_studies():
    text = ".param a=2 b={a*3}\nmass m x 0 b\ndrive V x 0 velocity=1\n"
    c = mechcirc.parse(text, params={"a": 5.0})
    assert c.params == {"a": 5.0, "b": 15.0} and c.element("m").value == 15.0
    with pytest.raises(NetlistError, match="no .param named 'z'"):
        mechcirc.parse(text, params={"z": 1.0})


def test_override_of_a_parameter_with_a_unit_is_si():
    text = ".param L=120 mm k=5\nspring s a 0 {k*L} N/mm\ndrive V a 0 velocity=1\n"
    assert mechcirc.parse(text).element("s").value == pytest.approx(600.0, rel=1e-15)
    c = mechcirc.parse(text, params={"L": 0.2})
    assert c.params["L"] == 0.2 and c.element("s").value == pytest.approx(1000.0, rel=1e-15)
