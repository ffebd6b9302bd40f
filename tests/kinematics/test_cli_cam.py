"""The ``cam`` sub-command: output equals the API, files, warnings and exit codes."""

import json
import math

import numpy as np
import pytest
from cli_helpers import assert_user_error, run

from mechcirc.cli.cam_commands import _LAWS
from mechcirc.kinematics.cam import cam_profile, profile_csv
from mechcirc.motion_laws import LAWS, cam_cycle, read_motion_table

BASE = ["cam", "--law", "cycloidal", "--rise", "120", "--dwell", "60", "--return", "120",
        "--stroke", "20", "--base-radius", "40", "--roller-radius", "10"]


def test_the_cli_offers_the_laws_of_motion_laws():
    assert _LAWS == LAWS


def test_text_json_and_files_match_the_api(tmp_path, capsys):
    csv, svg = tmp_path / "p.csv", tmp_path / "p.svg"
    status, out, err = run(BASE + ["--offset", "5", "-o", csv, "--svg", svg], capsys)
    assert status == 0 and err == ""
    cam = cam_profile(cam_cycle("cycloidal", 120, 60, 120, 20.0), 40.0, roller_radius=10.0,
                      offset=5.0)
    phi = cam.check("pressure_angle")
    assert f"max |φ| = {math.degrees(phi.value):.4f}° at θ = {math.degrees(phi.theta):.3f}°" \
        in out
    assert "undercut: no" in out and f"wrote {csv}, {svg}" in out
    assert csv.read_text() == profile_csv(cam)
    assert svg.read_text().count("<polygon") == 1
    status, out, err = run(BASE + ["--offset", "5", "--json"], capsys)
    doc = json.loads(out)
    assert doc["checks"]["pressure_angle"]["value_deg"] == math.degrees(phi.value)
    assert doc["checks"]["undercut"]["ok"] is True
    assert np.array_equal(doc["profile"]["x"], cam.x)


def test_oscillating_stroke_and_table_in_degrees(tmp_path, capsys):
    status, out, _ = run(["cam", "--law", "harmonic", "--rise", "90", "--return", "90",
                          "--stroke", "15", "--base-radius", "30", "--roller-radius", "8",
                          "--follower", "oscillating", "--arm", "50", "--pivot", "60",
                          "--json"], capsys)
    assert status == 0
    cam = cam_profile(cam_cycle("harmonic", 90, 0, 90, math.radians(15)), 30.0, "oscillating",
                      roller_radius=8.0, arm=50.0, pivot=60.0)
    assert np.array_equal(json.loads(out)["profile"]["y"], cam.y)
    table = tmp_path / "lift.csv"
    th = np.linspace(0, 360, 73)
    table.write_text("angle_deg,displacement\n"
                     + "".join(f"{a!r},{10 * (1 - math.cos(math.radians(a)))!r}\n"
                               for a in map(float, th)))
    status, out, _ = run(["cam", "--motion", table, "--base-radius", "30", "--roller-radius",
                          "8", "--follower", "oscillating", "--arm", "50", "--pivot", "60",
                          "--json"], capsys)
    assert status == 0
    ref = cam_profile(read_motion_table(table).scaled(math.pi / 180), 30.0, "oscillating",
                      roller_radius=8.0, arm=50.0, pivot=60.0)
    assert np.array_equal(json.loads(out)["profile"]["x"], ref.x)


def test_undercut_and_pressure_angle_warn_with_their_values(capsys):
    status, out, err = run(["cam", "--law", "cycloidal", "--rise", "60", "--dwell", "30",
                            "--return", "60", "--stroke", "40", "--base-radius", "10",
                            "--roller-radius", "20"], capsys)
    assert status == 0 and "undercut: YES" in out and "EXCEEDED" in out
    cam = cam_profile(cam_cycle("cycloidal", 60, 30, 60, 40.0), 10.0, roller_radius=20.0)
    cut, phi = cam.check("undercut"), cam.check("pressure_angle")
    assert f"warning: undercut at θ = {math.degrees(cut.theta):.3f}°" in err
    assert f"so the profile's is {cut.value:.4g} mm" in err
    assert f"warning: pressure angle {math.degrees(phi.value):.4f}°" in err


@pytest.mark.parametrize("extra,needles", [
    (["--low-dwell", "30"], ("= 330°, not 360°",)),
    (["--low-dwell", "60"], ()),
    (["--pivot", "80"], ("--pivot applies to an oscillating follower, not --follower roller",)),
    (["--follower", "flat"], ("--roller-radius applies to a roller follower, not --follower flat",)),
])
def test_cycle_sum_and_options_that_do_not_apply(extra, needles, capsys):
    if needles:
        assert_user_error(BASE + extra, capsys, *needles)
    else:
        assert run(BASE + extra, capsys)[0] == 0


@pytest.mark.parametrize("argv,needles", [
    (["--rise", "220"], ("more than one revolution",)),
    (["--base-radius", "-40"], ("--base-radius", "must be > 0")),
    (["--roller-radius", "-1"], ("--roller-radius", "≥ 0")),
    (["--offset", "60"], ("offset |e| = 60",)),
    (["--follower", "oscillating"], ("--arm and --pivot",)),
    (["--stroke", "0"], ("stroke must be a finite nonzero",)),
    (["--motion", "nofile.csv"], ("not allowed with argument --law",)),
])
def test_bad_input_exits_2_with_one_line(argv, needles, capsys):
    args = list(BASE)
    for opt, val in zip(argv[::2], argv[1::2]):
        if opt in args:
            args[args.index(opt) + 1] = val
        else:
            args += [opt, val]
    assert_user_error(args, capsys, *needles)


