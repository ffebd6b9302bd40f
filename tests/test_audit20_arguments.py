"""A wrong argument in a notebook (issue 26): a MechcircError (or TypeError) that names the
argument, what it got and what is right, with "did you mean" for a name; never a traceback
from deep inside (an AttributeError, a numpy ufunc error) nor a message naming nothing."""

from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc.errors import MechcircError
from mechcirc.forces import element_forces
from mechcirc.kinematics import cam_profile, synthesize
from mechcirc.modes import sweep_sensitivity
from mechcirc.motion_laws import cam_cycle
from mechcirc.periodic import periodic, speed_map
from mechcirc.scene import build, load_scene, simulate_scene
from mechcirc.sley import preset, simulate
from mechcirc.transient import transient

REPO = Path(__file__).resolve().parents[1]
HEALD = REPO / "netlists" / "heald_damped.mcir"
CAM = "drive V a 0 velocity=1\nmass m a b 1\nspring k b 0 100\n"


@pytest.fixture(scope="module")
def heald():
    return mechcirc.load(HEALD)


@pytest.fixture(scope="module")
def designs():
    return mechcirc.designs(HEALD.read_text(), {"eta1": np.linspace(0.7, 0.9, 3)})


def test_extremes_with_the_band_given_as_two_numbers_says_how(designs):
    # on main: AttributeError 'int' object has no attribute 'single' from _extremes
    with pytest.raises(TypeError, match=r"resonances must be a DesignResonances.*got 2000"
                                        r".*extremes\(\[lo, hi\]\)"):
        designs.extremes(1, 2000)


@pytest.mark.parametrize("call, message", [
    (lambda ds: ds.resonances("x"), "omega_max must be > 0 rad/s or None, got 'x'"),
    (lambda ds: ds.sweep("x"), r"omega must be numbers \[rad/s\], got 'x'"),
])
def test_designs_name_the_bad_argument(designs, call, message):
    # on main: numpy's UFuncTypeError / "could not convert string to float"
    with pytest.raises(MechcircError, match=message):
        call(designs)


def test_omega_as_text_is_named(heald):
    with pytest.raises(MechcircError, match=r"omega must be numbers \[rad/s\], got 'x'"):
        sweep_sensitivity(heald, "x")
    with pytest.raises(MechcircError, match="omega must be a finite number > 0 rad/s, got 'x'"):
        element_forces(heald, "x")
    with pytest.raises(MechcircError, match="need 0 < omega_min < omega_max, got a and 2"):
        mechcirc.adaptive_sweep(heald, "a", 2)


def test_periodic_takes_one_element_name(heald):
    # on main: the name was iterated letter by letter ("no loaded element named 'k'")
    one = periodic(heald, 600, elements="k4", points=36)
    both = periodic(heald, 600, elements=["k4"], points=36)
    assert list(one.forces) == ["k4"]
    np.testing.assert_array_equal(one.forces["k4"], both.forces["k4"])
    assert list(speed_map(heald, 300, 900, 4, elements="k4").element_peaks) == ["k4"]


def test_unknown_names_get_did_you_mean(heald):
    # (Circuit.element keeps its bare KeyError: circuit.py may import only errors.py)
    with pytest.raises(MechcircError, match="unknown frequency unit 'hz'; did you mean 'Hz'"):
        heald.sweep(np.linspace(1, 10, 3)).plot(unit="hz")
    with pytest.raises(MechcircError, match="did you mean 'medium'"):
        synthesize(load="medum")
    with pytest.raises(MechcircError, match="did you mean 'roller'"):
        cam_profile(cam_cycle("cycloidal", 100, 80, 80, 0.02), 40.0, "rolller")
    with pytest.raises(MechcircError, match="did you mean 'one-side'"):
        preset("one-sid")
    with pytest.raises(MechcircError, match="did you mean 'DOP853'"):
        simulate("one-side", 3, 1, method="dop853")
    with pytest.raises(MechcircError, match="did you mean 'DOP853'"):
        simulate_scene(load_scene(REPO / "examples" / "slider_crank_scene.toml"),
                       method="dop853")


def test_times_and_angles_as_text_are_named():
    # on main: "must be real number, not str" / "could not convert string to float"
    with pytest.raises(MechcircError, match=r"--t-end must be a finite time > 0 \[s\], got x"):
        transient(mechcirc.parse(CAM), "x", 1e-3)
    with pytest.raises(MechcircError, match=r"theta must be a finite angle \[rad\], got 'x'"):
        build(load_scene(REPO / "examples" / "heald_scene.toml"), "x")


def test_more_wrong_arguments_are_named(heald, designs):
    from mechcirc.motion_laws import law
    from mechcirc.transient import crosscheck

    # on main: each of these was silent, or a TypeError/AttributeError/ValueError from deep
    # inside naming no argument
    with pytest.raises(TypeError, match=r"elements must be True or False, got \['k4'\]"):
        transient(heald, 0.01, 1e-4, "harmonic:300", elements=["k4"])   # ran as True
    with pytest.raises(TypeError, match=r"velocities must be True or False, got 'no'"):
        transient(mechcirc.load(REPO / "examples" / "cam_follower.mcir"), 1e-3, 1e-5, rpm=800,
                  velocities="no")                      # a run with clearances
    with pytest.raises(MechcircError, match="omega_max must be > 0 rad/s or None, got 'x'"):
        crosscheck(heald, "x")
    with pytest.raises(MechcircError, match="motion must be a Motion .* got 'x'"):
        periodic(heald, 600, motion="x")
    with pytest.raises(MechcircError, match="tol must be between 0 and 1, got 'x'"):
        periodic(heald, 600, tol="x")
    with pytest.raises(MechcircError, match=r"params\['eta1'\] must be numbers, got 'x'"):
        mechcirc.designs(HEALD.read_text(), {"eta1": "x"})
    with pytest.raises(MechcircError, match="got 'hz'; did you mean 'Hz'"):
        heald.resonances().table("hz")
    with pytest.raises(MechcircError, match="got 'SP'; did you mean 'sp'"):
        heald.sweep([1.0], method="SP")
    with pytest.raises(ValueError, match="got 'q0'; did you mean 'Q0'"):
        heald.sweep([1.0, 2.0]).peak("q0")
    with pytest.raises(ValueError, match="'cycloidl'.*did you mean 'cycloidal'"):
        law("cycloidl", np.linspace(0, 1, 3))
    with pytest.raises(ValueError, match="'cycloidl'.*did you mean 'cycloidal'"):
        cam_cycle("cycloidl", 100, 80, 80, 0.02)
    with pytest.raises(ValueError, match="omega must be a finite number > 0 rad/s, got 'x'"):
        simulate_scene(load_scene(REPO / "examples" / "slider_crank_scene.toml"), omega="x")


def test_kinematics_numbers_as_text_are_named():
    from mechcirc.kinematics import FourBar, frame_loading

    # on main: "must be real number, not str" (math.isfinite) and "could not convert
    # string to float" (float()), naming no argument
    with pytest.raises(MechcircError, match="crank speed ω must be finite and > 0 rad/s, got x"):
        frame_loading(FourBar(35, 62.8, 170.1, 170.65), [0.1], "x")
    with pytest.raises(MechcircError, match="the base radius must be a finite number, got 'x'"):
        cam_profile(cam_cycle("cycloidal", 100, 80, 80, 0.02), "x")
