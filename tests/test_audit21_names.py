"""Names and arguments a user meets (issue 26): a name that is not there is an
UnknownNameError (a MechcircError and a KeyError) saying the nearest ("did you mean") and
those there are; a number argument given as text or None is a named error saying which
argument and what is right, never numpy's "could not convert string to float"."""

import re
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc.errors import (GeometryError, InputError, MechcircError, NetlistError,
                             ParameterError, UnknownNameError)
from mechcirc.kinematics import FourBar, cam_profile, load_linkage, parse_linkage
from mechcirc.modes import sweep_sensitivity
from mechcirc.motion_laws import cam_cycle
from mechcirc.scene import parse_scene
from mechcirc.sley import eigenfrequencies, linearise, preset, to_circuit, to_netlist
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]
QUICK = REPO / "examples" / "quick_return.toml"
SLIDER = REPO / "examples" / "slider_crank_scene.toml"
STB_ELEMENTS = "k0, k4, k5, m1, m10, m11, m12, m2, m3, m4, m5, m6, m7, m8, m9"


@pytest.fixture(scope="module")
def stb():
    return mechcirc.load(STB)


def raises(error, message, call):
    """``call()`` raises ``error`` whose whole text is ``message``."""
    with pytest.raises(error) as info:
        call()
    assert str(info.value) == message
    return info.value


# ------------------------------------------------------------------ names
def test_circuit_element_names_the_nearest_and_the_elements(stb):
    # on main: KeyError "no element named 'k44'" (no hint, printed in quotes)
    exc = raises(UnknownNameError, f"no element named 'k44'; did you mean 'k4'? (elements: "
                                   f"{STB_ELEMENTS})", lambda: stb.element("k44"))
    assert isinstance(exc, KeyError) and isinstance(exc, MechcircError)
    assert stb.element("k4").name == "k4"


def test_sensitivity_of_a_parameter_not_computed_names_the_nearest(stb):
    # on main: KeyError "no sensitivity to 'k44' computed; computed: k0, ..." (no hint)
    s = sweep_sensitivity(stb, np.array([100.0, 200.0]))
    with pytest.raises(UnknownNameError, match=re.escape(
            "no parameter named 'k44' among the sensitivities computed; did you mean 'k4'? "
            "(parameters: eta1, eta2,")) as info:
        s.relative("k44")
    assert str(info.value).endswith(", … (21 in all))")


def test_a_long_list_of_names_says_how_many(stb):
    # on main: the first 20 names, and no word of the others
    r = stb.sweep([100.0])
    names = [f"n{i:02d}" for i in range(25)]
    from mechcirc.sources import name_index

    raises(UnknownNameError, "no node named 'n24x'; did you mean 'n24'? (nodes: "
                             + ", ".join(names[:20]) + ", … (25 in all))",
           lambda: name_index("n24x", names, "node"))
    assert r.force("k4").shape == (1,)


def test_cam_check_by_a_wrong_name_is_named():
    # on main: StopIteration from next() (a generator's end, not an error a user can read)
    cam = cam_profile(cam_cycle("cycloidal", 100, 80, 80, 0.02), 40.0, "roller",
                      roller_radius=10.0)
    raises(UnknownNameError, "no check named 'undercutt'; did you mean 'undercut'? (checks: "
                             "pressure_angle, undercut)", lambda: cam.check("undercutt"))
    assert cam.check("undercut").name == "undercut"


def test_linkage_assemble_names_an_unknown_or_missing_crank():
    # on main: KeyError 'crank' (a bare key) and numpy's conversion error
    lk = load_linkage(QUICK)
    raises(UnknownNameError, "no crank link named 'crnk'; did you mean 'crank'? (crank links: "
                             "crank)", lambda: lk.assemble({"crank": 0.1, "crnk": 0.1}))
    raises(InputError, "crank_angles has no angle for crank link 'crank': give one for each "
                       "of 'crank' [rad]", lambda: lk.assemble({}))
    raises(InputError, "crank_angles must be finite numbers [rad], got ['a']",
           lambda: lk.assemble({"crank": "a"}))
    assert set(lk.assemble({"crank": 0.1})["points"]) == set(lk.pose)


