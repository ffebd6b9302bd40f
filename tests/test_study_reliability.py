"""Studies that cannot mix or leak: spec records, resume checks, the output lock, Dask
start-up errors, provenance and units, samples (Latin hypercube, Sobol, a user's file)
and located errors in sample files (issue 21 §5-6, issue 23 §6)."""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import assert_user_error, run
from reference.inputs import STB

from mechcirc.errors import MechcircError, NetlistError
from mechcirc.study import (
    column_units,
    journal_path,
    load_spec,
    parse_spec,
    run_study,
    sidecar_path,
)

REPO = Path(__file__).resolve().parents[1]
OMEGA = {"min": 10, "max": 2000, "points": 30, "log": True}


def spec_file(tmp_path, grid="eta1 = [0.7, 0.8]", name="s.toml", extra=""):
    path = tmp_path / name
    path.write_text(f'netlist = "{STB}"\n[omega]\nmin = 10\nmax = 2000\npoints = 30\n'
                    f'log = true\n{extra}[grid]\n{grid}\n')
    return path


def files(folder):
    return sorted(p.name for p in Path(folder).iterdir())


# ------------------------------------------------------------------ resume checks the spec
def test_resume_refuses_a_table_of_another_grid_and_names_the_change(tmp_path, capsys):
    a = spec_file(tmp_path, "eta1 = [0.7, 0.8]", "a.toml")
    b = spec_file(tmp_path, "eta1 = [0.1, 0.2]", "b.toml")
    out = tmp_path / "r.csv"
    assert run(["study", a, "-o", out, "--workers", "1"], capsys)[0] == 0
    before = out.read_bytes()
    assert_user_error(["study", b, "-o", out, "--resume", "--workers", "1"], capsys,
                      "r.csv was made from another spec",
                      "sample.axes.eta1 was [0.7, 0.8], now [0.1, 0.2]", "cannot resume")
    assert out.read_bytes() == before
    assert not Path(journal_path(out)).exists() and not Path(f"{out}.lock").exists()
    # the same spec resumes: every row kept
    status, stdout, _ = run(["study", a, "-o", out, "--resume", "--workers", "1"], capsys)
    assert status == 0 and "2 point(s) kept" in stdout
    assert out.read_bytes() == before


@pytest.mark.parametrize("old, new, change", [
    ("points = 30", "points = 31", "omega.points was 30, now 31"),
    ("max = 2000", "max = 2001", "omega.max was 2000.0, now 2001.0"),
    ("log = true", "log = false", "omega.log was True, now False"),
])
def test_resume_from_a_journal_of_another_spec_is_refused(tmp_path, old, new, change):
    a = spec_file(tmp_path)
    out = tmp_path / "r.csv"
    calls = []

    def stop(n):
        calls.append(n)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(load_spec(a), output=out, workers=1, batch_size=1, on_rows=stop)
    journal = Path(journal_path(out))
    kept = journal.read_bytes()
    a.write_text(a.read_text().replace(old, new))
    with pytest.raises(MechcircError, match="was made from another spec: " + change):
        run_study(load_spec(a), output=out, workers=1, resume=True)
    assert journal.read_bytes() == kept and not out.exists()


def test_resume_notices_an_edited_netlist(tmp_path):
    net = tmp_path / "n.mcir"
    net.write_text(".param m=2\nmass m1 a 0 m\nspring k a 0 100\ndrive V a 0 velocity=1\n")
    spec = tmp_path / "s.toml"
    spec.write_text('netlist = "n.mcir"\nanalysis = "resonances"\n[grid]\nm = [1.0, 2.0]\n')
    out = tmp_path / "r.csv"
    run_study(load_spec(spec), output=out, workers=1)
    net.write_text(net.read_text().replace("100", "200"))
    with pytest.raises(MechcircError, match=r"netlist_sha256 was [0-9a-f]{12}…, now"):
        run_study(load_spec(spec), output=out, workers=1, resume=True)