def test_table_errors_are_located(tmp_path, capsys):
    table = tmp_path / "lift.csv"
    table.write_text("angle_deg,displacement\n0,0\n90,1\n180,x\n270,1\n360,0\n")
    assert_user_error(["cam", "--motion", table, "--base-radius", "30", "--roller-radius",
                       "5"], capsys, f"{table}:4:5", "'x' is not a number")
    assert_user_error(["cam", "--motion", table, "--rise", "30", "--base-radius", "30",
                       "--roller-radius", "5"], capsys, "--rise applies to a --law cycle")


def test_no_output_file_on_error(tmp_path, capsys):
    csv = tmp_path / "p.csv"
    assert_user_error(BASE + ["--offset", "60", "-o", csv], capsys, "offset")
    assert not csv.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("angle", ["--rise", "--return"])
def test_a_rise_or_return_too_short_for_float64_is_a_user_error(angle, capsys):
    """Fuzz (issue 23): --rise 1e-320 was ZeroDivisionError (1/β² underflowed), exit 1."""
    argv = ["cam", "--law", "cycloidal", "--rise", "120", "--return", "120", "--stroke", "20",
            "--base-radius", "40", "--roller-radius", "10"]
    argv[argv.index(angle) + 1] = "1e-320"
    assert_user_error(argv, capsys, "too short")


FLAT = ["cam", "--law", "cycloidal", "--rise", "120", "--dwell", "60", "--return", "120",
        "--stroke", "8", "--base-radius", "40", "--follower", "oscillating_flat"]


def test_an_oscillating_flat_face_reports_the_curvature_written_out_here(capsys):
    """--follower oscillating_flat: the smallest radius of curvature printed against
    ρ = p + (p_θθ φ_θ − p_θ φ_θθ)/φ_θ³ of the face's line through the pivot (p = D sin ψ,
    ψ = asin(r_b/D) + s, φ_θ = −(1 + s′)), the cycloidal law written out on 200,001
    angles; the 4 decimals shown (the CLI refines its extreme between its 721 angles).  (On
    2,000,001 angles, 0.53 s of CPU more, the minimum moved by 2.3e-9 mm, to 24.33118550 mm,
    3.5e-5 mm from where the 4th decimal would change: the same text is asserted.)"""
    status, out, err = run(FLAT + ["--pivot", "130"], capsys)
    assert status == 0 and err == "", err
    h, b1, d1 = math.radians(8.0), math.radians(120.0), math.radians(60.0)
    th = np.linspace(0.0, 2 * math.pi, 200_001)
    s, s1, s2 = (np.zeros_like(th) for _ in range(3))
    for lo, sign in ((0.0, 1.0), (b1 + d1, -1.0)):
        on = (th >= lo) & (th < lo + b1)
        u = (th[on] - lo) / b1
        s[on] = h * (u - np.sin(2 * np.pi * u) / (2 * np.pi)) if sign > 0 else \
            h * (1 - u + np.sin(2 * np.pi * u) / (2 * np.pi))
        s1[on] = sign * h / b1 * (1 - np.cos(2 * np.pi * u))
        s2[on] = sign * 2 * np.pi * h / b1 ** 2 * np.sin(2 * np.pi * u)
    s[(th >= b1) & (th < b1 + d1)] = h
    psi = math.asin(40.0 / 130.0) + s
    p = 130.0 * np.sin(psi)
    p1 = 130.0 * np.cos(psi) * s1
    p2 = 130.0 * (np.cos(psi) * s2 - np.sin(psi) * s1 ** 2)
    f1, f2 = -(1.0 + s1), -s2
    rho = p + (p2 * f1 - p1 * f2) / f1 ** 3
    assert "follower: oscillating flat face, pivot 130 mm" in out
    assert f"smallest convex {rho.min():.4f} mm" in out, (rho.min(), out)
    assert "max |φ| = 0.0000°" in out and "undercut: no" in out


@pytest.mark.parametrize("extra, needle", [
    ([], "needs --pivot"),
    (["--pivot", "130", "--arm", "50"], "--arm applies to an oscillating roller follower"),
    (["--pivot", "130", "--roller-radius", "5"], "--roller-radius applies to a roller follower"),
    (["--pivot", "30"], "must be more than the base radius"),
])
def test_an_oscillating_flat_face_refuses_bad_options(extra, needle, capsys):
    assert_user_error(FLAT + extra, capsys, needle)


def test_an_oscillating_face_that_turns_back_is_named_not_given_a_radius(tmp_path, capsys):
    """A 50° swing returned in 60°: 1 + s′ = 0 at 180° + 60°·acos(1 − 60/50)/(2π)
    (the cycloidal return written out); the warning says the face turns back there,
    the JSON value is −Infinity."""
    argv = ["cam", "--law", "cycloidal", "--rise", "60", "--dwell", "120", "--return", "60",
            "--stroke", "50", "--base-radius", "40", "--follower", "oscillating_flat",
            "--pivot", "100"]
    theta = 180.0 + 60.0 * math.acos(1.0 - 60.0 / 50.0) / (2 * math.pi)
    status, out, err = run(argv, capsys)
    assert status == 0 and "undercut: YES" in out
    assert f"warning: undercut at θ = {theta:.3f}°: the face stops turning" in err
    status, out, _ = run(argv + ["--json"], capsys)
    check = json.loads(out)["checks"]["undercut"]
    assert status == 0 and check["value"] == -math.inf and not check["ok"]
    assert check["theta_deg"] == pytest.approx(theta, abs=1e-9)
    # its profile is not exported: exit 2 naming the angle, neither file written
    out_csv, out_svg = tmp_path / "p.csv", tmp_path / "p.svg"
    assert_user_error(argv + ["-o", out_csv, "--svg", out_svg], capsys,
                      f"turns back at θ = {theta:.3f}°", "not written")
    assert list(tmp_path.iterdir()) == []
