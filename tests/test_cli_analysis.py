"""CLI: resonances, --method, --adaptive, and the flag column."""

import json

import numpy as np

import mechcirc
from mechcirc.cli import main
from reference.inputs import STB

BRIDGE = """drive V a 0 velocity=0.5
spring k1 a b 1e4
damper c2 a c 30
mass   m3 b c 2
spring k4 b 0 3e4
mass   m5 c 0 5
"""


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_resonances_text_and_json(capsys):
    status, out, err = run(["resonances", STB], capsys)
    assert status == 0, err
    assert "3 resonances (K = 0), 2 anti-resonances (K = ∞)" in out
    status, out, err = run(["resonances", STB, "--omega-max", 800], capsys)
    assert status == 0 and ": 1 resonance (K = 0), 1 anti-resonance (K = ∞) up to" in out
    status, out, err = run(["resonances", STB, "--omega-max", 1000, "--json"], capsys)
    doc = json.loads(out)
    api = mechcirc.load(STB).resonances(omega_max=1000)
    assert [r["omega"] for r in doc["resonances"]] == [r.omega for r in api]
    assert [r["kind"] for r in doc["resonances"]] == ["resonance", "antiresonance", "resonance",
                                                     "antiresonance"]
    assert all(abs(r["f_hz"] * 2 * np.pi - r["omega"]) < 1e-9 * r["omega"]
               for r in doc["resonances"])


def test_sweep_method_nodal_and_auto_fallback(tmp_path, capsys):
    path = tmp_path / "bridge.mcir"
    path.write_text(BRIDGE)
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 100, "--points",
                            5, "--json"], capsys)
    assert status == 0, err
    assert json.loads(out)["method"] == "nodal"
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 100,
                            "--method", "sp"], capsys)
    assert status == 2
    assert "not series–parallel reducible" in err and "Traceback" not in err


def test_check_of_a_bridge_says_nodal_analysis_is_used(tmp_path, capsys):
    path = tmp_path / "bridge.mcir"
    path.write_text(BRIDGE)
    status, out, err = run(["check", path], capsys)
    assert status == 0, err
    assert "not series–parallel" in out and "nodal analysis is used" in out


def test_flag_column_marks_a_point_on_a_resonance(tmp_path, capsys):
    path = tmp_path / "lc.mcir"
    path.write_text("drive V a 0 velocity=1\nmass m a b 1\nspring k b 0 1\n")
    out_csv = tmp_path / "lc.csv"
    status, out, err = run(["sweep", path, "--omega-min", 0, "--omega-max", 2, "--points", 3,
                            "-o", out_csv], capsys)
    assert status == 0, err
    rows = out_csv.read_text().splitlines()
    assert rows[0].endswith(",flag")
    assert [r.split(",")[-1] for r in rows[1:]] == ["1", "1", "0"]
    assert "2 point(s) on or within rounding of a pole or zero" in out


def test_adaptive_sweep_reports_its_points(tmp_path, capsys):
    path = tmp_path / "sdof.mcir"
    path.write_text("drive V a 0 velocity=1\nspring k a b 1e4\ndamper c a b 2\nmass m b 0 1\n")
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 1e3,
                            "--adaptive", "--json"], capsys)
    assert status == 0, err
    doc = json.loads(out)
    assert doc["points"] == len(doc["omega"]) < 400
    q = np.hypot(doc["Q0"]["re"], doc["Q0"]["im"])
    assert abs(q.max() / 5000.99990006 - 1) < 0.01     # exact peak of this SDOF


def test_force_drive_csv_has_velocity_columns(tmp_path, capsys):
    path = tmp_path / "f.mcir"
    path.write_text("drive F a 0 force=10\nmass m a 0 2\nspring k a 0 800\n")
    out_csv = tmp_path / "f.csv"
    status, _, err = run(["sweep", path, "--omega-min", 5, "--omega-max", 47, "--points", 4,
                          "-o", out_csv], capsys)
    assert status == 0, err
    header = out_csv.read_text().splitlines()[0]
    assert header == "omega,K_re,K_im,Q0_re,Q0_im,v0_re,v0_im,flag"
    table = np.loadtxt(out_csv, delimiter=",", skiprows=1)
    w = table[:, 0]
    K = 1 / (2j * w + 800 / (1j * w))
    np.testing.assert_allclose(table[:, 5] + 1j * table[:, 6], 10 * K, rtol=1e-13)


def test_adaptive_sweep_says_its_work_bound_or_refuses_with_it(tmp_path, capsys, monkeypatch):
    """The bound counts work (K evaluations × elements) and is said when hit (issue 23 §8)."""
    from mechcirc import limits

    path = tmp_path / "two.mcir"
    path.write_text("drive V a 0 velocity=1\nspring k1 a b 2e4\ndamper c1 a b 0.01\n"
                    "mass m1 b 0 1\nspring k2 b c 5e4\ndamper c2 b c 0.01\nmass m2 c 0 0.5\n")
    monkeypatch.setattr(limits, "MAX_ADAPTIVE_WORK", 6 * 400)      # 400 evaluations of K
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 1e4,
                            "--adaptive", "--tol", 1e-5, "--points", 41], capsys)
    assert status == 0, err
    assert ("note: work bound of 2,400 element evaluations (400 evaluations of K on this "
            "network of 6 elements and levers, method sp) reached: ") in out
    points = int(out.split(": ")[1].split()[0])
    assert points <= 400 // 3
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 1e4,
                            "--adaptive", "--points", 1000], capsys)
    assert status == 2 and out == ""
    assert err.startswith("mechcirc: error: adaptive sweep: its starting grid of ")
    assert "over the work bound of 2,400 element evaluations" in err
