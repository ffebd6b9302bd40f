"""``mechcirc scene`` and ``mechcirc reduce``: outputs, JSON, exit statuses, atomic files."""

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from mechcirc.scene import build, load_scene
from reference.inputs import STB

ROOT = Path(__file__).resolve().parents[2]
HEALD = ROOT / "examples" / "heald_scene.toml"


def run(argv, capsys):
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def test_scene_theta_writes_the_netlist_of_the_api(tmp_path, capsys):
    out = tmp_path / "h.mcir"
    status, text, err = run(["scene", HEALD, "--theta", "40", "-o", out], capsys)
    assert status == 0, err
    api = build(load_scene(HEALD), math.radians(40.0))
    assert out.read_text() == api.netlist
    written = mechcirc.load(out)
    w = np.geomspace(10.0, 3000.0, 50)
    np.testing.assert_allclose(written.sweep(w).K, api.circuit.sweep(w).K, rtol=1e-14)
    first = min(r.omega for r in api.circuit.resonances() if r.kind == "resonance")
    assert f"{first:.6g}" in text and "node lever3: lever3" in text


def test_scene_theta_json(capsys):
    status, text, err = run(["scene", HEALD, "--theta", "40", "--json", "--reflect", "lever"],
                            capsys)
    assert status == 0, err
    doc = json.loads(text)
    assert doc["parts"]["lever3"] == ["lever3"]
    assert "lever L_mframe" in doc["netlist"]
    assert doc["ratios"]["J1"] == pytest.approx(
        build(load_scene(HEALD), math.radians(40.0)).ratios["J1"], rel=1e-15)


def test_scene_cycle_csv_plot_and_json(tmp_path, capsys):
    csv_path, png = tmp_path / "c.csv", tmp_path / "c.png"
    status, text, err = run(["scene", HEALD, "--cycle", "--points", "12", "--harmonics", "7",
                             "-o", csv_path, "--plot", png, "--json"], capsys)
    assert status == 0, err
    doc = json.loads(text)
    assert len(doc["points"]) == 12 and doc["harmonics"] == list(range(1, 8))
    rows = list(csv.DictReader(csv_path.open()))
    assert len(rows) == 12
    assert float(rows[3]["abs_Q0_h2"]) == pytest.approx(doc["points"][3]["abs_Q0"][1], rel=1e-9)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_scene_errors_exit_2_with_a_located_message(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(HEALD.read_text().replace('point = "M"\nmass = 3.0', 'point = "Z"\nmass = 3.0'))
    status, _, err = run(["scene", bad, "--theta", "10"], capsys)
    assert status == 2
    line = next(n for n, t in enumerate(bad.read_text().splitlines(), 1) if 'point = "Z"' in t)
    assert err.startswith(f"{bad}:{line}:") and "'Z' does not exist" in err
    status, _, err = run(["scene", tmp_path / "none.toml", "--theta", "10"], capsys)
    assert status == 2 and "no such file" in err


def test_scene_at_a_dead_centre_exits_2(capsys):
    from scipy.optimize import brentq

    scene = load_scene(HEALD)
    # crank O0-P and rod P-T in line: lever 1, and everything behind it, stops
    th = np.radians(np.arange(0.0, 360.0, 3.0))
    w = np.array([s.angular_velocities["lever1"] for s in scene.linkage.solve(th)])
    i = int(np.flatnonzero(np.sign(w) != np.sign(np.roll(w, -1)))[0])
    t0 = brentq(lambda t: scene.linkage.solve(t).angular_velocities["lever1"],
                th[i], th[i + 1], xtol=1e-15)
    status, _, err = run(["scene", HEALD, "--theta", repr(math.degrees(t0))], capsys)
    assert status == 2
    assert "dead centre" in err and "at rest" in err


def test_scene_bad_plot_format_writes_nothing(tmp_path, capsys):
    csv_path = tmp_path / "c.csv"
    status, _, err = run(["scene", HEALD, "--cycle", "--points", "4", "-o", csv_path,
                          "--plot", tmp_path / "c.bmpx"], capsys)
    assert status == 2 and "unsupported plot format" in err
    assert not csv_path.exists()


def test_reduce_cli_text_json_and_file(tmp_path, capsys):
    out = tmp_path / "r.mcir"
    status, text, err = run(["reduce", STB, "--band", "10:300", "--tol", "0.01", "-o", out],
                            capsys)
    assert status == 0, err
    assert "measured worst relative error" in text and out.exists()
    status, text, err = run(["reduce", STB, "--band", "10:300", "--tol", "0.01", "--json"],
                            capsys)
    doc = json.loads(text)
    assert doc["error"] <= 0.01 and doc["elements_after"] < doc["elements_before"]
    assert doc["netlist"] == out.read_text()


@pytest.mark.parametrize("band", ["300:10", "10:10", "x:3"])
def test_reduce_bad_band_exits_2(band, capsys):
    status, _, err = run(["reduce", STB, "--band", band, "--tol", "0.01"], capsys)
    assert status == 2 and "band" in err


def test_scene_reduce_uses_the_analysis_table(tmp_path, capsys):
    out = tmp_path / "r.mcir"
    status, text, err = run(["scene", HEALD, "--reduce", "-o", out], capsys)   # θ from the file
    assert status == 0, err
    assert "reduced for the force in kEF" in text and "(reduced)" in text
    reduced = mechcirc.load(out)
    full = build(load_scene(HEALD), math.radians(40.0)).circuit
    w = np.geomspace(30.0, 480.0, 2000)
    a, b = full.sweep(w).force("kEF"), reduced.sweep(w).force("kEF")
    assert np.max(np.abs(b - a) / np.abs(a)) <= 0.01
    assert len(reduced.elements) < len(full.elements)


def test_scene_reduce_without_a_band_exits_2(tmp_path, capsys):
    bare = tmp_path / "bare.toml"
    bare.write_text(HEALD.read_text().split("[analysis]")[0])
    status, _, err = run(["scene", bare, "--theta", "10", "--reduce"], capsys)
    assert status == 2 and "needs band" in err
    status, _, err = run(["scene", bare], capsys)
    assert status == 2 and "give --theta" in err


def test_a_theta_beyond_the_continuation_limit_says_so_not_that_the_linkage_fails(capsys):
    """``scene HEALD --theta 1e9`` said the linkage "cannot be assembled there or passes a
    position where its velocity ratios ... are infinite", then the step limit: the file's
    one crank turns at 60 rad/s, so 100,000 steps of 2° reach 200,000° from the pose; the
    message names θ and that reach, and nothing about assembly."""
    from cli_helpers import assert_user_error

    err = assert_user_error(["scene", HEALD, "--theta", "1e9"], capsys, "θ = 1e+09°",
                            "the limit is 100000", "a path of 200000° from the pose")
    assert "assembled" not in err and "linearised" not in err


def test_a_geared_cycle_map_names_the_shaft_speed_and_its_fundamental(capsys):
    """New-user pass, session 28: the geared six-bar (first crank 20 rad/s, a cycle of two
    turns) printed 'shaft Ω = 10 rad/s', the cycle's fundamental, as the shaft's speed."""
    fnf = Path(__file__).resolve().parents[2] / "examples" / "fnf_sixbar_scene.toml"
    assert cli.main(["scene", str(fnf), "--cycle", "--points", "4", "--harmonics", "2"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].endswith("shaft Ω = 20 rad/s; the cycle of 2 turns repeats at Ω/2 = 10 rad/s")
    assert out[1].endswith("at h·Ω/2:")
