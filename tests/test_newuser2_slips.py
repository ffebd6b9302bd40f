"""A new user's pass over issue 26's slips and units: what each still got wrong
(each test failed before its fix)."""

import json
import math
import warnings
from pathlib import Path

import pytest
from cli_helpers import assert_user_error, run

import mechcirc
from mechcirc.errors import MechcircError
from mechcirc.study import parse_spec
from mechcirc.transient import transient

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

ROTARY = """# rotary drive with a clearance
drive W p 0 velocity=2 rad/s
mass Jcrank p 0 0.05 kg*m^2
spring kshaft p q 2.0e4 N*m/rad backlash=0.5 deg damping=5 N*m*s/rad
mass Jsley q 0 0.8 kg*m^2
damper cs q 0 1.5 N*m*s/rad
"""


def test_the_backlash_warning_gives_its_unit(tmp_path, capsys):
    """0.5° is π/360 rad; a translational clearance of 0.2 mm is 0.0002 m."""
    f = tmp_path / "rot.mcir"
    f.write_text(ROTARY)
    status, _, err = run(["check", f], capsys)
    assert status == 0
    assert f"spring 'kshaft' has backlash={math.pi / 360:g} rad: the frequency domain" in err
    f.write_text("drive V p 0 velocity=0.1\nmass m p 0 1\n"
                 "spring k p q 1e5 backlash=0.2 mm damping=5\nmass m2 q 0 2\n")
    status, _, err = run(["check", f], capsys)
    assert status == 0 and "spring 'k' has backlash=0.0002 m: the frequency domain" in err


def test_transient_summary_repr_gives_units(tmp_path):
    """A velocity step of 2 rad/s held for 0.2 s turns the driven node 0.4 rad: the summary
    says rad and N·m for a rotary drive."""
    f = tmp_path / "rot.mcir"
    f.write_text(ROTARY.replace(" backlash=0.5 deg damping=5 N*m*s/rad", ""))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = transient(mechcirc.load(f), 0.2, waveform="step")
    text = repr(r)
    assert "(max |x| 0.4 rad)" in text and "N·m)" in text and len(text) < 400


def test_a_spice_deck_is_told_what_else_to_change_at_its_first_error(tmp_path, capsys):
    """The '*' comment of a SPICE deck stops the parse at line 1: the error says there what
    the rest needs too (statements and numbers without suffixes); a deck with a title line
    and a SPICE name says so from its name (the text is not quoted)."""
    deck = tmp_path / "filter.mcir"
    deck.write_text("* SPICE deck\nL1 a b 1m\nC1 b 0 1u\n")
    assert_user_error(["check", deck], capsys, "filter.mcir:1:1:", "'#' or ';'",
                      "without SPICE suffixes (3e3 or 3 kN/m, not 3k)")
    deck = tmp_path / "filter.cir"
    deck.write_text("RC filter title\nL1 a b 1m\nC1 b 0 1u\n.end\n")
    err = assert_user_error(["check", deck], capsys, "filter.cir:1:1: error: not a netlist",
                            "the name is a SPICE deck's", "not 3k")
    assert "RC filter" not in err
    plain = tmp_path / "notes.txt"
    plain.write_text("RC filter title\n")
    err = assert_user_error(["check", plain], capsys, "not a netlist")
    assert "SPICE" not in err


@pytest.mark.parametrize("command", [["check"], ["sweep", "--omega-min", "1", "--omega-max", "10"],
                                     ["resonances"], ["forces", "--omega", "10"],
                                     ["transient", "--t-end", "1"]])
def test_a_scene_file_given_to_a_netlist_command_is_named_as_such(command, capsys):
    """A scene (TOML) to a netlist command stopped at its first 'key = value' with "spaces
    around '='", as if it were a netlist with a typo: it is named a TOML file now, with the
    command that turns a scene into a netlist."""
    scene = EXAMPLES / "heald_scene.toml"
    assert_user_error([command[0], scene, *command[1:]], capsys,
                      "heald_scene.toml: error: a TOML file", "not a netlist",
                      "mechcirc scene ", "--theta DEG -o FILE.mcir")


def test_the_peak_of_an_empty_sweep_is_a_clear_error():
    """c.sweep([]).peak() raised numpy's 'zero-size array to reduction operation'; the cam
    command said 'a oscillating follower'."""
    c = mechcirc.parse("drive V a 0 velocity=0.1\nmass m a 0 2\nspring k a 0 800\n")
    with pytest.raises(ValueError, match="a band: a sweep of two ω or more"):
        c.sweep([]).peak()


def test_an_oscillating_follower_without_a_roller_radius(capsys):
    assert_user_error(["cam", "--law", "cycloidal", "--follower", "oscillating",
                       "--base-radius", "40", "--rise", "120", "--stroke", "20"], capsys,
                      "an oscillating follower needs --roller-radius")