def test_resume_refuses_a_table_without_a_spec_record(tmp_path):
    a = spec_file(tmp_path)
    out = tmp_path / "r.csv"
    run_study(load_spec(a), output=out, workers=1)
    os.unlink(sidecar_path(out))
    with pytest.raises(MechcircError, match="records no study spec"):
        run_study(load_spec(a), output=out, workers=1, resume=True)


def test_a_journal_row_with_other_parameter_values_is_run_again(tmp_path):
    from mechcirc.study.journal import _crc

    spec = load_spec(spec_file(tmp_path, "eta1 = [0.7, 0.8, 0.9]"))
    out = tmp_path / "r.csv"
    full = run_study(spec, output=tmp_path / "full.csv", workers=1)
    seen = []

    def stop(n):
        seen.append(n)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(spec, output=out, workers=1, batch_size=1, on_rows=stop)
    journal = Path(journal_path(out))
    lines = journal.read_text().splitlines()
    fields = next(csv.reader([lines[3]]))[:-1]
    assert fields[1] == "0.8"
    fields[1] = "0.85"                      # a valid row (checksum and all) of another point
    lines[3] = ",".join([*fields, _crc(fields)])
    journal.write_text("\n".join(lines) + "\n")
    r = run_study(spec, output=out, workers=1, resume=True)
    assert r.skipped == 1
    assert [row["eta1"] for row in r.rows] == [0.7, 0.8, 0.9]
    assert out.read_bytes() == (tmp_path / "full.csv").read_bytes()
    assert r.rows == full.rows


# ------------------------------------------------------------------ the output lock
HOLD = """
import sys
from mechcirc.study.executors import _lock
with _lock(sys.argv[1]):
    print("held", flush=True)
    sys.stdin.read()
"""


def _holder(out):
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(REPO)})
    assert proc.stdout.readline() == "held\n"
    return proc


@pytest.mark.skipif(sys.platform == "win32", reason="fcntl")
def test_a_second_writer_of_the_same_output_is_refused(tmp_path, capsys):
    a = spec_file(tmp_path)
    out = tmp_path / "r.csv"
    holder = _holder(out)
    try:
        assert_user_error(["study", a, "-o", out, "--workers", "1"], capsys,
                          "r.csv is being written by another study",
                          f"pid {holder.pid} on ")
        assert files(tmp_path) == ["r.csv.lock", "s.toml"]      # nothing else written
    finally:
        holder.stdin.close()
        holder.wait()
    assert files(tmp_path) == ["s.toml"]                        # the holder removed it
    assert run(["study", a, "-o", out, "--workers", "1"], capsys)[0] == 0
    assert files(tmp_path) == ["r.csv", "r.csv.meta.json", "s.toml"]


@pytest.mark.skipif(sys.platform == "win32", reason="fcntl")
def test_the_lock_of_a_killed_study_is_taken_over(tmp_path, capsys):
    a = spec_file(tmp_path)
    out = tmp_path / "r.csv"
    holder = _holder(out)
    holder.kill()                           # SIGKILL: no clean-up, the lock file stays
    holder.wait()
    holder.stdin.close()
    lock = Path(f"{out}.lock")
    assert lock.read_text().startswith(f"pid {holder.pid} on ")
    assert run(["study", a, "-o", out, "--workers", "1"], capsys)[0] == 0
    assert not lock.exists() and out.exists()


# ------------------------------------------------------------------ Dask start-up
def test_a_scheduler_without_workers_is_a_user_error_and_leaves_no_files(tmp_path, capsys):
    import distributed  # the test extra installs it: CI runs this
    a = spec_file(tmp_path)
    out = tmp_path / "r.csv"
    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=":0") as cluster:
        assert_user_error(["study", a, "-o", out, "--scheduler", cluster.scheduler_address,
                           "--connect-timeout", "0.5"], capsys,
                          f"the Dask scheduler at {cluster.scheduler_address} has no workers",
                          "within 0.5 s")
    assert files(tmp_path) == ["s.toml"]


