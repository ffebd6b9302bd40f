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
    with pytest.warns(mechcirc.errors.UnitMixWarning):     # kt on node a with m: a slip
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
    ("mass m a 0 1 eta=2 mm\n" + D, 1, 20, "an eta value needs a ratio"),
    ("mass m a 0 1\ndrive V a 0 velocity=1 N\n", 2, 24, "is a force; a velocity value"),
    ("mass m a 0 1\ndrive V a 0 force=1 m/s\n", 2, 21, "is a velocity; a force value"),
    ("mass m a 0 2kgs\n" + D, 1, 12, "malformed number '2kgs'"),
    ("mass m a 0 1 2\n" + D, 1, 14, "takes 4 fields"),
])
def test_unit_errors_are_located(text, line, col, fragment):
    err = _error(text)
    assert fragment in err.message, err.message
    assert (err.line, err.col) == (line, col)


def test_glued_unit_gets_advice():
    # A plain number glued to its unit is now read as pint reads it (issue 17 §1);
    # inside an expression the unit still needs the space.
    assert mechcirc.parse("mass m a 0 2kg\n" + D).element("m").value == 2.0
    err = _error("mass m a 0 2*3kg\n" + D)
    assert err.expected == "a space between the number and its unit: '3 kg'"
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


@pytest.mark.parametrize("text", ["50 kg", "fast", "50Hz3", ""])  # kHz is now accepted (issue 17)
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


# ---------------------------------------------------------------------------
# One grammar on every surface (issue 17 §1): pint is the independent reference.

from mechcirc.units import parse_quantity, UnitError as _UE   # noqa: E402

QUANTITIES = [
    # (text, role, pint expression of the same quantity, SI unit in pint)
    ("500g", "mass", "500 g", "kg"), ("500 g", "mass", "500 g", "kg"),
    ("2 kN/mm", "spring", "2 kN/mm", "N/m"), ("2kN/mm", "spring", "2 kN/mm", "N/m"),
    ("1.5e3 N/m", "spring", "1.5e3 N/m", "N/m"), ("3 mg", "mass", "3 mg", "kg"),
    ("250 µm", "length", "250 um", "m"), ("12 mrad", "angle", "12 mrad", "rad"),
    ("30 deg", "angle", "30 deg", "rad"), ("5 ms", "time", "5 ms", "s"),
    ("2 min", "time", "2 min", "s"), ("0.4 g*cm^2", "mass", "0.4 g*cm**2", "kg*m**2"),
    ("3000rpm", "omega", "3000 rpm", "rad/s"), ("3000 rpm", "omega", "3000 rpm", "rad/s"),
    # Hz counts revolutions (ω = 2πf): compared with pint's revolution/second, since
    # pint's own Hz -> rad/s gives 1 rad/s per Hz (documented in docs/units.md)
    ("50Hz", "omega", "50 revolution/s", "rad/s"), ("50 Hz", "omega", "50 revolution/s", "rad/s"),
    ("1.2 kHz", "omega", "1200 revolution/s", "rad/s"), ("314 rad/s", "omega", "314 rad/s", "rad/s"),
    ("0.1 m/s", "velocity", "0.1 m/s", "m/s"), ("100mm/s", "velocity", "100 mm/s", "m/s"),
    ("2 kN", "force", "2 kN", "N"), ("3 N*m", "force", "3 N*m", "N*m"),
]


@pytest.mark.parametrize("text, role, pint_text, si", QUANTITIES)
def test_quantities_agree_with_pint(ureg, text, role, pint_text, si):
    expected = ureg.Quantity(pint_text).to(si).magnitude
    assert parse_quantity(text, role) == pytest.approx(expected, rel=1e-14)


def test_glued_and_spaced_netlist_values_are_the_same():
    glued = mechcirc.parse(".param v=100mm/s\nmass m a 0 500g\nspring k a 0 5kN/m eta=0.5\n"
                           "damper c a 0 30N*s/m\ndrive V a 0 velocity=v\n")
    spaced = mechcirc.parse(".param v=100 mm/s\nmass m a 0 500 g\nspring k a 0 5 kN/m eta=0.5\n"
                            "damper c a 0 30 N*s/m\ndrive V a 0 velocity=v\n")
    assert glued.elements == spaced.elements
    assert glued.drive.amplitude == spaced.drive.amplitude == pytest.approx(0.1, rel=1e-15)
    assert glued.element("m").value == 0.5 and glued.element("k").value == 5000.0


