"""``mechcirc transient`` and ``mechcirc crosscheck FILE.mcir``: interface of issue 12 §4."""

import json
from pathlib import Path

import numpy as np
import pytest

from mechcirc import cli
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]
NETLISTS = sorted(REPO.glob("netlists/*.mcir")) + sorted(REPO.glob("examples/*.mcir"))


def run(argv, capsys):
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize("path", NETLISTS, ids=lambda p: p.name)
def test_every_shipped_netlist_runs_transient_and_crosscheck(path, capsys):
    speed = ["--rpm", "600"] if "motion=" in path.read_text() else []   # a cam drive
    status, out, err = run(["transient", path, "--t-end", "0.02", "--dt", "1e-4", "--json",
                            *speed], capsys)
    assert status == 0, err
    doc = json.loads(out)
    assert len(doc["time"]) == 201
    assert set(doc) >= {"time", "nodes", "elements", "drive", "notes"}
    for node in doc["nodes"].values():
        assert len(node["x"]) == 201 and np.all(np.isfinite(node["v"]))
    status, out, err = run(["crosscheck", path, "--json"], capsys)
    assert status == 0, err
    doc = json.loads(out)
    assert doc["verdict"] == "agrees" and doc["summary"]["disagree"] == 0
    assert doc["resonances"] and doc["steady_state"]
    for r in doc["resonances"]:
        assert set(r) >= {"kind", "omega", "ringing_omega_d", "rel_error", "verdict", "tol"}
        # A mode that has faded out of the record (heald_damped's 3066 rad/s, decay
        # 408 1/s) is "cannot be measured", with why; every measured one agrees.
        assert r["verdict"] in ("agrees", "cannot be measured")
        if r["verdict"] == "agrees":
            assert r["rel_error"] < 1e-9          # achieved ≤ 1.3e-13 on these
    assert sum(r["verdict"] == "agrees" for r in doc["resonances"]) >= \
        len(doc["resonances"]) / 2
    for s in doc["steady_state"]:
        assert set(s) >= {"omega", "expected", "measured", "rel_error", "verdict"}
        assert s["verdict"] == "agrees"
        assert s["rel_error"] < 1e-9              # achieved ≤ 1.6e-13


def test_crosscheck_says_disagrees_and_exits_3(monkeypatch, capsys):
    """A time domain that is wrong (here: the steady state not started periodic, so the
    record still rings) is said on its line and in the verdict, with exit status 3."""
    import mechcirc.transient as tr
    import mechcirc.transient.simulate as sim

    monkeypatch.setattr(sim, "periodic_start", lambda ss, *a: np.zeros(ss.size))
    # The text and the --json run print one result (its transients computed once, by the
    # first run, not twice: 2.7 s of CPU); each run still parses, loads and exits itself.
    real, done = tr.crosscheck, []

    def once(circuit, **kw):
        done[:] = done or [real(circuit, **kw)]
        return done[0]

    monkeypatch.setattr(tr, "crosscheck", once)
    path = REPO / "netlists/stb_heald.mcir"
    status, out, _ = run(["crosscheck", path], capsys)
    assert status == 3
    assert "DISAGREES (> tol" in out and out.splitlines()[-1].startswith("verdict: DISAGREES")
    status, out, _ = run(["crosscheck", path, "--json"], capsys)
    assert status == 3 and json.loads(out)["verdict"] == "disagrees" and len(done) == 1


def test_crosscheck_of_a_netlist_refuses_netlist_output(tmp_path, capsys):
    """--netlist writes the netlist built from a scene or preset; with a netlist FILE there
    is none, so the option is refused (exit 2, nothing written) rather than ignored."""
    out_path = tmp_path / "used.mcir"
    status, out, err = run(["crosscheck", REPO / "netlists/stb_heald.mcir",
                            "--netlist", out_path], capsys)
    assert status == 2 and "--netlist" in err and "is a netlist already" in err
    assert not out_path.exists() and out == ""