def test_an_unknown_range_key_is_named():
    spec = {"netlist": "netlists/stb_heald.mcir", "omega": {"min": 10, "max": 1e3, "points": 5},
            "sample": {"n": 3, "params": {"eta1": {"min": 1, "maximum": 2}}}}
    with pytest.raises(MechcircError, match=r"must be \{min, max\[, log\]\}: unknown key "
                                            r"'maximum'; did you mean 'max'\?"):
        parse_spec(spec, source="t.toml")


def test_transient_element_panel_suggests_the_nearest(tmp_path, capsys):
    f = tmp_path / "rot.mcir"
    f.write_text(ROTARY)
    png = tmp_path / "t.png"
    assert_user_error(["transient", f, "--t-end", "0.01", "--plot", png, "--element", "kshft"],
                      capsys, "unknown element 'kshft'; did you mean 'kshaft'?")
    assert not png.exists()


def test_scene_cycle_and_theta_show_rpm(tmp_path, capsys):
    """--unit rpm on a scene: n = 60·ω/2π in the table, the shaft speed, the CSV's columns
    (named n_res…) and the --theta list; the values are the rad/s run's, converted here."""
    import numpy as np

    base = ["scene", "examples/heald_scene.toml", "--cycle", "--points", "4", "--harmonics", "1"]
    rad, rpm = tmp_path / "rad.csv", tmp_path / "rpm.csv"
    status, out_rad, _ = run(base + ["-o", rad], capsys)
    assert status == 0
    status, out, _ = run(base + ["-o", rpm, "--unit", "rpm", "--plot", tmp_path / "c.png"],
                         capsys)
    assert status == 0 and "resonances [rpm]" in out and "n_r1" in out
    assert f"shaft Ω = {60 * 60 / (2 * math.pi):g} rpm" in out       # Ω = 60 rad/s
    assert rpm.read_text().splitlines()[0].startswith("theta_deg,n_res1,")
    a = np.loadtxt(rad, delimiter=",", skiprows=1)
    b = np.loadtxt(rpm, delimiter=",", skiprows=1)
    res = [i for i, c in enumerate(rad.read_text().splitlines()[0].split(",")) if "_res" in c]
    assert np.allclose(b[:, res], a[:, res] * 60 / (2 * np.pi), rtol=1e-9)
    assert np.array_equal(np.delete(a, res, axis=1), np.delete(b, res, axis=1))
    status, out, _ = run(["scene", "examples/heald_scene.toml", "--theta", "40", "--json"],
                         capsys)
    first = json.loads(out)["resonances"][0]
    status, out, _ = run(["scene", "examples/heald_scene.toml", "--theta", "40", "--unit",
                          "rpm"], capsys)
    assert status == 0
    assert f"{first['kind']:<14} {first['omega'] * 60 / (2 * math.pi):12.6g} rpm" in out


def test_mode_plot_titles_follow_unit(tmp_path, capsys):
    """k | m with k = 4·10⁴ N/m, m = 1 kg: the undamped anti-resonance at ω = 200 rad/s is
    n = 60·200/2π rpm in the panel's title under --unit rpm (was always rad/s)."""
    from matplotlib.figure import Figure

    from mechcirc.modes import modes
    from mechcirc.plotting import plot_modes

    f = tmp_path / "km.mcir"
    f.write_text("drive V a 0 velocity=1\nspring k a 0 4e4\nmass m a 0 1\n")
    found = modes(mechcirc.load(f))
    fig = plot_modes(found, "km", fig=Figure(), unit="rpm")
    title = fig.axes[0].get_title()
    assert title == f"km: antiresonance n = {200 * 60 / (2 * math.pi):.6g} rpm", title
    assert plot_modes(found, "km", fig=Figure()).axes[0].get_title() == \
        f"km: antiresonance ω = 200 rad/s ({200 / (2 * math.pi):.4g} Hz)"
    status, out, _ = run(["resonances", f, "--unit", "Hz", "--plot", tmp_path / "m.png"], capsys)
    assert status == 0 and (tmp_path / "m.png").exists()


def test_crosscheck_steady_state_header_gives_units(tmp_path, capsys):
    f = tmp_path / "rot.mcir"
    f.write_text(ROTARY.replace(" backlash=0.5 deg damping=5 N*m*s/rad", ""))
    status, out, _ = run(["crosscheck", f], capsys)
    assert status == 0
    assert "(b) |Q0| [N·m] from the sweep vs the harmonic transient started in its periodic " \
        "steady state, at ω [rad/s]" in out


@pytest.mark.parametrize("text, needle", [
    (".param stiff=3\ndrive V a 0 velocity=1\nspring k a 0 {stif}\n",
     "3:15: error: undefined parameter 'stif'; did you mean 'stiff'?"),
    ("drive V a 0 velocity=1\nspring k a 0 {3*sqr(2)}\n",
     "2:17: error: unknown function 'sqr'; did you mean 'sqrt'?"),
    ("drive V a 0 velocity=1\nspring k a 0 3 N/mmm\n",
     "2:18: error: unknown unit 'mmm'; did you mean 'mm'?"),
])
def test_netlist_names_suggest_the_nearest(text, needle, tmp_path, capsys):
    f = tmp_path / "t.mcir"
    f.write_text(text)
    assert_user_error(["check", f], capsys, needle)