def test_an_unreachable_scheduler_leaves_no_files(tmp_path, capsys):
    a = spec_file(tmp_path)
    assert_user_error(["study", a, "-o", tmp_path / "r.csv", "--scheduler",
                       "tcp://127.0.0.1:9", "--connect-timeout", "1"], capsys,
                      "cannot reach the Dask scheduler")
    assert files(tmp_path) == ["s.toml"]
    assert_user_error(["study", a, "--connect-timeout", "0"], capsys, "--connect-timeout")


# ------------------------------------------------------------------ provenance and units
def test_csv_output_records_the_spec_and_every_columns_unit(tmp_path):
    net = tmp_path / "n.mcir"
    net.write_text(".param m=2 k=100 r=0.5 x=1\nmass m1 a 0 m\nspring s a 0 {k*x}\n"
                   "lever L a 0 b 0 ratio=r\nmass m2 b 0 1\ndrive V a 0 velocity=1\n")
    path = tmp_path / "s.toml"
    text = ('netlist = "n.mcir"\n[omega]\nmin = 1\nmax = 10\npoints = 5\n'
            '[grid]\nm = [1.0, 2.0]\nr = [0.5]\nx = [1.0]\n')
    path.write_text(text)
    spec = load_spec(path)
    out = tmp_path / "r.csv"
    run_study(spec, output=out, workers=1)
    record = json.loads(Path(sidecar_path(out)).read_text())
    assert record["spec_text"] == text and record["spec_file"] == str(path)
    assert record["spec_sha256"] == spec.sha256
    # the hash is of the canonical spec as recorded: recomputed here from the record
    import hashlib
    canonical = json.dumps(record["spec"], sort_keys=True, separators=(",", ":"))
    assert hashlib.sha256(canonical.encode()).hexdigest() == spec.sha256
    with open(out, newline="") as fh:
        header = next(csv.reader(fh))
    assert list(record["units"]) == header
    assert record["units"] == {
        "index": "1", "m": "kg", "r": "1", "x": None, "status": "", "error": "",
        "K_abs_min": "m/(N·s)", "omega_at_K_min": "rad/s", "K_abs_max": "m/(N·s)",
        "omega_at_K_max": "rad/s", "Q0_abs_max": "N", "omega_at_Q0_max": "rad/s",
        "n_flagged": "1"}


@pytest.mark.parametrize("data", [
    {"analysis": "resonances", "netlist": str(STB), "resonances": 2},
    {"analysis": "simulate", "sley": {"drive": "one-side"}},
    {"analysis": "simulate", "sley": {"drive": "both-sides"}},
])
def test_every_column_of_every_analysis_has_a_unit(data):
    grid = {"omega": [100.0], "C2": [5e4]} if data["analysis"] == "simulate" else \
        {"eta1": [0.8]}
    spec = parse_spec({**data, "grid": grid})
    units = column_units(spec)
    assert list(units) == spec.columns
    assert None not in [units[c] for c in spec.columns if c not in spec.params]
    if data["analysis"] == "simulate":
        assert units["omega"] == "rad/s" and units["C2"] == "N·m/rad"
        assert units["eps4T_min"] == "rad/s²" and units["M2V_max"] == "N·m"
    else:
        assert units["resonance_2"] == units["antiresonance_1"] == "rad/s"


def test_a_rotary_drive_gives_the_k_and_q0_columns_rotary_units(tmp_path):
    net = tmp_path / "rot.mcir"
    net.write_text(".param J=0.2\ndrive W s 0 velocity=2 rad/s\nspring k s a 4e3 N*m/rad\n"
                   "mass J a 0 J kg*m^2\n")
    spec = parse_spec({"netlist": str(net), "analysis": "sweep",
                       "omega": {"min": 1, "max": 1e3, "points": 5}, "grid": {"J": [0.1]}})
    units = column_units(spec)
    assert units["K_abs_min"] == units["K_abs_max"] == "rad/(N·m·s)"
    assert units["Q0_abs_max"] == "N·m" and units["omega_at_K_max"] == "rad/s"