def test_crosscheck_unmeasurable_line_says_why(tmp_path, capsys):
    # the massless damped drive node's first-order mode (ω = k1/c1 = 6000) rings not at all
    net = tmp_path / "chain.mcir"
    net.write_text("drive V s 0 velocity=1\nspring k1 s a 12000\ndamper c1 s a 2\n"
                   "mass m1 a 0 1.3\nspring k2 a b 14000\ndamper c2 a b 2\nmass m2 b 0 1.6\n")
    status, out, _ = run(["crosscheck", net, "--omega-max", "1e4"], capsys)
    assert status == 0
    assert "cannot be measured: overdamped" in out
    assert out.splitlines()[-1].startswith("verdict: agrees") and "1 cannot be measured" in out


def test_transient_outputs_csv_and_plot(tmp_path, capsys):
    csv_path, png = tmp_path / "o.csv", tmp_path / "o.png"
    status, out, err = run(["transient", REPO / "examples/msl_backlash.mcir", "--t-end", "0.1",
                            "--dt", "1e-3", "-o", csv_path, "--plot", png], capsys)
    assert status == 0, err
    rows = csv_path.read_text().splitlines()
    assert rows[0].startswith("t,x(phi),x(phi2)") and len(rows) == 102
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert "Dormand-Prince" in out


def test_transient_plot_element_panel(tmp_path, capsys):
    png = tmp_path / "e.png"
    net = REPO / "examples/msl_backlash.mcir"
    status, _, err = run(["transient", net, "--t-end", "0.1", "--dt", "1e-3", "--plot", png,
                          "--element", "eb", "--element", "sd"], capsys)
    assert status == 0, err
    assert png.read_bytes()[:4] == b"\x89PNG"
    bad = tmp_path / "bad.png"
    status, _, err = run(["transient", net, "--t-end", "0.1", "--plot", bad,
                          "--element", "nope"], capsys)
    assert status == 2 and "unknown element 'nope'" in err and not bad.exists()
    status, _, err = run(["transient", net, "--t-end", "0.1", "--element", "eb"], capsys)
    assert status == 2 and "--plot" in err


def test_transient_drive_waveforms_and_json_drive_key(tmp_path, capsys):
    net = tmp_path / "v.mcir"
    net.write_text("drive V b 0 velocity=0.2\nspring k b a 900\nmass m a 0 4\n")
    status, out, _ = run(["transient", net, "--t-end", "0.1", "--waveform", "harmonic:30",
                          "--json"], capsys)
    assert status == 0
    assert "force" in json.loads(out)["drive"]
    samples = tmp_path / "d.csv"
    samples.write_text("t,v\n0,0\n0.1,1\n")
    status, out, _ = run(["transient", net, "--t-end", "0.1", "--waveform", f"csv:{samples}",
                          "--json"], capsys)
    assert status == 0


@pytest.mark.parametrize("argv, message", [
    (["--t-end", "-1"], "--t-end"),
    (["--t-end", "1", "--waveform", "harmonic:-3"], "ω"),
    (["--t-end", "1", "--waveform", "square"], "not understood"),
    (["--t-end", "1", "--waveform", "csv:/nonexistent.csv"], "nonexistent"),
    (["--t-end", "1", "--dt", "1e-12"], "limit"),
    # issue 23 item 4: OverflowError (exit 1) and NaN labelled "exact" (exit 0) before
    (["--t-end", "1", "--dt", "5e-324"], "below 1e-300 s"),
    (["--t-end", "1e10", "--dt", "1e-300"], "t_end/dt = inf samples, the limit is 2000000"),
    (["--t-end", "1e300", "--waveform", "step"], "the transient is not finite from t = 5e+296 s"),
    # issue 24: --drive names the sley's side (simulate); the waveform's old spelling says so
    (["--t-end", "1", "--drive", "step"], "--drive was renamed --waveform"),
])
def test_transient_user_errors_exit_2(argv, message, capsys, tmp_path):
    out_csv = tmp_path / "never.csv"
    status, _, err = run(["transient", REPO / "netlists/stb_heald.mcir", *argv, "-o", out_csv],
                         capsys)
    assert status == 2
    assert message in err
    assert not out_csv.exists() and not list(tmp_path.iterdir())


