"""The ``fourbar``, ``synth`` and ``linkage`` sub-commands: output equals the API, exit codes."""

import json
import math
import warnings
from pathlib import Path

import pytest

from mechcirc.cli import main
from mechcirc.kinematics import FourBar, load_linkage, synthesize

ROOT = Path(__file__).resolve().parents[2]
FNF = ROOT / "examples" / "fnf_sixbar.toml"
MRAZEK = ["fourbar", "--crank", "29", "--coupler", "37", "--rocker", "188", "--frame", "189"]


def _json(capsys, argv):
    status = main(argv + ["--json"])
    out = capsys.readouterr().out
    return status, json.loads(out)


def test_fourbar_text_and_json(capsys, tmp_path):
    png = tmp_path / "fb.png"
    assert main(MRAZEK + ["--omega", "100", "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "[-2319.4, 2914.6]" in out and "crank-rocker" in out and "swing Ψ = 17.7500°" in out
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    status, doc = _json(capsys, MRAZEK + ["--omega", "40"])
    assert status == 0
    assert (round(doc["eps4T_min"]), round(doc["eps4T_max"])) == (-371, 466)
    front, back = FourBar(29, 37, 188, 189).dead_centres()
    assert doc["dead_centres"][0]["theta_deg"] == pytest.approx(math.degrees(front.theta))
    assert doc["dead_centres"][1]["nu"] == pytest.approx(back.nu)


def test_fourbar_impossible_geometry_exit_2(capsys):
    assert main(["fourbar", "--crank", "10", "--coupler", "20", "--rocker", "30",
                 "--frame", "70"]) == 2
    err = capsys.readouterr().err
    assert "cannot be assembled" in err and "frame" in err


def test_frame_impossible_geometry_names_the_lengths_as_typed(capsys):
    """New-user pass, session 28: ``frame`` reported 0.4 and 0.2484 (metres, no unit)
    for lengths typed in mm (400, 248.4 as ``fourbar`` says)."""
    assert main(["frame", "--crank", "35", "--coupler", "57.8", "--rocker", "155.6",
                 "--frame", "400", "--rpm", "600", "--mass", "2,1.5,15"]) == 2
    err = capsys.readouterr().err
    assert "the frame (400) is not shorter" in err and "(248.4)" in err


def test_synth_json_matches_api(capsys, tmp_path):
    png = tmp_path / "s.png"
    status, doc = _json(capsys, ["synth", "--load", "heavy", "--swing", "25", "--limit", "3",
                                 "--plot", str(png)])
    assert status == 0 and png.exists()
    api = synthesize("heavy", 25.0, limit=3)
    assert len(doc["designs"]) == 3
    for d, des in zip(doc["designs"], api.designs):
        assert (d["a"], d["b"], d["c"], d["d"]) == pytest.approx((des.a, des.b, des.c, des.d))
        assert set(d["criteria"]) == {"crank_length", "front_transmission", "min_transmission",
                                      "acceleration_ratio", "frame_length", "rocker_ratio",
                                      "swing"}
        assert all(c["passed"] for c in d["criteria"].values())


def test_synth_infeasible_says_which_criteria_conflict(capsys):
    assert main(["synth", "--swing", "20"]) == 2
    err = capsys.readouterr().err
    assert "cannot hold together" in err and "frame_length" in err


def test_linkage_json_matches_api(capsys, tmp_path):
    png = tmp_path / "lk.png"
    status, doc = _json(capsys, ["linkage", str(FNF), "--theta", "30", "--plot", str(png)])
    assert status == 0 and png.exists()
    assert doc["mobility"] == 2 and doc["revolute_pairs"] == 8
    state = load_linkage(FNF).solve(math.radians(30))
    assert doc["velocities"]["K"] == pytest.approx(state.velocities["K"].tolist())
    assert doc["conditional_stop"]["crank2"]["K"] == pytest.approx(
        state.contributions["crank2"]["K"].tolist())


def test_linkage_file_error_is_located(capsys, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(FNF.read_text().replace('output6  = ["O6", "K"]', 'output6  = ["O6", "Z"]'))
    assert main(["linkage", str(bad)]) == 2
    err = capsys.readouterr().err
    line = next(n for n, l in enumerate(bad.read_text().splitlines(), 1) if l.startswith("output6"))
    assert err.startswith(f"{bad}:{line}:") and "unknown point 'Z'" in err


def test_registering_the_commands_imports_nothing_heavy(light_imports):
    # (whether `import mechcirc` loads numpy is the package's business, not ours;
    # one process with the other light-import checks: tests/conftest.py, light_imports)
    loaded = set(light_imports["register kinematics"])
    assert not loaded & {"mechcirc.kinematics", "scipy", "matplotlib"}, loaded
    assert "matplotlib" not in light_imports["import mechcirc.kinematics"]


@pytest.mark.parametrize("cmd", ["fourbar", "synth", "linkage"])
def test_help_has_an_example(cmd, capsys):
    with pytest.raises(SystemExit):
        main([cmd, "--help"])
    assert f"Example: mechcirc {cmd}" in capsys.readouterr().out


def test_fourbar_change_point_is_named_and_nu_withheld(capsys):
    argv = ["fourbar", "--crank", "30", "--coupler", "100", "--rocker", "30", "--frame", "100",
            "--omega", "100"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    out = captured.out
    assert "change-point" in out and "parallelogram" in out and "crank-rocker" not in out
    assert "branches cross at θ = 0°, 180°" in out
    assert "ν range: [" not in out and "e+15" not in out and "e15" not in out
    assert "RuntimeWarning" not in captured.err


@pytest.mark.parametrize("dims", [("50", "30", "30", "50"), ("30", "100", "100", "30")])
def test_fourbar_deltoid_with_crank_equal_frame_reports_and_plots(capsys, tmp_path, dims):
    """B lies on D at θ = 0.  On main: 50/30/30/50 a RuntimeWarning (an internal error
    under -W error), 30/100/100/30 with --plot exit 2, 'locks at θ = 0° (the crank reaches
    θ ∈ [0°, 360°] only)'."""
    png = tmp_path / "deltoid.png"
    argv = ["fourbar"] + [x for pair in zip(("--crank", "--coupler", "--rocker", "--frame"),
                                            dims) for x in pair]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(argv + ["--omega", "10", "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "deltoid" in out and "branches cross at θ = 0°" in out
    assert "cannot be assembled" not in out
    assert png.stat().st_size > 0


@pytest.mark.parametrize("extra,what", [(["--omega", "1e300"], "at most"),
                                        (["--omega", "nan"], "finite"),
                                        (["--omega", "inf"], "finite")])
def test_fourbar_bad_omega_exit_2(capsys, extra, what):
    with pytest.raises(SystemExit) as info:
        main(MRAZEK + extra)
    assert info.value.code == 2
    assert what in capsys.readouterr().err


def test_fourbar_huge_lengths_exit_2_without_warnings(capsys):
    argv = ["fourbar", "--crank", "1e308", "--coupler", "37", "--rocker", "1e308",
            "--frame", "189"]
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "--crank" in err and "at most" in err and "Warning" not in err


# ------------------------------------------------------------------ frame
FRAME = ["frame", "--crank", "35", "--coupler", "57.8", "--rocker", "155.6", "--frame", "162.75",
         "--rpm", "600", "--mass", "2,1.5,15", "--crank-com", "12,3", "--crank-inertia", "0.002",
         "--coupler-com=25,-4", "--coupler-inertia", "0.0009", "--rocker-com", "110,30",
         "--rocker-inertia", "0.08", "--reed-force=-50,-500", "--reed-point", "140,50",
         "--gravity", "--points", "73"]


def test_frame_json_matches_the_api_and_the_moment_transfer(capsys):
    import numpy as np

    from mechcirc.kinematics import LinkMass, beat_up_force, frame_loading

    status, doc = _json(capsys, FRAME)
    assert status == 0
    fb = FourBar(0.035, 0.0578, 0.1556, 0.16275)
    theta = np.radians(np.linspace(0, 360, 73))
    res = frame_loading(fb, theta, 20 * math.pi, crank=LinkMass(2, (0.012, 0.003), 0.002),
                        coupler=LinkMass(1.5, (0.025, -0.004), 0.0009),
                        rocker=LinkMass(15, (0.11, 0.03), 0.08),
                        reed_force=beat_up_force(fb, (-50, -500)), reed_point=(0.14, 0.05),
                        gravity=(0, -9.81))
    cols = {k: np.array(v) for k, v in doc["columns"].items()}
    np.testing.assert_allclose(cols["S_abs_N"], res.shaking_force_magnitude, rtol=1e-12)
    # moment transfer T_a − T_d = AD × S with AD = (d, 0): d·S_y
    np.testing.assert_allclose(cols["T_a_Nm"] - cols["T_d_Nm"], 0.16275 * cols["S_y_N"],
                               rtol=0, atol=1e-14 * np.max(np.abs(cols["T_d_Nm"])))  # 1e-16
    # eq. 7 as printed: F_Ax·AD_y − F_Ay·AD_x − T = −F_Ay·d − T
    np.testing.assert_allclose(cols["T_d_printed_Nm"], -cols["F_Ay_N"] * 0.16275 - cols["T_Nm"],
                               rtol=0, atol=2e-14 * np.max(np.abs(cols["T_Nm"])))  # 1.6e-15
    assert doc["summary"]["T_d_printed_minus_T_d_max_abs_Nm"] > 100
    assert "T_d = AD_x·F_Ay − AD_y·F_Ax − T" in doc["convention"]


def test_frame_text_csv_and_plot(capsys, tmp_path):
    csv, png = tmp_path / "f.csv", tmp_path / "f.png"
    assert main(FRAME + ["-o", str(csv), "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "sign convention: T_a = F_Dx·AD_y" in out and "printed eq. 7's T_d" in out
    assert "|S| shaking force on the frame [N]" in out
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("# mechcirc frame") and lines[1].startswith("theta_deg,F_Ax_N")
    assert len(lines) == 2 + 73
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_frame_refuses_a_non_crank_rocker_without_writing(capsys, tmp_path):
    csv = tmp_path / "f.csv"
    argv = ["frame", "--crank", "30", "--coupler", "100", "--rocker", "30", "--frame", "100",
            "--rpm", "100", "-o", str(csv)]
    assert main(argv) == 2
    assert "crank-rocker" in capsys.readouterr().err and not csv.exists()


def test_beat_up_force_is_a_half_sine_around_the_front_dead_centre():
    import numpy as np

    from mechcirc.kinematics import beat_up_force

    fb = FourBar(29, 37, 188, 189)
    front = fb.dead_centres()[0].theta
    f = beat_up_force(fb, (3.0, -4.0), window_deg=40)
    x = front + np.radians([0.0, 10.0, -10.0, 19.9, 20.1, 180.0])
    got = f(x)
    c45 = math.cos(math.pi / 4)                     # 10° into a 40° window: a quarter period
    np.testing.assert_allclose(got[:3], [[3, -4], [3 * c45, -4 * c45], [3 * c45, -4 * c45]],
                               rtol=1e-12)
    assert got[3, 1] == pytest.approx(-4 * math.cos(19.9 / 40 * math.pi), rel=1e-12)
    assert np.all(got[4:] == 0)


def test_synth_export_lists_files_that_scene_and_linkage_run(capsys, tmp_path):
    status, doc = _json(capsys, ["synth", "--load", "light", "--limit", "2", "--export",
                                 str(tmp_path)])
    assert status == 0
    names = [Path(e[k]).name for e in doc["exported"] for k in ("linkage", "scene")]
    assert names == ["design_1.linkage.toml", "design_1.scene.toml",
                     "design_2.linkage.toml", "design_2.scene.toml"]
    scene = doc["exported"][0]["scene"]
    assert main(["scene", scene, "--theta", "100"]) == 0
    assert "resonance" in capsys.readouterr().out
    assert main(["linkage", doc["exported"][0]["linkage"], "--theta", "45"]) == 0


def test_synth_export_to_a_missing_folder_is_a_user_error(capsys, tmp_path):
    assert main(["synth", "--limit", "1", "--export", str(tmp_path / "nope")]) == 2
    assert "no such folder" in capsys.readouterr().err


@pytest.mark.parametrize("option", ["--sley-inertia", "--rocker-inertia", "--crank-inertia",
                                    "--c2", "--c4", "--beat-window"])
def test_synth_scene_values_the_scene_refuses_are_refused_as_options(option, capsys):
    """New-user pass, session 28: '--sley-inertia 0' passed the option's check (>= 0) and
    was refused later as 'scene I4P must be a positive finite number'."""
    from cli_helpers import assert_user_error

    assert_user_error(["synth", "--swing", "25", option, "0"], capsys, f"argument {option}",
                      "must be > 0")


def test_synth_fixed_frame_and_ranges_on_the_cli(capsys):
    status, doc = _json(capsys, ["synth", "--load", "medium", "--frame", "165", "--limit", "2",
                                 "--swing-range", "24:26", "--b-a-range", "1.5:2"])
    assert status == 0 and doc["fixed_mm"] == {"frame": 165.0}
    for des in doc["designs"]:
        assert des["d"] == pytest.approx(165.0) and des["b"] / des["a"] <= 2 + 1e-9
        assert 24 - 1e-9 <= des["swing_deg"] <= 26 + 1e-9