def test_parquet_output_records_the_spec_and_units(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet", reason="pyarrow is not installed")
    spec = load_spec(spec_file(tmp_path))
    out = tmp_path / "r.parquet"
    run_study(spec, output=out, workers=1)
    schema = pq.read_schema(out)
    record = json.loads(schema.metadata[b"mechcirc"])
    assert record["spec_sha256"] == spec.sha256 and record["units"]["K_abs_max"] == "m/(N·s)"
    assert schema.field("omega_at_Q0_max").metadata == {b"unit": b"rad/s"}
    assert files(tmp_path) == ["r.parquet", "s.toml"]
    assert run_study(spec, output=out, workers=1, resume=True).skipped == 2
    other = load_spec(spec_file(tmp_path, "eta1 = [0.7, 0.9]"))
    with pytest.raises(MechcircError, match="sample.axes.eta1 was"):
        run_study(other, output=out, workers=1, resume=True)


# ------------------------------------------------------------------ samples
def _sample_spec(method, n, seed=1, **extra):
    return parse_spec({"netlist": str(STB), "analysis": "resonances",
                       "sample": {"method": method, "n": n, "seed": seed, **extra,
                                  "params": {"eta1": {"min": 0.6, "max": 1.0},
                                             "eta4": {"min": 0.5, "max": 2.0, "log": True}}}})


def _unit_cube(spec):
    """The points mapped back to [0, 1)² (eta4 on its log scale), independently of the code."""
    e1, e4 = np.array(spec.points).T
    return np.column_stack([(e1 - 0.6) / 0.4, np.log(e4 / 0.5) / np.log(4.0)])


@pytest.mark.parametrize("n", [7, 50])
def test_latin_hypercube_puts_one_point_in_each_stratum(n):
    spec = _sample_spec("latin-hypercube", n)
    u = _unit_cube(spec)
    for j in range(2):
        assert sorted(np.floor(u[:, j] * n).astype(int)) == list(range(n))
    assert spec.points == _sample_spec("latin-hypercube", n).points       # seeded
    assert spec.points != _sample_spec("latin-hypercube", n, seed=2).points


@pytest.mark.parametrize("m", [4, 6])
def test_sobol_points_are_a_net(m):
    n = 2 ** m
    spec = _sample_spec("sobol", n)
    u = _unit_cube(spec)
    assert np.all((u >= 0) & (u < 1))
    # every 1-D projection of the first 2^m points of a (scrambled) Sobol sequence
    # has one point in each interval [k/2^m, (k+1)/2^m)
    for j in range(2):
        assert sorted(np.floor(u[:, j] * n).astype(int)) == list(range(n))
    # and the 2-D elementary boxes of 2^(m/2) × 2^(m/2) hold one point each
    h = 2 ** (m // 2)
    boxes = np.floor(u[:, 0] * h).astype(int) * h + np.floor(u[:, 1] * h).astype(int)
    assert sorted(boxes) == list(range(n))
    assert spec.points == _sample_spec("sobol", n).points


def test_sample_random_is_the_random_table():
    ranges = {"eta1": {"min": 0.6, "max": 1.0}}
    a = parse_spec({"netlist": str(STB), "omega": OMEGA,
                    "random": {"n": 5, "seed": 3, "params": ranges}})
    b = parse_spec({"netlist": str(STB), "omega": OMEGA,
                    "sample": {"method": "random", "n": 5, "seed": 3, "params": ranges}})
    assert a.points == b.points and a.canonical == b.canonical


def test_a_sample_file_gives_the_grids_rows(tmp_path):
    (tmp_path / "d.csv").write_text("eta1,eta3\n0.7,0.8\n0.7, 1.0\n\n0.8,0.8\n")
    path = tmp_path / "s.toml"
    path.write_text(f'netlist = "{STB}"\n[omega]\nmin = 10\nmax = 2000\npoints = 30\n'
                    '[sample]\nfile = "d.csv"\n')
    spec = load_spec(path)
    assert spec.params == ("eta1", "eta3")
    assert spec.points == ((0.7, 0.8), (0.7, 1.0), (0.8, 0.8))
    grid = parse_spec({"netlist": str(STB), "omega": {"min": 10, "max": 2000, "points": 30},
                       "grid": {"eta1": [0.7, 0.8], "eta3": [0.8, 1.0]}})
    by_grid = {(r["eta1"], r["eta3"]): r for r in run_study(grid, workers=1).rows}
    for r in run_study(spec, workers=1).rows:
        expect = by_grid[(r["eta1"], r["eta3"])]
        assert {k: v for k, v in r.items() if k != "index"} == \
            {k: v for k, v in expect.items() if k != "index"}
    # the file's content is part of the spec: editing it changes the hash
    before = spec.sha256
    (tmp_path / "d.csv").write_text("eta1,eta3\n0.7,0.8\n0.7,1.0\n0.8,0.9\n")
    assert load_spec(path).sha256 != before


SIMPLE = ".param m=2 k=100\nmass m1 a 0 m\nspring s a 0 {2*k}\ndrive V a 0 velocity=1\n"


@pytest.mark.parametrize("content, line, col, fragment", [
    ("m,k\n1,nan\n", 2, 3, "column k: 'nan' is not a finite number"),
    ("m,k\n1,2\n3,abc\n", 3, 3, "column k: 'abc' is not a finite number"),
    ("m,k\n1,2\n-1,2\n", 3, 1, ("column m: -1 is not allowed: m is the mass of 'm1', "
                               "which must be > 0")),
    ("m,k\n1,2\n0,2\n", 3, 1, "m is the mass of 'm1'"),
    ("m,kk\n1,2\n", 1, 3, "column 'kk' is not a .param of the netlist; did you mean 'k'?"),
    ("m,k\n1,2\n3\n", 3, 1, "1 values, the header names 2 columns (no value for k)"),
    ("m,k\n1,2,3\n", 2, 5, "3 values, the header names 2 columns"),
    ("m,,k\n1,2,3\n", 1, 3, "column 2 has no name"),
    ("m,m\n1,2\n", 1, 3, "column 'm' appears twice"),
    ("m,k\n", 0, 0, "has a header but no rows of values"),
    ("m,k\n1,\n", 2, 3, "column k: '' is not a finite number"),
])
def test_bad_sample_files_are_located_and_write_nothing(tmp_path, capsys, content, line, col,
                                                        fragment):
    (tmp_path / "n.mcir").write_text(SIMPLE)
    (tmp_path / "d.csv").write_text(content)
    spec = tmp_path / "s.toml"
    spec.write_text('netlist = "n.mcir"\nanalysis = "resonances"\n[sample]\nfile = "d.csv"\n')
    with pytest.raises(NetlistError) as info:
        load_spec(spec)
    assert fragment in info.value.message
    assert (info.value.source, info.value.line, info.value.col) == \
        (str(tmp_path / "d.csv"), line, col)
    assert_user_error(["study", spec, "-o", tmp_path / "r.csv"], capsys, fragment)
    assert files(tmp_path) == ["d.csv", "n.mcir", "s.toml"]


def test_a_parquet_sample_file(tmp_path):
    pa = pytest.importorskip("pyarrow", reason="pyarrow is not installed")
    import pyarrow.parquet as pq

    (tmp_path / "n.mcir").write_text(SIMPLE)
    spec = tmp_path / "s.toml"
    spec.write_text('netlist = "n.mcir"\nanalysis = "resonances"\n[sample]\n'
                    'file = "d.parquet"\n')
    pq.write_table(pa.table({"m": [1.0, 2.0, 3.0], "k": [50, 100, 200]}),
                   tmp_path / "d.parquet")
    assert load_spec(spec).points == ((1.0, 50), (2.0, 100), (3.0, 200))
    pq.write_table(pa.table({"m": [1.0, float("nan")], "k": [50.0, 100.0]}),
                   tmp_path / "d.parquet")
    with pytest.raises(NetlistError, match="column m: nan is not a finite number") as info:
        load_spec(spec)
    assert (info.value.line, info.value.col) == (3, 1)


@pytest.mark.parametrize("data, fragment", [
    ({"netlst": "x"}, "unknown top-level key 'netlst'; did you mean 'netlist'?"),
    ({"sample": {"methd": "sobol"}}, "unknown key 'methd' in [sample]; did you mean 'method'?"),
    ({"sample": {"method": "sobool", "n": 4, "params": {"eta1": {"min": 1, "max": 2}}}},
     "did you mean 'sobol'?"),
    ({"sample": {"method": "sobol", "n": 4, "seed": -1,
                 "params": {"eta1": {"min": 1, "max": 2}}}}, "sample.seed must be an integer"),
    ({"sample": {"file": "d.csv", "n": 3}}, "[sample] with file takes no 'n'"),
    ({"grid": {"eta5": [1.0]}}, "eta5 is not a .param of"),
    ({"grid": {"eta1": [1.0]}, "sample": {"file": "d.csv"}}, "exactly one of"),
    ({"analysis": "resonance", "grid": {"eta1": [1.0]}}, "did you mean 'resonances'?"),
    ({"grid": {"eta1": {"mn": 1, "max": 2, "num": 3}}}, "got max, mn, num; did you mean 'min'?"),
    ({"sample": {"n": 3, "params": {"eta1": {"mni": 1, "max": 2}}}},
     "sample.params.eta1 must be {min, max[, log]}: unknown key 'mni'; did you mean 'min'?"),
])
def test_bad_spec_keys_suggest_the_nearest(data, fragment):
    base = {"netlist": str(STB), "omega": OMEGA, "grid": {"eta1": [0.8]}}
    if "sample" in data:
        base.pop("grid")
    with pytest.raises(MechcircError) as info:
        parse_spec({**base, **data}, source="t.toml")
    assert fragment in str(info.value)


@pytest.mark.parametrize("body, where", [
    ("[grid]\n# the lever\neta1 = [0.8]\n\nkk = [2.0]\n", (8, 1)),
    ("grid.eta1 = [0.8]\ngrid.zz = [1.5]\n", (5, 6)),
    ("[sample]\nn = 4\n[sample.params]\neta1 = {min=1, max=2}\nqq = {min=1, max=2}\n", (8, 1)),
])
def test_a_parameter_that_is_not_a_param_is_located_at_its_key(body, where, tmp_path):
    """New-user pass, session 28: reported at the table's header (4:2), and a dotted key
    without a line at all."""
    spec = tmp_path / "s.toml"
    spec.write_text(f'netlist = "{STB}"\nomega = {{min = 1, max = 10, points = 3}}\n'
                    f'analysis = "sweep"\n{body}')
    with pytest.raises(NetlistError, match="is not a .param of") as info:
        load_spec(spec)
    assert (info.value.line, info.value.col) == where, str(info.value)


# ------------------------------------------------------------------ issue 23 §6
def test_a_file_that_is_not_a_netlist_is_not_quoted(tmp_path, capsys):
    secret = tmp_path / "shadow"
    secret.write_text("root:$6$SECRETHASH:19000:0:99999:7:::\nbin:*:19000:0:99999:7:::\n")
    spec = tmp_path / "s.toml"
    spec.write_text(f'netlist = "{secret}"\n[omega]\nmin = 1\nmax = 10\npoints = 3\n'
                    '[grid]\neta1 = [0.8]\n')
    err = assert_user_error(["study", spec, "--workers", "1"], capsys,
                            f"s.toml:1:1: error: netlist '{secret}' is not a netlist: its first "
                            "statement (line 1) does not begin with one of")
    assert "SECRET" not in err and "99999" not in err
    # a netlist with a fault is still quoted: it is the user's own netlist
    net = tmp_path / "n.mcir"
    net.write_text("# a comment\n.param m=2\nmas m1 a 0 m\ndrive V a 0 velocity=1\n")
    spec.write_text('netlist = "n.mcir"\nanalysis = "resonances"\n[grid]\nm = [1.0]\n')
    assert_user_error(["study", spec], capsys, "n.mcir:3:1: error: unknown keyword 'mas'")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux /proc")
def test_worker_processes_do_not_hold_the_output_lock(tmp_path):
    """A flock belongs to every copy of its descriptor: forked workers close theirs,
    so the lock of a killed study does not live on in its workers."""
    spec = load_spec(spec_file(tmp_path, "eta1 = [0.6, 0.7, 0.8, 0.9]"))
    out = tmp_path / "r.csv"
    lock = str(tmp_path / "r.csv.lock")
    seen = []

    def holders(n):
        me = os.getpid()
        for pid in os.listdir("/proc"):
            if not pid.isdigit():
                continue
            try:
                with open(f"/proc/{pid}/stat") as fh:
                    ppid = int(fh.read().rsplit(")", 1)[1].split()[1])
                if ppid != me:
                    continue
                fds = [os.readlink(f"/proc/{pid}/fd/{fd}")
                       for fd in os.listdir(f"/proc/{pid}/fd")]
            except OSError:
                continue
            seen.append((pid, lock in fds))

    r = run_study(spec, output=out, workers=2, batch_size=1, on_rows=holders)
    assert r.executor == "local"
    assert seen and not any(held for _, held in seen), seen


def test_a_parameters_unit_is_the_one_written_after_it(tmp_path):
    net = tmp_path / "n.mcir"
    net.write_text(".param m=250 k=5 v=100 c=3 x=2\nmass m1 a 0 m g\n"
                   "spring s a 0 k N/mm  # a comment\ndamper d a 0 c\nspring s2 a 0 {x*k} N/mm\n"
                   "drive V a 0 velocity=v mm/s\n")
    spec = parse_spec({"netlist": str(net), "analysis": "resonances",
                       "grid": {"m": [250.0], "k": [5.0], "v": [100.0], "c": [3.0],
                                "x": [2.0]}})
    assert spec.param_units == ("g", "N/mm", "mm/s", "N·s/m", None)


def test_rows_of_another_computation_are_not_resumed(tmp_path, monkeypatch):
    from mechcirc.study import spec as study

    a = spec_file(tmp_path)
    out = tmp_path / "r.csv"
    run_study(load_spec(a), output=out, workers=1)
    monkeypatch.setattr(study, "ROWS_VERSION", study.ROWS_VERSION + 1)
    with pytest.raises(MechcircError, match=f"rows was {study.ROWS_VERSION - 1}, now "
                                            f"{study.ROWS_VERSION}"):
        run_study(load_spec(a), output=out, workers=1, resume=True)


def test_a_sample_file_that_is_not_a_table_is_not_quoted(tmp_path, capsys):
    (tmp_path / "n.mcir").write_text(SIMPLE)
    secret = tmp_path / "shadow"
    secret.write_text("root:$6$SECRETHASH:19000:0:99999:7:::\n")
    spec = tmp_path / "s.toml"
    spec.write_text(f'netlist = "n.mcir"\nanalysis = "resonances"\n[sample]\nfile = "{secret}"\n')
    err = assert_user_error(["study", spec], capsys, "sample.file must name a .csv or .parquet")
    assert "SECRET" not in err
    table = tmp_path / "shadow.csv"
    table.write_text(secret.read_text() + "1\n")
    spec.write_text('netlist = "n.mcir"\nanalysis = "resonances"\n[sample]\nfile = "shadow.csv"\n')
    err = assert_user_error(["study", spec], capsys,
                            "shadow.csv:1:1: error: column 1 (not a parameter name) is not a "
                            ".param of the netlist")
    assert "SECRET" not in err and "19000" not in err


# ------------------------------------------------------------------ lock and Parquet refusals
def test_a_lock_that_cannot_be_created_and_the_lock_without_fcntl(tmp_path, capsys, monkeypatch):
    """The lock path taken by a folder: exit 2 naming it and the OS's reason, nothing written.
    Without fcntl (Windows) the lock is an exclusive create: a lock file left by another
    study is refused with its holder and the hint to delete it."""
    from mechcirc.study.executors import _lock

    a = spec_file(tmp_path)
    out = tmp_path / "r.csv"
    Path(f"{out}.lock").mkdir()
    assert_user_error(["study", a, "-o", out, "--workers", "1"], capsys,
                      f"r.csv: cannot create the lock file {out}.lock: Is a directory")
    assert files(tmp_path) == ["r.csv.lock", "s.toml"]
    Path(f"{out}.lock").rmdir()
    monkeypatch.setitem(sys.modules, "fcntl", None)          # import fcntl fails
    with _lock(out):
        assert Path(f"{out}.lock").read_text().startswith(f"pid {os.getpid()} on ")
        with pytest.raises(MechcircError, match=(
                f"is being written by another study \\(pid {os.getpid()} on .*; wait for it to "
                f"end, or write another -o \\(if it is no longer running, delete {out}.lock\\)")):
            with _lock(out):
                pass
    assert files(tmp_path) == ["s.toml"]


def test_parquet_refusals_say_what_is_wrong_and_write_nothing(tmp_path, capsys, monkeypatch):
    """A damaged Parquet table to resume, a damaged Parquet sample file: exit 2 with the
    file and the reason; without pyarrow, Parquet output and a Parquet sample file are
    refused with the package to install and the CSV alternative."""
    a = spec_file(tmp_path)
    (tmp_path / "n.mcir").write_text(SIMPLE)
    s = tmp_path / "p.toml"
    s.write_text('netlist = "n.mcir"\nanalysis = "resonances"\n[sample]\nfile = "d.parquet"\n')
    bad = b"PAR1 not a table"
    (tmp_path / "d.parquet").write_bytes(bad)
    (tmp_path / "r.parquet").write_bytes(bad)
    before = files(tmp_path)
    if _importable("pyarrow"):
        assert_user_error(["study", a, "-o", tmp_path / "r.parquet", "--resume", "--workers",
                           "1"], capsys, "r.parquet: not a Parquet table (", "cannot resume")
        assert (tmp_path / "r.parquet").read_bytes() == bad
        assert_user_error(["study", s, "-o", tmp_path / "x.csv"], capsys,
                          "d.parquet", "not a Parquet file (")
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    assert_user_error(["study", a, "-o", tmp_path / "new.parquet", "--workers", "1"], capsys,
                      "Parquet output needs pyarrow (pip install pyarrow); or write CSV")
    assert_user_error(["study", s, "-o", tmp_path / "x.csv"], capsys, "d.parquet",
                      "reading Parquet needs pyarrow (pip install pyarrow); or give a CSV file")
    assert files(tmp_path) == before


def _importable(name):
    import importlib.util

    return importlib.util.find_spec(name) is not None


@pytest.mark.parametrize("batch_fails", [False, True])
def test_a_failed_sweep_batch_gives_each_point_its_curve_or_nan(batch_fails, monkeypatch):
    """run_batch(curves=True) on a batch that one point breaks (a negative mass): the good
    point's K(ω) is the closed form 1/(jωm + 2k/(jω)), the bad one's row the located
    error and its curve NaN; the same when the batch as a whole fails (batch.designs made
    to raise for more than one point), so that each point is run alone (the fallback)."""
    import mechcirc.batch
    from mechcirc.study import StudySpec, run_batch

    if batch_fails:
        designs = mechcirc.batch.designs

        def whole_batch_fails(text, params, **kw):
            if len(next(iter(params.values()))) > 1:
                raise MemoryError("the batch does not fit")
            return designs(text, params, **kw)

        monkeypatch.setattr(mechcirc.batch, "designs", whole_batch_fails)
    spec = StudySpec(SIMPLE, "n.mcir", "sweep", ("m",), ((3.0,), (-1.0,)),
                     omega=(1.0, 100.0, 5, True))
    rows, K = run_batch(spec, [(0, {"m": 3.0}), (1, {"m": -1.0})], True)
    w = np.geomspace(1.0, 100.0, 5)
    np.testing.assert_allclose(K[0], 1 / (1j * w * 3.0 + 200 / (1j * w)), rtol=1e-14)
    assert np.isnan(K[1]).all() and K.shape == (2, 5)
    assert rows[0]["status"] == "ok" and rows[1]["status"] == "error"
    assert rows[1]["error"].startswith("NetlistError: n.mcir:2:")
    assert "must be > 0" in rows[1]["error"]
    assert rows[0]["K_abs_min"] == pytest.approx(np.abs(K[0]).min(), rel=1e-14)