def test_glued_drive_value():
    c = mechcirc.parse("mass m a 0 1\ndrive F a 0 force=2kN\n")
    assert c.drive.amplitude == 2000.0


@pytest.mark.parametrize("text", ["5 kg", "abc", "50 Hzz", "", "1 2 Hz"])
def test_frequency_errors_say_what_is_accepted(text):
    with pytest.raises(_UE) as info:
        parse_quantity(text, "omega")
    assert info.value.expected


def test_mixed_translational_and_rotational_units_on_a_node_warn():
    with pytest.warns(mechcirc.errors.UnitMixWarning, match="node 'a'.*kg\\*m\\^2.*'kg'"):
        mechcirc.parse("mass m a 0 2 kg\nmass J a 0 0.1 kg*m^2\ndrive V a 0 velocity=1\n")
    with pytest.warns(mechcirc.errors.UnitMixWarning, match="node 'b'"):
        mechcirc.parse("spring k a b 5 N/m\nspring kt b 0 3 N*m/rad\nmass m a 0 1\n"
                       "drive V a 0 velocity=1\n")


@pytest.mark.parametrize("text,match", [
    ("drive W a 0 velocity=0.1 m/s\nmass J a 0 0.1 kg*m^2\n", "'m/s' of 'W'.*'kg\\*m\\^2'"),
    ("drive W a 0 force=2 N*m\nmass m a 0 3 kg\n", "'N\\*m' of 'W'.*'kg'"),
    ("drive W a 0 motion=harmonic rise=180 return=180 stroke=20 deg\nmass m a 0 3 kg\n",
     "'deg' of 'W'.*'kg'"),
])
def test_a_drive_unit_against_its_nodes_elements_warns(text, match):
    """The drive's own unit counts: a translational drive on an inertia, or a rotary one on
    a mass, was relabelled silently (the inertia listed in kg, the mass in kg·m²)."""
    with pytest.warns(mechcirc.errors.UnitMixWarning, match=match):
        mechcirc.parse(text)


def test_a_drive_unit_that_agrees_does_not_warn(recwarn):
    mechcirc.parse("drive W a 0 velocity=2 rad/s\nmass J a 0 0.1 kg*m^2\n")
    mechcirc.parse("drive V a 0 force=2 N\nmass m a 0 3 kg\n")
    assert not [w for w in recwarn.list if w.category is mechcirc.errors.UnitMixWarning]


def test_separate_nodes_do_not_warn(recwarn):
    mechcirc.parse("mass m a 0 2 kg\nspring k a b 5 N/m\nmass J c 0 0.1 kg*m^2\n"
                   "spring kt c b 3 N*m/rad\ndrive V a 0 velocity=1\n")
    # b joins a translational spring and a rotational one: that is a warning; a, c are clean
    assert all("node 'a'" not in str(w.message) and "node 'c'" not in str(w.message)
               for w in recwarn.list)


# The command line reads the same grammar, glued or spaced.
@pytest.mark.parametrize("w1, w2", [("1Hz", "50Hz"), ("1 Hz", "50 Hz"), ("6.283185307179586",
                                                                        "0.05 kHz"),
                                    ("60 rpm", "3000rpm")])
def test_cli_frequencies_glued_or_spaced(capsys, w1, w2):
    from mechcirc.cli import main

    argv = ["sweep", "netlists/stb_heald.mcir", "--points", "3", "--json"]
    argv[2:2] = ["--omega-min", *w1.split(" ", 1)] if " " in w1 else ["--omega-min", w1]
    argv[2:2] = ["--omega-max", *w2.split(" ", 1)] if " " in w2 else ["--omega-max", w2]
    assert main(argv) == 0
    import json
    doc = json.loads(capsys.readouterr().out)
    assert doc["omega"][0] == pytest.approx(2 * math.pi, rel=1e-12)
    assert doc["omega"][-1] == pytest.approx(100 * math.pi, rel=1e-12)


def test_cli_band_and_set_take_units(capsys):
    from mechcirc import parse_band

    assert parse_band("1Hz:50Hz") == pytest.approx((2 * math.pi, 100 * math.pi), rel=1e-15)
    assert parse_band("10:2000") == (10.0, 2000.0)
    from mechcirc.cli.sley_commands import _overrides
    import argparse
    ns = argparse.Namespace(alpha=40.0, beat_sign=-1, set=["omega=3000rpm", "clearance=0.1 deg"])
    out = _overrides(ns)
    assert out["omega"] == pytest.approx(100 * math.pi, rel=1e-15)
    assert out["clearance"] == pytest.approx(math.pi / 1800, rel=1e-15)   # an angle [rad]


