"""``mechcirc periodic``: outputs agree with the API, are written whole or not at all,
and bad input is a located one-line error with exit status 2."""

import csv
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import assert_user_error, run

from mechcirc import load
from mechcirc.periodic import periodic, speed_map

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
CAM = EXAMPLES / "cam_drive.mcir"


def test_one_speed_csv_and_json_agree_with_the_api(tmp_path, capsys):
    out = tmp_path / "q.csv"
    status, text, err = run(["periodic", CAM, "--rpm", "600", "-o", out, "--elements", "k1"],
                            capsys)
    assert status == 0, err
    ref = periodic(load(CAM), 600, elements=["k1"])
    assert f"{ref.harmonics} harmonics" in text and "peak |Q|" in text
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 360 and list(rows[0]) == ["angle_deg", "x", "v", "Q", "F_k1", "v_k1"]
    Q = np.array([float(r["Q"]) for r in rows])
    assert np.array_equal(Q, ref.Q)
    status, text, _ = run(["periodic", CAM, "--rpm", "600", "--json"], capsys)
    doc = json.loads(text)
    assert doc["n_harmonics"] == ref.harmonics == len(doc["harmonics"])
    assert doc["harmonics"][0]["k"] == 1 and doc["error"] == ref.error
    assert math.isclose(doc["peak"], ref.peak, rel_tol=1e-15)


def test_speed_map_csv_plot_and_crossings(tmp_path, capsys):
    out, png = tmp_path / "map.csv", tmp_path / "map.png"
    status, text, err = run(["periodic", CAM, "--rpm-min", "300", "--rpm-max", "900",
                             "--points", "7", "-o", out, "--plot", png], capsys)
    assert status == 0, err
    ref = speed_map(load(CAM), 300, 900, 7)
    rows = list(csv.DictReader(out.open()))
    assert [float(r["peak_Q"]) for r in rows] == list(ref.peak)
    assert png.stat().st_size > 1000
    assert "k·Ω = ωn" in text
    status, text, _ = run(["periodic", CAM, "--rpm-min", "300", "--rpm-max", "900",
                           "--points", "7", "--json"], capsys)
    doc = json.loads(text)
    assert len(doc["crossings"]) == len(ref.crossings)


def test_periodic_plot_is_written(tmp_path, capsys):
    png = tmp_path / "q.svg"
    status, _, err = run(["periodic", CAM, "--rpm", "450", "--plot", png, "--harmonics", "40"],
                         capsys)
    assert status == 0, err
    assert png.read_text().startswith("<?xml")


def test_a_failing_run_leaves_no_output(tmp_path, capsys):
    out = tmp_path / "q.csv"
    assert_user_error(["periodic", CAM, "--rpm", "600", "-o", out, "--elements", "nope"],
                      capsys, "unknown element 'nope'")
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("args,needle", [
    (["--rpm", "600", "--rpm-min", "1"], "either --rpm"),
    ([], "either --rpm"),
    (["--rpm-min", "500", "--rpm-max", "100"], "--rpm-min < --rpm-max"),
])
def test_bad_speed_options(args, needle, capsys):
    assert_user_error(["periodic", CAM, *args], capsys, needle)


def test_bad_table_is_located(tmp_path, capsys):
    err = assert_user_error(["periodic", EXAMPLES / "bad_lift.mcir", "--rpm", "600"], capsys,
                            "bad_lift.csv:363:5:", "not periodic")
    assert "expected the same displacement" in err


@pytest.mark.parametrize("body,where,needle", [
    ("angle_deg,displacement\n0,0\n180,1\n180,0\n360,0\n", ":4:1:", "repeats"),
    ("angle_deg,displacement\n0,0\n90,1\n180,NaN\n360,0\n", ":4:5:", "finite"),
    ("angle_deg,displacement\n0,0\n90,1\n180,0\n350,0\n", ":5:1:", "one revolution"),
])
def test_bad_tables_from_the_netlist(tmp_path, capsys, body, where, needle):
    shutil.copy(EXAMPLES / "cam_table.mcir", tmp_path / "n.mcir")
    (tmp_path / "lift.csv").write_text(body)
    assert_user_error(["periodic", tmp_path / "n.mcir", "--rpm", "600"], capsys,
                      "lift.csv" + where, needle)