def test_cycle_map_refuses_an_unknown_kind():
    # on main: any kind but "resonance" silently gave the antiresonances
    from mechcirc.scene.cycle import CycleMap

    cm = CycleMap(np.zeros(1), [()], [()], np.array([1]), 1.0, np.zeros((1, 1), complex),
                  {}, True)
    raises(InputError, "kind must be 'resonance' or 'antiresonance', got 'resonanse'; did you "
                       "mean 'resonance'?", lambda: cm.natural_frequencies("resonanse"))
    assert cm.natural_frequencies("antiresonance").shape == (1, 0)


# ------------------------------------------------------------------ names in files
@pytest.mark.parametrize("old, new, message", [
    ('points = ["O2", "O4"', 'points = ["O2", "O44"',
     "<string>:21:17: error: unknown point 'O44' in [ground]; did you mean 'O4'? (expected "
     "one of O2, A, O4, B, D, G1, G2)"),
    ('link   = ["B", "D"]', 'link   = ["B", "DD"]',
     "<string>:27:16: error: unknown point 'DD' in link 'link'; did you mean 'D'? (expected "
     "one of O2, A, O4, B, D, G1, G2)"),
])
def test_linkage_file_names_the_nearest_point(old, new, message):
    # on main: the same message without "; did you mean 'O4'?"
    raises(NetlistError, message, lambda: parse_linkage(QUICK.read_text().replace(old, new)))


@pytest.mark.parametrize("old, new, message", [
    ('[drive]\nlink = "crank"', '[drive]\nlink = "crnk"',
     "<string>:50:8: error: [drive] link 'crnk' is not a rigid link or torsion body; did you "
     "mean 'crank'? (expected one of block, crank)"),
    ('name = "k_rod"\nlink = "rod"', 'name = "k_rod"\nlink = "rodd"',
     "<string>:45:8: error: elastic link 'rodd' is not in the linkage's [links]; did you mean "
     "'rod'? (expected one of crank, rod, block)"),
    ('point = "C"', 'point = "CC"',
     "<string>:40:9: error: [[masses]] #1: point 'CC' does not exist in [points]; did you mean "
     "'C'? (expected one of A, B, C, G1, G2)"),
])
def test_scene_file_names_the_nearest_name(old, new, message):
    # on main: the same message without the hint (and [drive] link located at its key)
    raises(NetlistError, message, lambda: parse_scene(SLIDER.read_text().replace(old, new)))


def test_scene_set_of_an_unknown_field_names_the_nearest():
    # on main: "--set k_rod.stifness: no such parameter; known: ..." (no hint); the list of
    # known names is in parentheses now, as the sley's --set says it
    from mechcirc.scene.files import apply_overrides

    scene = parse_scene(SLIDER.read_text())
    with pytest.raises(MechcircError, match=re.escape(
            "--set k_rod.stifness: no such parameter; did you mean 'k_rod.stiffness'? "
            "(known: omega, ")):
        apply_overrides(scene, {"k_rod.stifness": 1e6})


def test_cli_scene_set_names_the_nearest(capsys):
    from mechcirc.cli import main

    assert main(["simulate", str(SLIDER), "--set", "k_rod.stifness=1e6"]) == 2
    assert capsys.readouterr().err == (
        "mechcirc: error: --set k_rod.stifness: no such parameter; did you mean "
        "'k_rod.stiffness'? (known: omega, omega_ripple.amplitude/harmonic, "
        "m_block.mass/inertia/value, k_rod.stiffness/damping/clearance)\n")


# ------------------------------------------------------------------ numbers
@pytest.fixture(scope="module")
def sley():
    return preset("one-side", 1)


