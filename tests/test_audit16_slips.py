"""Slips of a new user trying the CLI from the docs (audit16), each answered with
what would be right (exit 2, one line, no traceback, no output file):

* ``transient --waveform harmonic`` (the frequency left out) said "did you mean
  'harmonic'?", the very word given: it now says how the kind is written;
* a massless piece nothing holds (``spring k2 B C``, B and C used by nothing else):
  ``transient`` and ``crosscheck`` said "some nodes ..." without naming B and C;
* ``--t-end 50ms`` and ``--rpm 600rpm`` were "not a number" (and ``transient --rpm``
  took any float), ``frame``/``synth --omega 10Hz`` too: times, shaft speeds and
  every ``--omega`` read the one unit grammar, as docs/units.md promises;
* a scene's crank speed ``omega = "573 rpm"`` ([[cranks]], [simulate]) was refused;
* ``crosscheck NETLIST --theta 20`` (or ``--variant``, ``--drive``; ``--omega-max``
  with a scene or a preset) ran as if the option were not there;
* ``TransientResult.node("Q")`` raised "tuple.index(x): x not in tuple";
* ``load(params={"eta1": "abc"})`` and ``resonances(omega_max="5000")`` raised
  Python's own ValueError/TypeError from deep inside;
* ``sweep --adaptive --points 100000`` silently started from the 20,000-point budget;
* a rotary netlist: ``check --explain`` labelled its values kg and N/m, ``formula``
  said 'K in m/(N·s)' (``check``, ``sweep``, ``forces`` say kg·m², rad/(N·m·s)).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_helpers import assert_user_error
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("wave, form", [("harmonic", "harmonic:OMEGA"),
                                        ("harmonic:", "harmonic:OMEGA"),
                                        ("csv", "csv:PATH"), ("step:2", "step")])
def test_waveform_kind_without_its_argument_says_how_it_is_written(wave, form, capsys,
                                                                    tmp_path):
    out = tmp_path / "t.csv"
    err = assert_user_error(["transient", STB, "--t-end", "0.01", "--waveform", wave,
                             "-o", out], capsys, f"--waveform {wave!r}", f"write it as {form}")
    assert "did you mean" not in err
    assert not out.exists()


FLOATING = """drive V0 T 0 velocity=0.1
mass m1 T A 2
spring k1 A 0 1e5
spring k2 B C 1e4
"""


@pytest.mark.parametrize("cmd", [["transient", "--t-end", "0.1"], ["crosscheck"]])
@pytest.mark.parametrize("piece", ["spring k2 B C 1e4", "mass m2 B C 1"])
def test_massless_floating_nodes_are_named(cmd, piece, capsys, tmp_path):
    """A spring (or a mass: it resists only their relative motion) between two nodes
    nothing else touches: check and sweep warn that it carries no force; the time
    domain refused it without saying which nodes."""
    f = tmp_path / "float.mcir"
    f.write_text(FLOATING.replace("spring k2 B C 1e4", piece))
    err = assert_user_error([cmd[0], f, *cmd[1:]], capsys, "node(s) B, C can move with no mass")
    assert "undetermined" in err


def _json(argv, capsys):
    import json

    from cli_helpers import run

    status, out, err = run([*argv, "--json"], capsys)
    assert status == 0, err
    return json.loads(out)


def test_times_take_units_as_frequencies_do(capsys):
    """``--t-end 50ms`` was refused ("'50ms' is not a number") though the options that
    take a frequency or an angle read the one unit grammar."""
    plain = _json(["transient", STB, "--t-end", "0.05", "--dt", "0.0005"], capsys)
    units = _json(["transient", STB, "--t-end", "50ms", "--dt", "0.5 ms"], capsys)
    assert units["time"] == plain["time"] and len(plain["time"]) == 101
    assert_user_error(["transient", STB, "--t-end", "50kg"], capsys, "argument --t-end",
                      "time (s, ms, min)")


CAM = REPO / "docs" / "examples" / "cam_drive.mcir"


@pytest.mark.parametrize("speed", ["600rpm", "10Hz", "10 Hz"])
def test_shaft_speeds_take_units(speed, capsys):
    """``--rpm 600rpm`` was 'not a number' (periodic) or 'invalid float value'
    (transient, whose --rpm 1e300 then failed on its step instead of the option)."""
    for cmd in (["periodic", CAM], ["transient", CAM, "--t-end", "0.2"]):
        assert _json([*cmd, "--rpm", speed], capsys) == _json([*cmd, "--rpm", "600"], capsys)
    assert_user_error(["transient", CAM, "--t-end", "0.2", "--rpm", "1e300"], capsys,
                      "argument --rpm: must be at most 1e+09 rpm")


HEALD = (REPO / "examples" / "heald_scene.toml").read_text()


def test_scene_shaft_speeds_take_units(capsys, tmp_path):
    """A loom designer writes the crank speed in rpm: ``omega = "573 rpm"`` in
    [[cranks]] and [simulate] were refused ("must be a nonzero number [rad/s]")
    though docs/units.md says a scene value may carry a unit."""
    from mechcirc.errors import NetlistError
    from mechcirc.scene import parse_scene

    text = HEALD.replace("omega = 60.0 ", 'omega = "600 rpm"') + '\n[simulate]\nomega = "10 Hz"\n'
    scene = parse_scene(text, "h.toml")
    assert scene.linkage.cranks[0].omega == scene.simulate.omega == 20 * 3.141592653589793
    bad = HEALD.replace("omega = 60.0 ", 'omega = "600 rmp"')
    with pytest.raises(NetlistError, match="did you mean 'rpm'") as exc:
        parse_scene(bad, "h.toml")
    assert exc.value.line == 60
    f = tmp_path / "h.toml"
    f.write_text(text.replace('"10 Hz"', '"10 kg"'))
    assert_user_error(["scene", f, "--theta", "10"], capsys, "h.toml:", "angular frequency")


@pytest.mark.parametrize("file, extra, needle", [
    (STB, ["--theta", "20"], "--theta applies to a scene or a sley preset"),
    (STB, ["--variant", "2"], "--variant applies to a sley preset"),
    (STB, ["--drive", "both-sides"], "--drive applies to a sley preset"),
    (REPO / "examples" / "heald_scene.toml", ["--theta", "40", "--omega-max", "500"],
     "--omega-max applies to a netlist FILE"),
    (REPO / "examples" / "heald_scene.toml", ["--theta", "40", "--variant", "2"],
     "--variant applies to a sley preset"),
    (None, ["--omega-max", "500"], "--omega-max applies to a netlist FILE")])
def test_crosscheck_refuses_options_its_input_does_not_use(file, extra, needle, capsys):
    """``crosscheck NETLIST --theta 20`` ran at no angle, without a word: an option
    that does not apply to the input is refused, not ignored."""
    assert_user_error(["crosscheck", *([file] if file else []), *extra], capsys, needle,
                      "leave --")


def test_transient_result_names_a_missing_node_or_element():
    """``r.node("Q")`` raised "tuple.index(x): x not in tuple"; a Sweep says which names
    exist and the nearest: so does a TransientResult now."""
    import mechcirc
    from mechcirc.transient import transient

    r = transient(mechcirc.load(STB), 0.001)
    with pytest.raises(KeyError, match=r"no node named 'Mm'; did you mean 'M'\? \(nodes: "):
        r.node("Mm")
    with pytest.raises(KeyError, match=r"no element named 'k44'; did you mean 'k4'\?"):
        r.element_force("k44")
    assert r.node("M")[0].shape == r.element_force("k4").shape == r.time.shape


def test_notebook_values_of_the_wrong_type_are_named():
    """``load(..., params={"eta1": "abc"})`` raised "could not convert string to float"
    from inside the parser, ``resonances(omega_max="5000")`` "'>' not supported"."""
    import mechcirc
    from mechcirc.errors import InputError, NetlistError

    with pytest.raises(NetlistError, match=r"stb_heald.mcir:\d+:\d+: error: parameter "
                                           r"'eta1' set to 'abc' \(expected a finite number"):
        mechcirc.load(STB, params={"eta1": "abc"})
    with pytest.raises(NetlistError, match="parameter 'eta1' set to None"):
        mechcirc.load(STB, params={"eta1": None})
    c = mechcirc.load(STB, params={"eta1": "0.7"})          # a number's text, as float() reads
    assert c.params["eta1"] == 0.7
    with pytest.raises(InputError, match="omega_max must be > 0 rad/s or None, got '5000'"):
        c.resonances(omega_max="5000")
    assert len(c.resonances(omega_max=np.float32(800.0))) == 2


def test_adaptive_starting_grid_over_the_budget_is_refused_not_cut(capsys, tmp_path):
    """``sweep --adaptive --points 100000`` silently started from 20,000 points (the
    budget) and printed 20070 points without a word about the 100,000 asked."""
    out = tmp_path / "K.csv"
    assert_user_error(["sweep", STB, "--omega-min", "10", "--omega-max", "1e4", "--adaptive",
                       "--points", "100000", "-o", out], capsys,
                      "--points 100000 with --adaptive", "budget of 20,000 points")
    assert not out.exists()


ROTARY = "drive V0 T 0 velocity=2rad/s\nmass m1 T A 0.01kg*m^2\nspring k1 A 0 1e3 N*m/rad\n"


def test_rotary_units_in_formula_and_explain(capsys, tmp_path):
    """A rotary drive: ``check`` says kg·m² and N·m/rad, but ``check --explain`` said
    kg and N/m and ``formula`` 'K in m/(N·s)'."""
    from cli_helpers import run

    f = tmp_path / "rot.mcir"
    f.write_text(ROTARY)
    status, out, err = run(["check", f, "--explain"], capsys)
    assert status == 0, err
    assert "0.01 kg·m²" in out and "1000 N·m/rad" in out and " N/m " not in out
    pytest.importorskip("sympy")
    status, out, err = run(["formula", f], capsys)
    assert status == 0 and "K in rad/(N·m·s)" in out and "m/(N·s)" not in out, out + err