def test_drive_without_motion(capsys):
    """Located at the drive's line (new-user pass, session 28: no file, no line)."""
    assert_user_error(["periodic", EXAMPLES / "drive.mcir", "--rpm", "600"], capsys,
                      "drive.mcir:3:1: error: drive 'V0' has no motion", "expected a motion")


def test_a_rotary_drive_names_its_stroke_unit_and_the_table_its_frequency_unit(tmp_path,
                                                                                capsys):
    """New-user pass, session 28: the header showed stroke=0.3490658503988659 (20 deg, in
    rad) with no unit, and with --unit Hz the 'nearest ωn' column had none."""
    net = tmp_path / "rcam.mcir"
    net.write_text("drive W p 0 motion=modified_sine rise=80 dwell=20 return=80 stroke=20 deg\n"
                   "mass J1 p 0 0.02 kg*m^2\nspring kt p a 3000 N*m/rad\n"
                   "mass J2 a 0 0.15 kg*m^2\ndamper ct a 0 1.2 N*m*s/rad\n")
    status, text, err = run(["periodic", net, "--rpm", "300", "--unit", "Hz"], capsys)
    assert status == 0, err
    assert "stroke=0.3490658503988659 (stroke in rad) at 300 rpm" in text
    assert "nearest ωn [Hz]" in text


@pytest.mark.parametrize("rise", ["1e-320", "5e-324"])
def test_a_rise_too_short_for_float64_is_a_located_error(tmp_path, capsys, rise):
    """Fuzz (issue 23): rise=1e-320 deg made 1/β² underflow to 0 — ZeroDivisionError, exit 1."""
    text = Path(CAM).read_text().replace("rise=120", f"rise={rise}")
    net = tmp_path / "short.mcir"
    net.write_text(text)
    col = text.splitlines()[2].index("rise=") + len("rise=") + 1      # at the value
    assert_user_error(["periodic", net, "--rpm", "600"], capsys,
                      f"short.mcir:3:{col}: error: rise=")
    with pytest.raises(ValueError, match="too short"):
        from mechcirc.motion_laws import cam_cycle

        cam_cycle("polynomial_345", float(rise), 60, 120, 0.1)


def test_a_table_too_large_for_float64_slopes_is_located(tmp_path, capsys):
    """Fuzz (issue 23, seed 3004351): a displacement of 1e308 made scipy's spline raise
    ValueError ('dydx must contain only finite values'), exit 1."""
    lines = Path(CAM).parent.joinpath("lift.csv").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("90,"))
    lines[k] = "90,1e308"
    (tmp_path / "lift.csv").write_text("\n".join(lines) + "\n")
    net = tmp_path / "big.mcir"
    net.write_text(Path(CAM).read_text().replace(
        next(ln for ln in Path(CAM).read_text().splitlines() if ln.startswith("drive")),
        "drive V0 T 0 motion=lift.csv"))
    assert_user_error(["periodic", net, "--rpm", "600"], capsys,
                      f"lift.csv:{k + 1}:4: error: the spline through the table is not finite")


def test_a_circuit_without_resonances_lists_its_harmonics_without_nan(tmp_path, capsys):
    # A mass alone at the drive has no resonance: the table's last two columns were
    # "nan +nan%"; they are dashes now, the harmonics' own numbers as before.
    path = tmp_path / "mass.mcir"
    path.write_text("drive V T 0 motion=cycloidal rise=90 dwell=30 return=90 stroke=10 mm\n"
                    "mass m T 0 2\n")
    status, text, _ = run(["periodic", str(path), "--rpm", "600"], capsys)
    assert status == 0 and "+nan%" not in text and " nan " not in text
    rows = [line.split() for line in text.splitlines() if line.strip().startswith("1 ")]
    assert rows and rows[0][-2:] == ["—", "—"] and float(rows[0][1]) == pytest.approx(62.8319)


def test_a_speed_map_without_resonances_says_it_crosses_none(tmp_path, capsys):
    path = tmp_path / "mass.mcir"
    path.write_text("drive V T 0 motion=cycloidal rise=90 dwell=30 return=90 stroke=10 mm\n"
                    "mass m T 0 2\n")
    status, text, _ = run(["periodic", str(path), "--rpm-min", "200", "--rpm-max", "400",
                           "--points", "3"], capsys)
    assert status == 0 and "(k·Ω = ωn; 0 of 0 with" in text and ": none in this range" in text