@pytest.mark.parametrize("call, error, message", [
    (lambda: load_linkage(QUICK).motion("x"), InputError,
     "theta must be a finite number [rad], got 'x'"),
    (lambda: load_linkage(QUICK).motion(None), InputError,
     "theta must be a finite number [rad], got None"),
    (lambda: load_linkage(QUICK).solve([0.1, "x"]), InputError,
     "theta must be finite numbers [rad], got [0.1, 'x']"),
    (lambda: load_linkage(QUICK).motion(0.1, max_step_deg="a"), InputError,
     "max_step_deg must be a finite number > 0 [deg], got 'a'"),
    (lambda: FourBar(0.029, 0.037, 0.188, 0.189).transfer("x"), InputError,
     "theta must be a finite number [rad], got 'x'"),
    (lambda: FourBar(0.029, 0.037, 0.188, 0.189).evaluate([1.0, np.nan]), InputError,
     "theta must be finite numbers [rad], got [1.0, nan]"),
    (lambda: FourBar(0.029, 0.037, 0.188, 0.189).rocker_acceleration(1.0, "x"), GeometryError,
     "crank speed ω must be a finite number whose square is finite [rad/s], got 'x'"),
    (lambda: FourBar(0.029, 0.037, 0.188, 0.189).rocker_acceleration_range(None),
     GeometryError,
     "crank speed ω must be a finite number whose square is finite [rad/s], got None"),
    (lambda: FourBar(0.029, 0.037, 0.188, 0.189).summary("100"), GeometryError,
     "crank speed ω must be a finite number whose square is finite [rad/s], got '100'"),
    # (these two: TypeError "unsupported operand" and "can't multiply sequence" before)
    (lambda: FourBar(0.029, 0.037, 0.188, 0.189).nu_extrema("x"), InputError,
     "n must be a whole number of angles from 3 to 1,000,000, got 'x'"),
    (lambda: FourBar(0.029, 0.037, 0.188, 0.189).dead_centres()[0].rocker_acceleration("x"),
     GeometryError,
     "crank speed ω must be a finite number whose square is finite [rad/s], got 'x'"),
])
def test_kinematics_numbers_given_as_text_are_named(call, error, message):
    # on main: "could not convert string to float: 'x'", "'>' not supported between
    # instances of 'str' and 'int'", "can't multiply sequence by non-int of type 'str'",
    # an OutOfReach "reaching θ = nan°" for None
    raises(error, message, call)


@pytest.mark.parametrize("call, message", [
    (lambda p: linearise(p, "x"), "theta0 must be a finite number [rad], got 'x'"),
    (lambda p: linearise(p, 1.0, mu="a"), "mu must be a finite number [1], got 'a'"),
    (lambda p: eigenfrequencies(p, None), "theta0 must be a finite number [rad], got None"),
    (lambda p: to_circuit(p, 1.0, velocity="fast"),
     "velocity must be a finite number [rad/s], got 'fast'"),
    (lambda p: to_netlist(p, float("nan")), "theta0 must be a finite number [rad], got nan"),
])
def test_sley_linear_numbers_given_as_text_are_named(sley, call, message):
    # on main: "could not convert string to float", "float() argument must be ... not
    # 'NoneType'", a GeometryError "four-bar locks ... at θ = nan°"
    raises(ParameterError, message, lambda: call(sley))


def test_the_numbers_still_work(sley):
    fb = FourBar(0.029, 0.037, 0.188, 0.189)
    assert fb.transfer(np.float32(1.0)) == fb.transfer(float(np.float32(1.0)))
    assert fb.rocker_acceleration(1.0, np.float64(100.0)) == fb.nu(1.0) * 1e4
    lin = linearise(sley, np.float64(1.0))
    assert lin.theta0 == 1.0 and lin.mu == sley.fourbar().transfer(1.0)[1]
    assert len(load_linkage(QUICK).motion(np.array([0.1, 0.2]))) == 2


# ------------------------------------------------------------------ tables
def test_design_extremes_frame():
    # on main: DesignExtremes had no to_dataframe
    pytest.importorskip("pandas")
    text = (REPO / "netlists" / "heald_damped.mcir").read_text()
    e = mechcirc.designs(text, {"eta1": np.linspace(0.7, 0.9, 3)}).extremes([100, 2000])
    df = e.to_dataframe()
    names = ["K_min", "omega_at_K_min", "K_max", "omega_at_K_max", "Q0_max", "omega_at_Q0_max"]
    assert list(df.columns) == names + ["failed"] and len(df) == 3
    for name in names:
        np.testing.assert_array_equal(df[name], getattr(e, name))
    assert df["failed"].tolist() == ["", "", ""]
    assert df.attrs["units"] == {"K_min": "m/(N·s)", "omega_at_K_min": "rad/s",
                                 "K_max": "m/(N·s)", "omega_at_K_max": "rad/s", "Q0_max": "N",
                                 "omega_at_Q0_max": "rad/s", "failed": ""}