def test_driveless_netlist_transient_ok_sweep_and_crosscheck_refuse(tmp_path, capsys):
    net = tmp_path / "free.mcir"
    net.write_text("mass m a 0 1\nspring k a 0 100\n.ic a x=0.1\n")
    status, out, _ = run(["transient", net, "--t-end", "1", "--json"], capsys)
    assert status == 0
    x = np.array(json.loads(out)["nodes"]["a"]["x"])
    t = np.array(json.loads(out)["time"])
    assert np.abs(x - 0.1 * np.cos(10 * t)).max() < 1e-13
    for cmd in (["sweep", net, "--omega-min", "1", "--omega-max", "10"], ["crosscheck", net]):
        status, _, err = run(cmd, capsys)
        assert status == 2 and "no drive" in err


def test_sley_crosscheck_still_works_without_file(cli_once):
    # the same command line as tests/sley/test_cli_sley.py checks in full: run once
    status, out, _ = cli_once(["crosscheck", "--variant", "1", "--json"])
    assert status == 0
    assert "ringing" in json.loads(out)


def test_sweep_warns_backlash_is_linearised(capsys):
    status, _, err = run(["sweep", REPO / "examples/msl_backlash.mcir", "--omega-min", "1",
                          "--omega-max", "100", "--points", "5"], capsys)
    assert status == 0
    assert "linearised" in err


def test_crosscheck_reports_progress_per_transient_run():
    """One update per transient run, and the total announced matches the runs made."""
    import io

    import mechcirc
    from mechcirc.progress import Progress
    from mechcirc.transient import crosscheck

    c = mechcirc.load(STB)
    bar = Progress(0, "x", stream=io.StringIO(), enabled=True, delay=0.0)
    with bar:
        result = crosscheck(c, progress=bar)
    kinds = {r["kind"] for r in result.resonances}         # one record per kind here
    assert bar.total == len(kinds) + len(result.steady_state) == bar.done
    assert "[" in bar.stream.getvalue()            # the bar was drawn


# FILE:LINE:COL: error: as every input file's (the column and a row of three values
# added in session 28: "d.csv:3: 'x','2' are not two numbers", and 0,1,3 read as 0,1)
@pytest.mark.parametrize("content, message", [
    ("0\n1\n", "d.csv:1:3: error: 1 column(s) (expected two columns time,value)"),
    ("time,value\n0,1\nx,2\n", "d.csv:3:1: error: 'x' is not a number (expected time,value"),
    ("time,value\n0,1\n1,y\n", "d.csv:3:3: error: 'y' is not a number"),
    ("0,1\n1,2,3\n", "d.csv:2:5: error: 3 column(s) (expected two columns time,value)"),
    # located at the value (it was at the row's first column, the new-user pass)
    ("0,nan\n1,2\n", "d.csv:1:3: error: 'nan' is not finite"),
    ("0,1\ninf,2\n", "d.csv:2:1: error: 'inf' is not finite"),
    ("0,1\n1,2\n0.5,3\n", "d.csv:3:1: error: time 0.5 is not after the previous 1"),
    ("time,value\n0,1\n", "d.csv: needs at least two samples (time,value)"),
])
def test_bad_drive_csv_files_exit_2_at_their_line(content, message, capsys, tmp_path):
    from cli_helpers import assert_user_error

    (tmp_path / "d.csv").write_text(content)
    out_csv = tmp_path / "never.csv"
    assert_user_error(["transient", REPO / "netlists/stb_heald.mcir", "--t-end", "1",
                       "--waveform", f"csv:{tmp_path / 'd.csv'}", "-o", out_csv], capsys, message)
    assert not out_csv.exists()
