"""Units in the cam's numeric fields (audit18): the ``cam`` command's lengths and angles,
a scene's ``[cam]`` table, read by the one grammar; a bare number keeps its documented
meaning (mm or the scene's units, degrees), a number with a unit is converted to it."""

import json
import math
import re
from pathlib import Path

import pytest
from cli_helpers import assert_cam_key_error, assert_user_error, run

from mechcirc.cli._common import real
from mechcirc.scene import parse_scene
from mechcirc.units import in_unit_of

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CAM = ["cam", "--law", "cycloidal", "--dwell", "60", "--return", "120", "--json"]


@pytest.mark.parametrize("text, unit, role, want", [
    ("120 deg", "deg", "angle", 120.0),        # the option's own unit: the number as written
    ("30deg", "deg", "angle", 30.0),           # (SI and back gave 29.999999999999996)
    ("2 cm", "mm", "length", 20.0),
    ("0.5 rad", "deg", "angle", 0.5 * 180 / math.pi),
    ("75", "deg", "angle", 75.0),              # a bare number is in the unit asked for
    ("3 mm", "", "length", 0.003),             # "": SI
])
def test_in_unit_of(text, unit, role, want):
    assert in_unit_of(text, role, unit) == pytest.approx(want, rel=2e-16, abs=0)


def test_angle_option_in_its_own_unit_is_exact():
    assert real(unit="deg", role="angle")("30deg") == 30.0       # main: 29.999999999999996


def _cam(capsys, *extra):
    status, out, err = run([*CAM, *extra], capsys)
    assert status == 0, err
    doc = json.loads(out)
    doc.pop("motion")                          # its spec echoes the text as written
    return doc


def test_cam_lengths_and_angles_take_units(capsys):
    bare = _cam(capsys, "--rise", "120", "--stroke", "20", "--base-radius", "40",
                "--roller-radius", "10", "--offset", "5")
    with_units = _cam(capsys, "--rise", "120deg", "--stroke", "2cm", "--base-radius", "0.04 m",
                      "--roller-radius", "10mm", "--offset", "0.5cm")
    assert with_units == bare                  # main: '2cm' is not a number (exit 2)
    rad = _cam(capsys, "--rise", f"{2 * math.pi / 3!r}rad", "--stroke", "20", "--base-radius",
               "40", "--roller-radius", "10", "--offset", "5")
    assert rad["checks"]["pressure_angle"]["value_deg"] == pytest.approx(
        bare["checks"]["pressure_angle"]["value_deg"], rel=1e-12)


def test_oscillating_stroke_is_an_angle(capsys):
    osc = ["--rise", "120", "--base-radius", "40", "--roller-radius", "10", "--follower",
           "oscillating", "--arm", "100", "--pivot", "130"]
    assert _cam(capsys, *osc, "--stroke", "8deg") == _cam(capsys, *osc, "--stroke", "8")
    assert_user_error([*CAM, *osc, "--stroke", "20mm"], capsys, "--stroke 20mm",
                      "the arm's swing, an angle", "no unit means deg")
    assert_user_error([*CAM, *osc[:6], "--stroke", "15deg"], capsys, "--stroke 15deg",
                      "a lift, a length", "no unit means mm")


def _with(text, key, value):
    return re.sub(rf"(?m)^{key}\s*=.*$", f"{key} = {value}", text, count=1)


def test_scene_cam_table_takes_units():
    text = (EXAMPLES / "cam_jump_scene.toml").read_text()
    base = parse_scene(text, "s.toml").linkage
    changed = text
    for key, value in (("rise", '"100 deg"'), ("stroke", '"2 cm"'), ("spring", '"5 N/mm"'),
                       ("preload", '"0.05 kN"'), ("dwell", '"80"')):
        changed = _with(changed, key, value)
    lk = parse_scene(changed, "s.toml").linkage     # main: "[cam] rise must be a number"
    assert lk.key == base.key and (lk.spring, lk.preload) == (base.spring, base.preload)
    rad = parse_scene(_with(text, "rise", f'"{5 * math.pi / 9!r} rad"'), "s.toml").linkage
    assert rad.key[3] == pytest.approx(100.0, rel=1e-15)


def test_scene_cam_unit_of_the_wrong_kind_is_located(tmp_path, capsys):
    text = (EXAMPLES / "cam_heald_scene.toml").read_text()
    assert_cam_key_error(_with(text, "rise", '"120 mm"'), "rise",
                         ["unit 'mm' is a length", "angle (rad, deg)"], tmp_path, capsys)
    assert_cam_key_error(_with(text, "pivot", '"130 deg"'), "pivot",
                         ["unit 'deg'", "length (m, mm, cm)"], tmp_path, capsys)


def test_scene_cam_names_say_did_you_mean(tmp_path, capsys):
    text = (EXAMPLES / "cam_heald_scene.toml").read_text()
    assert_cam_key_error(_with(text, "law", '"cycloidl"'), "law",
                         ["not a motion law; did you mean 'cycloidal'?"], tmp_path, capsys)
    typo = _with(text, "follower", '"lever"\nfollower_type = "oscilating"')
    assert_cam_key_error(typo, "follower_type", ["did you mean 'oscillating'?"], tmp_path,
                         capsys)