def test_cycle_map_frame_has_the_cli_csv_columns():
    # on main: CycleMap had no to_dataframe
    pytest.importorskip("pandas")
    from mechcirc.scene import cycle_map, load_scene

    cm = cycle_map(load_scene(SLIDER), points=8, harmonics=3)
    df = cm.to_dataframe()
    assert list(df.columns) == ["theta_deg", "omega_res1", "abs_Q0_h1", "abs_Q0_h2", "abs_Q0_h3"]
    np.testing.assert_array_equal(df["theta_deg"], np.degrees(cm.theta))
    np.testing.assert_array_equal(df["omega_res1"], cm.natural_frequencies()[:, 0])
    np.testing.assert_array_equal(df["abs_Q0_h2"], np.abs(cm.Q0[:, 1]))
    # the drive is on the crank (a link): |Q0| is a moment
    assert df.attrs["units"] == {"theta_deg": "deg", "omega_res1": "rad/s", "abs_Q0_h1": "N·m",
                                 "abs_Q0_h2": "N·m", "abs_Q0_h3": "N·m"}


def test_scene_motion_frame_units_by_output():
    # on main: SceneMotion had no to_dataframe
    pytest.importorskip("pandas")
    from mechcirc.scene import load_scene, simulate_scene

    r = simulate_scene(load_scene(SLIDER))
    df = r.to_dataframe()
    assert list(df.columns) == list(r.columns()) and len(df) == r.crank_angle.size
    for name, arr in r.values.items():
        np.testing.assert_array_equal(df[name], arr)
    # the crank turns (rad/s²), the block slides (its travel in m/s²), the rod is an
    # elastic link (N, m), the drive is on a link (N·m), points accelerate in m/s²
    assert df.attrs["units"] == {
        "crank_angle_deg": "deg", "crank.acceleration": "rad/s²",
        "block.acceleration": "rad/s²", "block.travel.acceleration": "m/s²",
        "k_rod.force": "N", "k_rod.deformation": "m", "drive.moment": "N·m",
        **{f"{p}.acceleration{s}": "m/s²" for p in "BC" for s in ("", "_x", "_y")}}


def test_a_hand_built_scene_motion_must_say_its_units():
    # on main: SceneMotion(...) without units built, and its frame said "" (no unit) for
    # every output; the units are now a required keyword (output_units gives them)
    import dataclasses

    from mechcirc.scene import load_scene, simulate_scene
    from mechcirc.scene.simulation import SceneMotion, output_units

    scene = load_scene(SLIDER)
    r = simulate_scene(scene, revolutions=1)
    given = {f.name: getattr(r, f.name) for f in dataclasses.fields(r) if f.name != "units"}
    with pytest.raises(TypeError, match="units"):
        SceneMotion(**given)
    built = SceneMotion(**given, units=output_units(scene, r.values))
    assert built.units == r.units and "" not in built.units.values()


def test_shaft_motion_frame_units_of_torsion_rods():
    # on main: ShaftMotion had no to_dataframe
    pytest.importorskip("pandas")
    from mechcirc.scene import load_scene
    from mechcirc.scene.shaft import simulate_shaft

    m = simulate_shaft(load_scene(REPO / "examples" / "fnf_sixbar_scene.toml"), points=64)
    df = m.to_dataframe()
    bodies = ["crank1", "crank2", "coupler3", "link4", "coupler5", "output6", "shaft", "organ"]
    assert list(df.columns) == ["theta", "time", "speed", "acceleration", "motor_torque",
                                "load_torque", *(f"{b}.acceleration" for b in bodies),
                                "eps_organ", "C1.force", "C1.deformation", "C6.force", "C6.deformation"]
    np.testing.assert_array_equal(df["speed"], m.speed)
    np.testing.assert_array_equal(df["organ.acceleration"], m.body_accelerations["organ"])
    np.testing.assert_array_equal(df["eps_organ"], m.body_accelerations["organ"])   # an alias
    np.testing.assert_array_equal(df["C6.force"], m.values["C6.force"])
    assert df.attrs["units"] == {
        "theta": "rad", "time": "s", "speed": "rad/s", "acceleration": "rad/s²",
        "motor_torque": "N·m", "load_torque": "N·m",
        **{f"{b}.acceleration": "rad/s²" for b in bodies}, "eps_organ": "rad/s²",
        "C1.force": "N·m", "C1.deformation": "rad", "C6.force": "N·m", "C6.deformation": "rad"}


def test_plot_motion_names_the_nearest_output():
    # on main: ValueError "no output 'k_rod.forse'; outputs: ..." (no hint)
    pytest.importorskip("matplotlib")
    from mechcirc.scene import load_scene, simulate_scene
    from mechcirc.scene.plots import plot_motion

    r = simulate_scene(load_scene(SLIDER))
    raises(InputError, "no output 'k_rod.forse'; did you mean 'k_rod.force'? (outputs: "
                       + ", ".join(r.values) + ")", lambda: plot_motion(r, ["k_rod.forse"]))


