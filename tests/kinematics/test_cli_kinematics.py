"""The ``fourbar``, ``synth`` and ``linkage`` sub-commands: output equals the API, exit codes."""

import json
import math
import subprocess
import sys
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


def test_registering_the_commands_imports_nothing_heavy():
    # (whether `import mechcirc` loads numpy is the package's business, not ours)
    code = ("import sys, argparse; from mechcirc.cli import kinematics_commands as k; "
            "p = argparse.ArgumentParser(); k.register(p.add_subparsers()); "
            "print(*[m in sys.modules for m in ('mechcirc.kinematics', 'scipy', 'matplotlib')])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.split() == ["False", "False", "False"]
    code = "import sys, mechcirc.kinematics; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "False"


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


@pytest.mark.parametrize("extra,what", [(["--omega", "1e300"], "square overflows"),
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
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "out of range" in err and "Warning" not in err and err.count("\n") == 1
