"""A scene's ``[cam]`` with an oscillating FLAT-FACED follower (``follower_type =
"oscillating_flat"``: a flat face through the arm's pivot, 130 mm from the cam's centre)
against references computed here independently of the scene code.

* The arm's angle against the cam it rides on: the profile of
  ``kinematics.cam.cam_profile(..., "oscillating_flat")`` (200,001 points) is turned to
  each cam angle θ and the face through the pivot A = (D, 0) that touches it is found
  as the supporting line, the largest angle β from A→O of A→P over the profile points
  P (refined by a parabola); its change from θ = 0 must be the scene's arm rotation,
  and its value at θ = 0 asin(r_b / D) (the face on the base circle).  Measured
  2.0e-11 rad (the profile's sampling), tested to 1e-10 rad.
* The arm's angle against the cycloidal law written out by hand: ≤ 1e-12 of the swing.
* The circuit at θ and one revolution of the simulation are tested with the roller
  follower in test_cam_scene.py (parametrised over both faces, the SymPy linearisation
  and the DOP853 reference of the frame's equation of motion).
* Bad input located at its key, exit 2 through the CLI: the roller's keys (arm,
  roller_radius) on a flat face, a pivot not beyond the base circle, a contact that can
  open (translating followers only).
"""

import math
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import assert_cam_key_error, run
from mechcirc.kinematics.cam import cam_profile
from mechcirc.scene import parse_scene

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "cam_heald_scene.toml"
TEXT = EXAMPLE.read_text()
FLAT = TEXT.replace("roller_radius = 12.0\narm = 100.0\n", "").replace(
    "[cam]\n", '[cam]\nfollower_type = "oscillating_flat"\n')
H = math.radians(8.0)
B1, D1, B2 = (math.radians(v) for v in (120.0, 60.0, 120.0))
RB, D = 40.0, 130.0                               # base radius, pivot distance [mm]


def cycloidal_angle(theta):
    """The arm's rotation x(θ) of the cycloidal 120/60/120/60° cycle, by hand."""
    th = np.mod(np.asarray(theta, float), 2 * math.pi)
    x = np.zeros_like(th)
    up = th < B1
    u = th[up] / B1
    x[up] = H * (u - np.sin(2 * np.pi * u) / (2 * np.pi))
    x[(th >= B1) & (th < B1 + D1)] = H
    down = (th >= B1 + D1) & (th < B1 + D1 + B2)
    u = (th[down] - B1 - D1) / B2
    x[down] = H * (1 - u + np.sin(2 * np.pi * u) / (2 * np.pi))
    return x


def _face_angle(x, y, theta):
    """The face through A = (D, 0) touching the profile (x, y) turned by θ: the largest
    angle from A→O of A→P over its points, refined by the parabola through the best three."""
    c, s = math.cos(theta), math.sin(theta)
    wx, wy = c * x - s * y, s * x + c * y
    beta = np.arctan2(wy, D - wx)
    i = int(np.argmax(beta))
    a, b, e = beta[i - 1], beta[i], beta[(i + 1) % beta.size]
    den = a - 2 * b + e
    return float(b - 0.125 * (a - e) ** 2 / den) if den < 0 else float(b)


def test_the_arm_touches_the_cam_it_rides_on():
    scene = parse_scene(FLAT, "flat.toml")
    lk = scene.linkage
    theta = np.radians(np.arange(0.0, 360.0, 7.5))
    m = lk.motion(theta)
    j = lk.link_index()["lever"]
    turn = np.unwrap(m.q[:, 3 * j + 2])
    turn = turn - turn[0]
    assert np.max(np.abs(turn - cycloidal_angle(theta))) <= 1e-12 * H
    prof = cam_profile(lk.cam, RB, "oscillating_flat", pivot=D, points=200_001)
    psi = np.array([_face_angle(prof.x[:-1], prof.y[:-1], t) for t in theta])
    assert abs(psi[0] - math.asin(RB / D)) <= 1e-10
    # measured 2.0e-11 rad: the profile's sampling (the parabola through three points)
    assert np.max(np.abs((psi - psi[0]) - turn)) <= 1e-10


def test_the_circuit_at_theta_is_printed_by_the_cli(tmp_path, capsys):
    f = tmp_path / "flat.toml"
    f.write_text(FLAT)
    code, out, err = run(["scene", f, "--theta", "60"], capsys)
    assert code == 0, err
    assert "drive ratio r0 = 0.133333" in out and "416.189" in out


def _bad(old, new):
    assert old in FLAT, old
    return FLAT.replace(old, new)


@pytest.mark.parametrize("text, key, needles", [
    (_bad("pivot = 130.0", "pivot = 130.0\narm = 100.0"), "arm",
     ["arm is for an oscillating roller follower, not oscillating_flat"]),
    (_bad("pivot = 130.0", "pivot = 130.0\nroller_radius = 5.0"), "roller_radius",
     ["roller_radius is for a roller follower, not oscillating_flat"]),
    (_bad("pivot = 130.0", "pivot = 35.0"), "pivot",
     ["cannot be built", "D = 35 must be more than the base radius r_b = 40"]),
    (_bad("pivot = 130.0", 'pivot = 130.0\ncontact = "rod"\nspring = 1.0\npreload = 1.0'),
     "contact", ["for a translating follower"]),
    (_bad('follower_type = "oscillating_flat"', 'follower_type = "oscillating_knife"'),
     "follower_type", ["not a follower type", "oscillating_flat"]),
])
def test_bad_flat_face_tables_are_located(text, key, needles, tmp_path, capsys):
    assert_cam_key_error(text, key, needles, tmp_path, capsys)


def test_a_face_that_turns_back_is_warned_at_its_angle():
    """A 70° swing returned over 120°: 1 + s′ = 0 first at 180° + 120°·acos(1 − 120/70)/(2π)
    (the cycloidal return written out); the warning names that angle, not a radius."""
    import re
    import warnings

    from mechcirc.errors import MechcircWarning

    text = re.sub(r"stroke_deg = [0-9.]+", "stroke_deg = 70.0", FLAT)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        parse_scene(text, "big.toml")
    msgs = [str(w.message) for w in got if issubclass(w.category, MechcircWarning)]
    at = 180.0 + 120.0 * math.acos(1.0 - 120.0 / 70.0) / (2 * math.pi)
    assert len(msgs) == 1 and "the face stops turning against the cam" in msgs[0], msgs
    assert f"at cam angle {at:.4g}°" in msgs[0], (at, msgs)