def test_scene_alias_of_a_misspelt_output_names_the_nearest():
    # on main: "... which is not an output (outputs: ...)" (no hint)
    from mechcirc.scene import simulate_scene

    text = SLIDER.read_text().replace("[simulate]\nrevolutions = 4", "[simulate]\nrevolutions = "
                                      "4\n[simulate.aliases]\nF = \"k_rod.forse\"")
    with pytest.raises(MechcircError, match=re.escape(
            "<string>: alias 'F' names 'k_rod.forse', which is not an output; did you mean "
            "'k_rod.force'? (outputs: crank.acceleration, ")):
        simulate_scene(parse_scene(text))


def test_an_option_of_another_command_is_not_near_an_unrelated_one(capsys):
    # on main: "--node is an option of sweep, not of transient; did you mean '--debug'?":
    # difflib counted the two dashes every option shares
    from mechcirc.cli import main
    from mechcirc.errors import did_you_mean

    assert did_you_mean("--node", ["--debug", "--t-end"]) == ""
    assert did_you_mean("--omga", ["--debug", "--omega"]) == "; did you mean '--omega'?"
    with pytest.raises(SystemExit) as info:
        main(["transient", str(STB), "--t-end", "0.01", "--node", "M"])
    assert info.value.code == 2
    assert capsys.readouterr().err == (
        "mechcirc transient: error: unrecognized arguments: --node M; --node is an option of "
        "sweep, not of transient (see 'mechcirc transient --help')\n")


def test_params_two_port_method_and_design_index_are_named(stb):
    # on main: no hint for a misspelt .param (load and designs) or port node; a ValueError
    # with no hint for the linkage's method; IndexError "index 5 is out of bounds for axis 0"
    heald = REPO / "netlists" / "heald_damped.mcir"
    params = "; did you mean 'eta1'? (expected one of eta1, eta2, eta3, eta4, etaB, etaC)"
    raises(NetlistError, f"{heald}: error: no .param named 'eta11' to set" + params,
           lambda: mechcirc.load(heald, params={"eta11": 0.8}))
    ds = mechcirc.designs(heald.read_text(), {"eta1": [0.7, 0.8]})
    raises(NetlistError, "<string>: error: no .param named 'eta11' to set" + params,
           lambda: mechcirc.designs(heald.read_text(), {"eta11": [0.7, 0.8]}))
    raises(InputError, "design must be an index 0..1 of the 2 designs (a negative one counts "
                       "from the end), got 5", lambda: ds.design(5))
    assert ds.design(-1).params["eta1"] == 0.8
    raises(InputError, "method must be 'auto', 'dyads' or 'newton', got 'dyad'; did you mean "
                       "'dyads'?", lambda: load_linkage(QUICK).motion(0.1, method="dyad"))
    pytest.importorskip("skrf")
    from mechcirc.errors import TopologyError

    raises(TopologyError, "port node 'Mm' is not a node of the circuit; did you mean 'M'? "
                          "(nodes: 0, A, B, C, D, E, F, G, H, I, J, L, M, T)",
           lambda: stb.two_port("Mm", "0", "A", "0", [100.0]))


def test_cam_cycle_and_plot_cycle_name_the_argument():
    # on main: cam_cycle("cycloidal", 100, 80, 80, "x"): TypeError "must be real number, not
    # str" (which argument?); an unknown law a plain ValueError; plot_cycle(unit="hz") a
    # ValueError with no hint
    from mechcirc.scene.cycle import CycleMap, plot_cycle

    raises(InputError, "stroke must be a number [m or rad], got 'x'",
           lambda: cam_cycle("cycloidal", 100, 80, 80, "x"))
    raises(InputError, "dwell must be a number [deg], got None",
           lambda: cam_cycle("cycloidal", 100, None, 80, 0.02))
    with pytest.raises(InputError, match="unknown motion law 'cycloidl'; .* did you mean "
                                         "'cycloidal'\\?"):
        cam_cycle("cycloidl", 100, 80, 80, 0.02)
    cm = CycleMap(np.zeros(1), [()], [()], np.array([1]), 1.0, np.zeros((1, 1), complex),
                  {}, True)
    raises(InputError, "unit must be one of 'rad/s', 'Hz', 'rpm', got 'hz'; did you mean "
                       "'Hz'?", lambda: plot_cycle(cm, unit="hz"))
