"""A scene's drive keeps its units everywhere: a link (crank) drive is rotary (rad/s, N·m,
rad/(N·m·s)) in the circuit, in the netlist it writes, in what that netlist reads back as,
and in the periodic force's result and plots; a point drive stays translational."""

import math
from pathlib import Path

import matplotlib
import pytest
from cli_helpers import run

from mechcirc import parse
from mechcirc.circuit import units_of
from mechcirc.periodic import periodic, speed_map
from mechcirc.scene import build, parse_scene
from mechcirc.scene.cycle import drive_motion

matplotlib.use("Agg")

SCENE = Path(__file__).resolve().parents[2] / "examples" / "slider_crank_scene.toml"
LINK_DRIVE = 'link = "crank"\nvelocity = 1.0'
ROTARY = {"v": "rad/s", "Q": "N·m", "x": "rad", "K": "rad/(N·m·s)"}
LINEAR = {"v": "m/s", "Q": "N", "x": "m", "K": "m/(N·s)"}


def scene_with(drive: str):
    text = SCENE.read_text()
    assert LINK_DRIVE in text                    # the example still drives its crank
    return parse_scene(text.replace(LINK_DRIVE, drive), source=str(SCENE))


@pytest.mark.parametrize("drive, units", [
    (LINK_DRIVE, ROTARY),
    ('link = "crank"\nforce = 2.0', ROTARY),
    ('point = "C"\nvelocity = 1.0', LINEAR),
    ('point = "C"\nforce = 2.0', LINEAR),
])
def test_the_circuit_and_its_netlist_carry_the_drives_units(drive, units):
    model = build(scene_with(drive), math.radians(30.0))
    assert model.rotational == (units is ROTARY)
    assert units_of(model.circuit.drive) == units
    back = parse(model.netlist)                  # the written text reads back the same way
    assert back.drive.rotational == (units is ROTARY)
    assert back.drive.kind == model.circuit.drive.kind
    assert back.drive.amplitude == model.circuit.drive.amplitude


def test_scene_netlist_round_trip_through_check_says_rad_per_s(tmp_path, capsys):
    out = tmp_path / "x.mcir"
    status, _, err = run(["scene", SCENE, "--theta", "30", "-o", out], capsys)
    assert status == 0, err
    status, text, err = run(["check", out], capsys)
    assert status == 0, err
    drive_line = next(line for line in text.splitlines() if line.startswith("drive "))
    assert "velocity 1 rad/s" in drive_line and "m/s" not in drive_line.replace("rad/s", "")


def test_periodic_result_and_plots_of_a_link_drive_are_in_newton_metres():
    model = build(scene_with(LINK_DRIVE), math.radians(30.0))
    # the crank turns uniformly (its own motion has no harmonics), so any periodic
    # motion serves to exercise the labels: the block's, taken from the point-drive scene
    motion = drive_motion(scene_with('point = "C"\nvelocity = 1.0'), math.radians(30.0))
    r = periodic(model.circuit, 300.0, motion=motion, harmonics=4, points=36)
    assert r.units == ROTARY
    fig = r.plot()
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert "moment [N·m]" in labels and "|Q_k| [N·m]" in labels
    assert "|K| [rad/(N·m·s)]" in labels
    assert not any(lab.endswith("[N]") or "m/(N·s)" in lab.replace("rad/(N·m·s)", "")
                   for lab in labels)
    m = speed_map(model.circuit, 200.0, 400.0, 5, motion=motion, harmonics=4)
    assert m.units == ROTARY
    ax = m.plot().axes[0]
    assert ax.get_ylabel() == "peak moment over the cycle [N·m]"


@pytest.mark.filterwarnings("ignore::mechcirc.errors.UnloadedElementWarning")
def test_periodic_result_of_a_point_drive_stays_in_newtons():
    scene = scene_with('point = "C"\nvelocity = 1.0')
    model = build(scene, math.radians(30.0))
    r = periodic(model.circuit, 300.0, motion=drive_motion(scene, math.radians(30.0)),
                 harmonics=4, points=36)
    assert r.units == LINEAR
    labels = [ax.get_ylabel() for ax in r.plot().axes]
    assert "force [N]" in labels and "|K| [m/(N·s)]" in labels