def test_sensitivity_name_suggests_the_nearest(tmp_path, capsys):
    f = tmp_path / "t.mcir"
    f.write_text(".param stiff=3e4\ndrive V a 0 velocity=1\nspring k a 0 {stiff}\nmass m a 0 1\n")
    assert_user_error(["sweep", f, "--omega-min", "1", "--omega-max", "2", "--sensitivity",
                       "stif"], capsys, "no element, lever or .param named 'stif'; did you "
                                        "mean 'stiff'? (there are: k, m, stiff)")


def test_a_slice_of_resonances_is_still_a_table():
    """k | m (ωₙ = 200 rad/s) in series with a second k2 | m2 (ωₙ = 100 rad/s): a slice
    shows the same table rows as the whole list; an index is one Resonance."""
    from mechcirc.resonances import Resonance, Resonances

    c = mechcirc.parse("drive V a 0 velocity=1\nspring k a b 4e4\nmass m a b 1\n"
                       "spring k2 b 0 1e4\nmass m2 b 0 1\n")
    found = c.resonances()
    part = found[1:]
    assert isinstance(part, Resonances) and isinstance(found[0], Resonance)
    assert repr(part).splitlines() == [repr(found).splitlines()[0],
                                       *repr(found).splitlines()[2:]]
    assert "<table>" in part._repr_html_()


def test_periodic_prints_its_frequencies_in_unit(capsys):
    """The rocker drive at 300 rpm: Ω is 300 rpm itself, the 7th harmonic 2100 rpm, and the
    resonance 223.607 rad/s is 60·223.607/2π = 2135.29 rpm."""
    argv = ["periodic", "docs/examples/rocker_drive.toml", "--theta", "30", "--rpm", "300"]
    status, out_rad, _ = run(argv, capsys)
    assert status == 0 and "(Ω = 31.4159 rad/s)" in out_rad
    status, out, _ = run(argv + ["--unit", "rpm"], capsys)
    assert status == 0 and "(Ω = 300 rpm)" in out
    w = float(out_rad.split("resonance ωn = ")[1].split(" rad/s")[0])
    assert f"k = 7: kΩ = 2100 rpm, resonance ωn = {w * 60 / (2 * math.pi):.6g} rpm" in out
    assert "kΩ [rpm]" in out


def test_mode_and_sensitivity_tables_align_long_names(tmp_path, capsys):
    """A 21-character element name: every row of the element and sensitivity tables has its
    kind column where its header has it (it was pushed right by the name's overflow)."""
    f = tmp_path / "t.mcir"
    f.write_text("drive W p 0 velocity=2 rad/s\nmass Jcrank p 0 0.05 kg*m^2\n"
                 "spring kshaft_long_name_here p q 2e4 N*m/rad\nmass Jsley q 0 0.8 kg*m^2\n"
                 "damper cs q 0 1.5 N*m*s/rad\n")
    status, out, _ = run(["resonances", f, "--modes", "--sensitivity"], capsys)
    assert status == 0
    lines = out.splitlines()
    tables = [i for i, s in enumerate(lines) if s.startswith(("  element ", "  name "))]
    assert len(tables) >= 4
    for i in tables:
        col = lines[i].index("kind")
        rows = []
        for s in lines[i + 1:]:
            if not s.startswith("  ") or s.startswith(("  to raise", "  name ", "  ...")):
                break
            rows.append(s)
        assert len(rows) == 4
        for s in rows:
            assert s[col - 1] == " " and s[col] != " ", (lines[i], s)
            assert s[2:col].rstrip() in ("Jcrank", "kshaft_long_name_here", "Jsley", "cs")


def test_json_of_sweep_and_transient_names_units(tmp_path, capsys):
    """A consumer of the JSON of a rotary circuit learns that Q0 is in N·m (it could not)."""
    f = tmp_path / "rot.mcir"
    f.write_text(ROTARY.replace(" backlash=0.5 deg damping=5 N*m*s/rad", ""))
    rotary = {"v": "rad/s", "Q": "N·m", "x": "rad", "K": "rad/(N·m·s)"}
    status, out, _ = run(["sweep", f, "--omega-min", "1", "--omega-max", "10", "--points", "3",
                          "--json"], capsys)
    assert status == 0 and json.loads(out)["units"] == {"omega": "rad/s", **rotary}
    status, out, _ = run(["transient", f, "--t-end", "0.01", "--json"], capsys)
    assert status == 0 and json.loads(out)["units"] == {"t": "s", **rotary}
    status, out, _ = run(["sweep", "netlists/stb_heald.mcir", "--omega-min", "1",
                          "--omega-max", "10", "--points", "3", "--json"], capsys)
    assert json.loads(out)["units"] == {"omega": "rad/s", "v": "m/s", "Q": "N", "x": "m",
                                        "K": "m/(N·s)"}