def test_cli_spaced_unit_is_not_taken_from_a_file_name():
    from mechcirc.cli._common import join_spaced_quantities as j

    assert j(["--omega-max", "50", "Hz"]) == ["--omega-max", "50 Hz"]
    assert j(["--points", "5", "netlists/stb_heald.mcir"]) == ["--points", "5",
                                                               "netlists/stb_heald.mcir"]
    assert j(["sweep", "50", "Hz"]) == ["sweep", "50", "Hz"]


def test_scene_toml_values_take_units(tmp_path):
    from mechcirc.scene.files import load_scene

    text = open("examples/heald_scene.toml").read()
    assert "\nstiffness = 2.0e6\n" in text
    p = tmp_path / "s.toml"
    p.write_text(text.replace("\nstiffness = 2.0e6\n", '\nstiffness = "2 kN/mm"\n', 1))
    assert load_scene(p).elastic[0].stiffness == 2.0e6
    p.write_text(text.replace("\nstiffness = 2.0e6\n", '\nstiffness = "2 kg"\n', 1))
    with pytest.raises(NetlistError) as info:
        load_scene(p)
    assert "an axial spring value needs stiffness" in info.value.message and info.value.line == 65
    # a unit of the other reading, the wrong kind for this element (session 28: read as
    # 2e6 N/m and 2.5 kg, silently): a torsional rigidity on an axial rod, an inertia at a
    # point; and each reading where it belongs
    for old, new, needle in (("\nstiffness = 2.0e6\n", '\nstiffness = "2e6 N*m/rad"\n',
                              "an axial spring value needs stiffness"),):
        p.write_text(text.replace(old, new, 1))
        with pytest.raises(NetlistError, match=needle):
            load_scene(p)
    sc = "examples/slider_crank_scene.toml"
    text = open(sc).read()
    assert "\nmass = 2.5\n" in text
    p.write_text(text.replace("\nmass = 2.5\n", '\nmass = "2.5 kg*m^2"\n', 1))
    with pytest.raises(NetlistError, match="a point mass value needs mass"):
        load_scene(p)
    p.write_text(text.replace("\nmass = 2.5\n", '\nmass = "2500 g"\n', 1))
    assert [m.value for m in load_scene(p).masses if m.kind == "mass"] == [2.5]


def test_study_toml_frequencies_take_the_same_grammar():
    import tomllib

    from mechcirc.study import parse_spec

    root = __import__("pathlib").Path(__file__).resolve().parents[1]
    doc = tomllib.loads((root / "examples" / "study_stb.toml").read_text())
    for text, expected in (("1500Hz", 3000 * math.pi), ("1.5 kHz", 3000 * math.pi),
                           ("90000 rpm", 3000 * math.pi), ("9424.777960769379", 9424.777960769379)):
        doc["omega"]["max"] = text
        spec = parse_spec(doc, source="s.toml", base=root / "examples")
        assert spec.omega[1] == pytest.approx(expected, rel=1e-12), text   # (min, max, n, log)


@pytest.mark.parametrize("ic, match", [
    (".ic a x=10 mm", "'mm' of '.ic a'.*'kg\\*m\\^2'"),
    (".ic a v=2 m/s", "'m/s' of '.ic a'.*'kg\\*m\\^2'"),
])
def test_an_initial_state_in_the_other_reading_warns(ic, match, recwarn):
    """.ic a x=10 mm on a node of inertias and torsion springs was 0.01 rad, silently (the
    new-user pass); as an element's or a drive's unit, it now warns.  An angle there, or
    a length on a node of kg and N/m, does not."""
    rotary = "mass J a 0 2 kg*m^2\nspring kt a 0 800 N*m/rad\n"
    with pytest.warns(mechcirc.errors.UnitMixWarning, match=match):
        mechcirc.parse(rotary + ic + "\n", require_drive=False)
    mechcirc.parse(rotary + ".ic a x=10 deg v=1 rad/s\n", require_drive=False)
    mechcirc.parse("mass m a 0 2 kg\nspring k a 0 800 N/m\n.ic a x=10 mm\n", require_drive=False)
    assert not [w for w in recwarn.list if w.category is mechcirc.errors.UnitMixWarning]
