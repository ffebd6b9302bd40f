"""`mechcirc simulate` and `mechcirc crosscheck`."""

import csv
import json
import math

import numpy as np
import pytest

from mechcirc.cli import main
from mechcirc.sley import simulate


def test_simulate_table_beside_paper(capsys):
    assert main(["simulate", "--variant", "7", "--revolutions", "1", "--points", "720"]) == 0
    out = capsys.readouterr().out
    assert "one-side variant 7" in out and "alpha = 10 deg" in out
    line = next(l for l in out.splitlines() if l.startswith("eps4T"))
    assert line.split()[2:] == ["-371", "466", "-371", "466"]


def test_simulate_json_equals_api(capsys):
    assert main(["simulate", "--drive", "both-sides", "--variant", "2", "--revolutions", "1",
                 "--points", "720", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    api = simulate("both-sides", 2, revolutions=1, points_per_revolution=720)
    for k, v in api.extrema.items():
        assert doc["extrema"][k] == pytest.approx(list(v), rel=1e-12)
    assert doc["alpha_deg"] == pytest.approx(10.0)
    assert doc["paper"]["eps4P"] == [-4664, 6822]


def test_simulate_csv_and_plot(tmp_path, capsys):
    out_csv, out_png = tmp_path / "s.csv", tmp_path / "s.png"
    assert main(["simulate", "--variant", "3", "--revolutions", "1", "--points", "360",
                 "--alpha", "30", "--set", "clearance=0.002", "-o", str(out_csv),
                 "--plot", str(out_png)]) == 0
    assert "alpha = 30 deg" in capsys.readouterr().out
    rows = list(csv.reader(l for l in out_csv.read_text().splitlines() if not l.startswith("#")))
    assert rows[0] == ["crank_angle_deg", "eps2P", "eps4P", "eps4T", "M2V", "M4"]
    data = np.array(rows[1:], dtype=float)
    api = simulate("one-side", 3, revolutions=1, points_per_revolution=360,
                   alpha=np.radians(30), clearance=0.002)
    np.testing.assert_allclose(data[:, 2], api.eps4P, rtol=1e-12)
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.csv", "s.png"]


@pytest.mark.parametrize("argv, text", [
    (["simulate", "--set", "omega=0"], "omega must be > 0"),
    (["simulate", "--set", "l2P=0.5"], "cannot be assembled"),
    (["simulate", "--set", "C2"], "NAME=VALUE"),
    (["simulate", "--variant", "9"], "variant must be one of"),
    # --set takes numbers: the layout, the table row and the label are chosen otherwise
    (["simulate", "--set", "drive=1"], ("--set drive: not a numeric parameter; choose the "
                                        "layout with --drive")),
    (["simulate", "--set", "variant=2"], ("--set variant: not a numeric parameter; choose "
                                          "the table row with --variant")),
    (["simulate", "--set", "label=1"], "--set label: not a numeric parameter"),
    # each value is read in its parameter's unit, and a name must be one
    (["simulate", "--set", "clearance=2kN"], ("--set clearance: unit 'kN' is a force; an "
                                              "angle value needs angle")),
    (["simulate", "--set", "I4=25kg"], "unit 'kg' is a mass; a rotary inertia value"),
    (["simulate", "--set", "C2=1e5N/m"], "a rotary spring value needs torsional rigidity"),
    (["simulate", "--set", "i4=3"], "--set i4: no such parameter; did you mean 'I4'?"),
    (["crosscheck", "--theta", "79.0638705730987"], "dead centre"),
])
def test_user_errors_exit_2(argv, text, capsys, tmp_path):
    assert main(argv + ["-o", str(tmp_path / "x.csv")] if argv[0] == "simulate" else argv) == 2
    assert text in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_set_reads_each_value_in_its_parameters_unit():
    """--set converts a unit of the parameter's kind to SI (independent factors here)."""
    import argparse

    from mechcirc.cli.sley_commands import _overrides

    args = argparse.Namespace(alpha=10.0, beat_sign=-1, set=[
        "clearance=0.1deg", "omega=3000rpm", "I4=2500kg*cm^2", "k2=7kg*m^2/s", "l3=37mm",
        "M0=2kN*m", "C4=5e4"])
    from dataclasses import fields

    from mechcirc.sley import SleyParameters
    from mechcirc.sley.models import UNIT_ROLES

    # every numeric parameter has its unit (the text ones are set by --drive/--variant)
    assert set(UNIT_ROLES) | {"drive", "label"} == {f.name for f in fields(SleyParameters)}
    got = _overrides(args)
    want = {"alpha": math.pi / 18, "beat_sign": -1, "clearance": math.pi / 1800,
            "omega": 100 * math.pi, "I4": 0.25, "k2": 7.0, "l3": 0.037, "M0": 2000.0,
            "C4": 5e4}
    assert got.keys() == want.keys()
    for name, value in want.items():
        assert got[name] == pytest.approx(value, rel=1e-15), name


def test_crosscheck_json(cli_once):
    status, out, _ = cli_once(["crosscheck", "--variant", "1", "--json"])
    assert status == 0
    doc = json.loads(out)
    assert all(r["rel_error"] < 1e-9 for r in doc["resonances"])
    assert doc["harmonic"]["rel_error"] < 0.01
    assert doc["ringing"]["rel_error"] < 0.02          # variant 1: no clearance
    assert doc["verdict"] == "agrees" and doc["summary"]["agree"] == 6
    rows = doc["resonances"] + [doc["ringing"]] + doc["harmonic"]["rows"]
    assert all(r["verdict"] == "agrees" and r["rel_error"] <= r["tol"] for r in rows)


def test_crosscheck_line_that_cannot_be_measured_says_why(cli_once):
    # variant 6 one-side: the pulse response rings out before enough zero crossings
    status, out, _ = cli_once(["crosscheck", "--variant", "6"])
    assert status == 0
    assert "(b) ringing after beat-up: cannot be measured: ringing: 2 zero crossing(s)" in out
    assert out.splitlines()[-1] == ("verdict: agrees — 5 of 6 checks agree, 0 disagree beyond "
                                    "their tolerance, 1 cannot be measured")


def test_crosscheck_disagreement_exits_3(monkeypatch, capsys, cli_once):
    """The time-domain amplitudes 1 % off: (c) disagrees, exit 3.  The amplitudes are the
    real ones of the same command (``cli_once``, shared with test_crosscheck_json) looked
    up by frequency rather than integrated again (2.6 s of CPU); a frequency not among
    them is a KeyError, so the patched run must ask for exactly those."""
    import mechcirc.sley.crosscheck as sc

    status, out, _ = cli_once(["crosscheck", "--variant", "1", "--json"])
    assert status == 0
    real = {r["omega"]: r["q0_time"] for r in json.loads(out)["harmonic"]["rows"]}
    monkeypatch.setattr(sc, "forced_amplitude", lambda circuit, w: 1.01 * real[float(w)])
    assert main(["crosscheck", "--variant", "1", "--json"]) == 3
    doc = json.loads(capsys.readouterr().out)
    assert doc["verdict"] == "disagrees" and doc["summary"]["disagree"] == 3


def test_a_warning_is_printed_once(capsys):
    """New-user pass, session 28: 'not yet periodic' came twice, as 'note: warning: ...'
    on stdout and as the command's warning on stderr."""
    assert main(["simulate", "--set", "omega=3000rpm", "--revolutions", "2"]) == 0
    out, err = capsys.readouterr()
    assert (out + err).count("not yet periodic") == 1 and "warning: one-side" in err


def test_changed_parameters_drop_the_paper_columns(capsys):
    """The paper computed its variants at their own parameters: --set omega=120 is not one."""
    assert main(["simulate", "--drive", "one-side", "--variant", "1", "--set", "omega=120",
                 "--revolutions", "2"]) == 0
    out = capsys.readouterr().out
    assert "the paper did not compute this case" in out
    assert "-2319" not in out                     # the paper's eps4T minimum of variant 1
    assert main(["simulate", "--drive", "one-side", "--variant", "1", "--set", "omega=120",
                 "--revolutions", "2", "--json"]) == 0
    assert "paper" not in json.loads(capsys.readouterr().out)
    # a different reading of the beat-up window is still the paper's case
    assert main(["simulate", "--drive", "one-side", "--variant", "1", "--alpha", "40",
                 "--revolutions", "2", "--json"]) == 0
    assert "paper" in json.loads(capsys.readouterr().out)


def test_simulate_variant_all_runs_the_fourteen_presets_and_refuses_one_file(tmp_path, capsys,
                                                                             monkeypatch):
    """--variant all: the 14 presets (Table 1 then Table 2, variants 1-7) with the
    overrides applied to each, each result the one-variant API's; -o/--plot (one
    variant's files) exit 2 and write nothing.  One process (cpu_count patched to 1)."""
    import math

    import mechcirc.sley.simulation as sim
    from cli_helpers import assert_user_error, run

    monkeypatch.setattr(sim.os, "cpu_count", lambda: 1)
    status, out, err = run(["simulate", "--variant", "all", "--revolutions", "1", "--points",
                            "360", "--alpha", "30", "--no-error-estimate", "--json"], capsys)
    assert status == 0, err
    results = json.loads(out)["results"]
    assert [r["parameters"]["label"] for r in results] == [
        f"{d} variant {v}" for d in ("one-side", "both-sides") for v in range(1, 8)]
    assert all(r["parameters"]["alpha"] == pytest.approx(math.radians(30), rel=1e-15)
               for r in results)
    for i, drive, variant in ((0, "one-side", 1), (13, "both-sides", 7)):
        api = simulate(drive, variant, revolutions=1, method="rk4", points_per_revolution=360,
                       alpha=math.radians(30), error_estimate=False)
        for k, v in api.extrema.items():
            assert results[i]["extrema"][k] == pytest.approx(list(v), rel=1e-12)
    for flag in ("-o", "--plot"):
        target = tmp_path / ("t.csv" if flag == "-o" else "t.png")
        assert_user_error(["simulate", "--variant", "all", flag, target], capsys,
                          "-o/--plot need one variant, not --variant all")
        assert not target.exists()
