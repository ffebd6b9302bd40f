"""The command line: ``mechcirc check`` and ``mechcirc sweep``, exit statuses, outputs.

Most tests run the CLI in-process through :func:`mechcirc.cli.main` and read
stdout/stderr with ``capsys``; a few run ``python -m mechcirc`` as a
subprocess, where the exit status comes from the real interpreter.
"""

import csv
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from mechcirc.cli import circuit_commands
from bounds import SUBPROCESS_TIMEOUT
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]
HEADER = "omega,K_re,K_im,Q0_re,Q0_im,flag"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

GOOD = "mass m1 a 0 2\nspring k1 a 0 800\ndamper c1 a 0 3\ndrive V a 0 velocity=0.1\n"


def run(argv, capsys):
    """Run the CLI in-process; return (exit status, stdout, stderr)."""
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as exc:         # argparse: --help, usage errors
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def run_subprocess(*argv, cwd=REPO):
    """``python -m mechcirc ARGV`` from the repository root (so the working tree is imported)."""
    return subprocess.run([sys.executable, "-m", "mechcirc", *map(str, argv)], cwd=cwd,
                          capture_output=True, text=True, timeout=SUBPROCESS_TIMEOUT)


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


# --------------------------------------------------------------------------
# help
# --------------------------------------------------------------------------

def test_help_lists_the_commands(capsys):
    status, out, _ = run(["--help"], capsys)
    assert status == 0
    assert re.search(r"^\s+check\s+\S", out, re.M)
    assert re.search(r"^\s+sweep\s+\S", out, re.M)


def test_no_command_prints_help_and_exits_2(capsys):
    """A usage error: the help on stderr, nothing on stdout (it was on stdout, against the
    contract of exit status 2)."""
    status, out, err = run([], capsys)
    assert status == 2 and out == ""
    assert "usage: mechcirc" in err


def test_python_m_mechcirc_help():
    proc = run_subprocess("--help")
    assert proc.returncode == 0, proc.stderr
    assert "check" in proc.stdout and "sweep" in proc.stdout
    assert proc.stdout.startswith("usage: mechcirc")


def test_console_script_help():
    script = Path(sys.executable).with_name("mechcirc")
    if not script.exists():
        pytest.skip("no mechcirc console script beside this interpreter")
    proc = subprocess.run([str(script), "--help"], capture_output=True, text=True,
                          timeout=SUBPROCESS_TIMEOUT)
    assert proc.returncode == 0, proc.stderr
    assert "check" in proc.stdout and "sweep" in proc.stdout


def test_import_mechcirc_does_not_import_matplotlib_or_heavy_modules(light_imports):
    """``import mechcirc`` and building the CLI parser (``--help``) stay light (docs/cli.md);
    the checkout's package is the one imported (one process with the other light-import checks: tests/conftest.py, light_imports)."""
    assert light_imports["mechcirc.__file__"].endswith("__init__.py")
    heavy = ("matplotlib", "scipy", "networkx", "numba")
    assert [m for m in light_imports["build_parser"] if m.split(".")[0] in heavy] == []


# --------------------------------------------------------------------------
# check
# --------------------------------------------------------------------------

def test_check_text(capsys):
    status, out, err = run(["check", STB], capsys)
    assert status == 0, err
    lines = out.splitlines()
    assert lines[0] == f"{STB}: 15 elements, 0 levers, 14 nodes"
    assert lines[1] == "drive V0: velocity 0.1 m/s between T and 0"
    assert lines[-1] == "K = " + str(mechcirc.load(STB).tree)
    assert lines[-1] == ("K = m1 + m2 + m3 + m4 + (k4 | (m5 + k5) | "
                         "(m6 + m7 + m8 + m9 + m10 + m11 + m12 + k0))")
    assert re.search(r"^\s+spring\s+k4\s+D\s+0\s+2e\+06 N/m\s+eta=0\.648$", out, re.M)
    assert re.search(r"^\s+mass\s+m1\s+T\s+A\s+2 kg$", out, re.M)
    assert err == ""


def test_check_json(capsys):
    status, out, err = run(["check", "--json", STB], capsys)
    assert status == 0, err
    doc = json.loads(out)
    c = mechcirc.load(STB)
    assert doc["name"] == "stb_heald"
    assert doc["tree"] == str(c.tree)
    assert doc["nodes"] == c.nodes
    assert [e["name"] for e in doc["elements"]] == [e.name for e in c.elements]
    k4 = next(e for e in doc["elements"] if e["name"] == "k4")
    assert k4 == {"name": "k4", "kind": "spring", "n1": "D", "n2": "0", "value": 2.0e6,
                  "eta": pytest.approx(0.8**2 * 1.25 * 0.9**2, rel=1e-15), "line": 22}
    assert doc["drive"] == {"name": "V0", "n1": "T", "n2": "0", "kind": "velocity",
                            "amplitude": 0.1}
    assert doc["levers"] == [] and doc["unloaded"] == [] and doc["warnings"] == []


def test_check_warns_about_unloaded_elements(tmp_path, capsys):
    path = write(tmp_path, "dangling.mcir", GOOD + "mass m9 a b 1\nspring k9 b c 5\n")
    status, out, err = run(["check", "--json", path], capsys)
    assert status == 0
    doc = json.loads(out)
    assert doc["unloaded"] == ["m9", "k9"]
    assert len(doc["warnings"]) == 1 and "m9, k9" in doc["warnings"][0]
    status, out, err = run(["check", path], capsys)
    assert status == 0
    assert err.startswith("warning: ") and "m9, k9" in err


# --------------------------------------------------------------------------
# sweep
# --------------------------------------------------------------------------

def test_sweep_csv_header_and_values_equal_the_api(tmp_path, capsys):
    out_csv = tmp_path / "K.csv"
    status, out, err = run(["sweep", STB, "--omega-min", 10, "--omega-max", 1e4,
                            "--points", 301, "--log", "-o", out_csv], capsys)
    assert status == 0, err
    assert out_csv.read_text().splitlines()[0] == HEADER
    header, table = read_csv(out_csv)
    assert ",".join(header) == HEADER
    assert table.shape == (301, 6)
    omega = np.geomspace(10, 1e4, 301)
    s = mechcirc.load(STB).sweep(omega)
    np.testing.assert_array_equal(table[:, 5], s.flags)
    # %.17g round-trips float64 exactly.
    np.testing.assert_array_equal(table[:, 0], omega)
    np.testing.assert_array_equal(table[:, 1], s.K.real)
    np.testing.assert_array_equal(table[:, 2], s.K.imag)
    np.testing.assert_array_equal(table[:, 3], s.Q0.real)
    np.testing.assert_array_equal(table[:, 4], s.Q0.imag)
    assert f"CSV written to {out_csv}" in out


def test_sweep_linear_grid(tmp_path, capsys):
    path = write(tmp_path, "rlc.mcir", GOOD)
    out_csv = tmp_path / "lin.csv"
    status, _, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 100,
                          "--points", 7, "-o", out_csv], capsys)
    assert status == 0, err
    _, table = read_csv(out_csv)
    np.testing.assert_array_equal(table[:, 0], np.linspace(1, 100, 7))
    # m | k | c in parallel: 1/K = jωm + k/(jω) + c.
    w = table[:, 0]
    K = 1 / (1j * w * 2 + 800 / (1j * w) + 3)
    np.testing.assert_allclose(table[:, 1] + 1j * table[:, 2], K, rtol=1e-13)
    np.testing.assert_allclose(table[:, 3] + 1j * table[:, 4], 0.1 / K, rtol=1e-13)


@pytest.mark.parametrize("lo, hi, expect", [
    ("1Hz", "3000rpm", (2 * np.pi, 100 * np.pi)),
    ("10", "1e3rad/s", (10.0, 1e3)),
    ("2 Hz", "50 1/s", (4 * np.pi, 50.0)),
])
def test_sweep_frequency_units(tmp_path, capsys, lo, hi, expect):
    out_csv = tmp_path / "K.csv"
    status, _, err = run(["sweep", STB, "--omega-min", lo, "--omega-max", hi,
                          "--points", 5, "-o", out_csv], capsys)
    assert status == 0, err
    _, table = read_csv(out_csv)
    np.testing.assert_allclose(table[:, 0], np.linspace(*expect, 5), rtol=1e-15)


def test_sweep_unknown_frequency_unit_exit_2(capsys):
    status, out, err = run(["sweep", STB, "--omega-min", "1", "--omega-max", "50x"], capsys)
    assert status == 2
    assert "unknown frequency unit 'x'" in err and out == ""


def test_sweep_text_summary(capsys):
    status, out, err = run(["sweep", STB, "--omega-min", 10, "--omega-max", 1e4,
                            "--points", 50, "--log"], capsys)
    assert status == 0, err
    s = mechcirc.load(STB).sweep(np.geomspace(10, 1e4, 50))
    lines = out.splitlines()
    assert lines[0] == f"{STB}: 50 points, omega 10 .. 10000 rad/s, method sp"
    assert lines[1] == (f"  |K|  {np.abs(s.K).min():.4g} .. {np.abs(s.K).max():.4g} m/(N·s)"
                        " on the grid")
    assert lines[2] == (f"  |Q0| {np.abs(s.Q0).min():.4g} .. {np.abs(s.Q0).max():.4g} N"
                        " on the grid")
    # The network is undamped and the band holds its resonances: the peak is ∞
    # (issue 11 §4), named at the exact resonances, not the grid's largest value.
    zeros = [r.omega for r in mechcirc.load(STB).resonances(omega_max=1e4)
             if r.kind == "resonance" and r.omega >= 10]
    assert lines[3] == ("  max |Q0| = inf: undamped resonance at omega = "
                        + ", ".join(f"{w:.10g}" for w in zeros)
                        + f" rad/s (the grid's largest, {np.abs(s.Q0).max():.4g} N, depends "
                        "only on how close a point falls)")


def test_sweep_json(capsys):
    status, out, err = run(["sweep", STB, "--omega-min", 10, "--omega-max", 1e4,
                            "--points", 40, "--log", "--json"], capsys)
    assert status == 0, err
    doc = json.loads(out)
    omega = np.geomspace(10, 1e4, 40)
    s = mechcirc.load(STB).sweep(omega)
    assert doc["name"] == "stb_heald"
    np.testing.assert_array_equal(doc["omega"], omega)
    np.testing.assert_array_equal(doc["K"]["re"], s.K.real)
    np.testing.assert_array_equal(doc["K"]["im"], s.K.imag)
    np.testing.assert_array_equal(doc["Q0"]["re"], s.Q0.real)
    np.testing.assert_array_equal(doc["Q0"]["im"], s.Q0.imag)
    assert doc["flags"] == [0] * 40 and doc["n_flagged"] == 0
    assert doc["warnings"] == []
    assert doc["peak"]["unbounded"] is True and doc["peak"]["value"] in ("inf", math.inf)


def test_sweep_json_at_a_pole_reads_as_numbers(tmp_path, capsys):
    """ω = 0 makes a mass's K infinite: the point is flagged, and the value is the number
    -Infinity for json.loads (issue 17 §2 changed the convention from strings "inf"/"-inf",
    which made the numeric arrays mixed)."""
    path = write(tmp_path, "m.mcir", "mass m a 0 2\ndrive V a 0 velocity=0.1\n")
    status, out, err = run(["sweep", path, "--omega-min", 0, "--omega-max", 10,
                            "--points", 3, "--json"], capsys)
    assert status == 0, err
    doc = json.loads(out)
    assert doc["flags"] == [1, 0, 0] and doc["n_flagged"] == 1
    assert doc["K"]["im"][0] == float("-inf")
    pd = pytest.importorskip("pandas")
    import io
    col = pd.read_json(io.StringIO(json.dumps({"im": doc["K"]["im"]})))["im"]
    assert col.dtype.kind == "f" and col.iloc[0] == float("-inf")
    assert doc["K"]["im"][1:] == [-1 / (5.0 * 2), -1 / (10.0 * 2)]


@pytest.mark.parametrize("element", ["mass m a 0 2", "spring k a 0 5", "damper c a 0 3"])
@pytest.mark.parametrize("output", [["--json"], ["--plot", "K.png"]])
def test_sweep_of_a_single_element(tmp_path, capsys, element, output):
    """The smallest circuits sweep too (one node besides the frame)."""
    path = write(tmp_path, "one.mcir", element + "\ndrive V a 0 velocity=0.1\n")
    argv = ["sweep", path, "--omega-min", 1, "--omega-max", 10, "--points", 3]
    argv += [str(tmp_path / o) if o.endswith(".png") else o for o in output]
    status, out, err = run(argv, capsys)
    assert status == 0, err
    if output == ["--json"]:
        doc = json.loads(out)
        K = mechcirc.parse(element + "\ndrive V a 0 velocity=0.1\n").sweep([1.0, 5.5, 10.0]).K
        np.testing.assert_array_equal(np.array(doc["K"]["re"]) + 1j * np.array(doc["K"]["im"]), K)
    else:
        assert (tmp_path / "K.png").read_bytes()[:8] == PNG_SIGNATURE


def test_sweep_force_drive_adds_v0_columns(tmp_path, capsys):
    """Force drive F0: Q0 = F0 everywhere and the velocity answer v0 = F0·K gets columns."""
    text = GOOD.replace("velocity=0.1", "force=20")
    path = write(tmp_path, "force.mcir", text)
    out_csv = tmp_path / "F.csv"
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 100,
                            "--points", 9, "--log", "-o", out_csv, "--json"], capsys)
    assert status == 0, err
    header, table = read_csv(out_csv)
    assert ",".join(header) == "omega,K_re,K_im,Q0_re,Q0_im,v0_re,v0_im,flag"
    s = mechcirc.parse(text).sweep(np.geomspace(1, 100, 9))
    np.testing.assert_array_equal(table[:, 1] + 1j * table[:, 2], s.K)
    np.testing.assert_array_equal(table[:, 3] + 1j * table[:, 4], np.full(9, 20.0))
    np.testing.assert_array_equal(table[:, 5] + 1j * table[:, 6], s.v0)
    np.testing.assert_allclose(s.v0, 20 * s.K, rtol=1e-15)
    doc = json.loads(out)
    np.testing.assert_array_equal(np.array(doc["v0"]["re"]) + 1j * np.array(doc["v0"]["im"]),
                                  s.v0)


def test_sweep_plot_writes_a_png(tmp_path, capsys):
    png = tmp_path / "K.png"
    status, out, err = run(["sweep", STB, "--omega-min", 10, "--omega-max", 1e4,
                            "--points", 100, "--log", "--plot", png], capsys)
    assert status == 0, err
    data = png.read_bytes()
    assert data[:8] == PNG_SIGNATURE
    assert len(data) > 5000            # an actual picture, not an empty image
    assert f"plot written to {png}" in out
    assert [p.name for p in tmp_path.iterdir()] == ["K.png"]   # no temporary left


# The sweep's CSV and PNG written by a process of its own (python -m mechcirc): in
# tests/test_startup.py, test_the_sweep_plot_uses_no_pyplot_and_no_scipy, which runs it
# for the modules it loads too.


# --------------------------------------------------------------------------
# user errors: exit 2, one located line on stderr
# --------------------------------------------------------------------------

BAD = [
    ("mass m1 a 0 2\nmas k1 a 0 100\ndrive V a 0 velocity=1\n",
     "2:1: error: unknown keyword 'mas'; did you mean 'mass'? (expected one of .param, .ic, mass, spring, damper, "
     "lever, drive)"),
    ("mass m1 a 0 2\nspring k1 a 0 {2e5 * }\ndrive V a 0 velocity=1\n",
     "2:22: error: expression ends too early (expected a number, a name or '(')"),
    ("mass m1 a 0 -2\ndrive V a 0 velocity=1\n",
     "1:13: error: mass 'm1' must be > 0 kg, got -2 (expected a positive value)"),
    (".param m=2\nmass m1 a 0 mm\ndrive V a 0 velocity=1\n",
     "2:13: error: undefined parameter 'mm'; did you mean 'm'? (expected a parameter defined by an earlier "
     ".param line)"),
    ("mass m1 a 0 2\nspring m1 a 0 5\ndrive V a 0 velocity=1\n",
     "2:8: error: element name 'm1' is already used on line 1 (expected a unique name)"),
]


@pytest.mark.parametrize("text, message", BAD)
@pytest.mark.parametrize("command", [["check"], ["check", "--json"],
                                     ["sweep", "--omega-min", "1", "--omega-max", "2"]])
def test_bad_netlist_gives_a_located_error_and_exit_2(tmp_path, capsys, text, message, command):
    path = write(tmp_path, "bad.mcir", text)
    status, out, err = run([command[0], path, *command[1:]], capsys)
    assert status == 2
    assert out == ""
    assert err == f"{path}:{message}\n"


def test_glued_compound_unit_hint_names_the_whole_unit(tmp_path, capsys):
    """``5N/mm`` should be advised as ``'5 N/mm'``; ``'5 N'`` would be a force, refused next.

    (Bug at the time of writing: the hint reads "a space between the number
    and its unit: '5 N'", because the malformed-number scan stops at '/'.)
    """
    # Issue 17 §1: a plain glued value is now read (5N/mm == 5 N/mm); the hint
    # remains for a glued unit inside an expression.
    path = write(tmp_path, "glued.mcir", "spring k1 a 0 5N/mm\ndrive V a 0 velocity=1\n")
    status, out, err = run(["check", path], capsys)
    assert status == 0 and "5000" in out
    path = write(tmp_path, "glued.mcir", "spring k1 a 0 1+5N/mm\ndrive V a 0 velocity=1\n")
    status, _, err = run(["check", path], capsys)
    assert status == 2
    assert err.startswith(f"{path}:1:17: error: ")
    assert "'5 N/mm'" in err


def test_bad_netlist_by_subprocess(tmp_path):
    write(tmp_path, "bad.mcir", BAD[0][0])
    proc = run_subprocess("check", "bad.mcir", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr == f"bad.mcir:{BAD[0][1]}\n"
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("op, value", [("+", 2000.0), ("*", 1.0)])
def test_long_flat_expression_within_the_limits(tmp_path, capsys, op, value):
    """2,000 terms joined by one operator: ~4,000 characters (limit 10,000) and no nesting.

    (Bug at the time of writing: ``expressions.evaluate`` and ``Expr.names``
    recurse once per operator, so from about 1,000 terms a RecursionError
    escapes: exit 1, "internal error".)
    """
    text = f"mass m a 0 {op.join(['1'] * 2000)}\ndrive V a 0 velocity=1\n"
    path = write(tmp_path, "long.mcir", text)
    status, out, err = run(["check", "--json", path], capsys)
    assert "internal error" not in err
    assert status == 0, err
    assert json.loads(out)["elements"][0]["value"] == value


def test_missing_file_exit_2(tmp_path, capsys):
    path = tmp_path / "nowhere.mcir"
    for argv in (["check", path], ["sweep", path, "--omega-min", 1, "--omega-max", 2]):
        status, out, err = run(argv, capsys)
        assert status == 2
        assert err.startswith(f"{path}: error: no such file")
        assert out == ""


def test_topology_error_exit_2(tmp_path, capsys):
    path = write(tmp_path, "apart.mcir", "mass m1 a 0 2\nmass m2 b c 1\ndrive V a b velocity=1\n")
    status, out, err = run(["check", path], capsys)
    assert status == 2
    # issue 17 §5: a statement error names FILE:LINE:COL (was "mechcirc: error: ...")
    assert err.startswith(f"{path}:3:1: error: the drive's nodes 'a' and 'b'")
    assert "not connected" in err


@pytest.mark.parametrize("options, message", [
    (["--omega-min", 10, "--omega-max", 1], "need 0 <= --omega-min < --omega-max"),
    (["--omega-min", 5, "--omega-max", 5], "need 0 <= --omega-min < --omega-max"),
    (["--omega-min", -1, "--omega-max", 1], "need 0 <= --omega-min < --omega-max"),
    (["--omega-min", "nan", "--omega-max", 1], "need 0 <= --omega-min < --omega-max"),
    (["--omega-min", 1, "--omega-max", "inf"], "need 0 <= --omega-min < --omega-max"),
    (["--omega-min", 0, "--omega-max", 1, "--log"], "--log needs --omega-min > 0"),
    (["--omega-min", 1, "--omega-max", 2, "--points", 0], "--points must be between"),
    (["--omega-min", 1, "--omega-max", 2, "--points", 1], "--points must be between 2 and"),
])
def test_bad_omega_range_exit_2(tmp_path, capsys, options, message):
    path = write(tmp_path, "ok.mcir", GOOD)
    out_csv = tmp_path / "K.csv"
    status, out, err = run(["sweep", path, *options, "-o", out_csv], capsys)
    assert status == 2
    assert err.startswith("mechcirc: error: ") and message in err
    assert not out_csv.exists()


def test_missing_required_option_is_a_usage_error(capsys):
    status, _, err = run(["sweep", STB, "--omega-min", 1], capsys)
    assert status == 2
    assert "--omega-max" in err


# --------------------------------------------------------------------------
# no output is left behind when a command fails
# --------------------------------------------------------------------------

def test_failed_sweep_creates_no_output(tmp_path, capsys):
    path = write(tmp_path, "bad.mcir", BAD[2][0])
    out_csv, png = tmp_path / "out.csv", tmp_path / "out.png"
    status, _, _ = run(["sweep", path, "--omega-min", 1, "--omega-max", 2,
                        "-o", out_csv, "--plot", png], capsys)
    assert status == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.mcir"]


def test_failed_sweep_leaves_an_existing_csv_untouched(tmp_path, capsys):
    path = write(tmp_path, "bad.mcir", BAD[2][0])
    out_csv = write(tmp_path, "out.csv", "old contents\n")
    os.utime(out_csv, (1_000_000_000, 1_000_000_000))
    status, _, _ = run(["sweep", path, "--omega-min", 1, "--omega-max", 2, "-o", out_csv],
                       capsys)
    assert status == 2
    assert out_csv.read_text() == "old contents\n"
    assert out_csv.stat().st_mtime == 1_000_000_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.mcir", "out.csv"]


def test_failing_plot_leaves_no_csv_behind(tmp_path, capsys):
    """The plot fails after the sweep succeeded: the command fails, so no CSV either.

    (Bug at the time of writing: ``cmd_sweep`` renames the CSV into place
    before it draws the plot, so a plot into a missing folder exits 2 but
    leaves the CSV written.)
    """
    path = write(tmp_path, "ok.mcir", GOOD)
    out_csv = tmp_path / "out.csv"
    status, _, _ = run(["sweep", path, "--omega-min", 1, "--omega-max", 2, "-o", out_csv,
                        "--plot", tmp_path / "no-such-folder" / "K.png"], capsys)
    assert status == 2
    assert not out_csv.exists()


def test_failing_plot_leaves_an_existing_csv_untouched(tmp_path, capsys):
    path = write(tmp_path, "ok.mcir", GOOD)
    out_csv = write(tmp_path, "out.csv", "old contents\n")
    status, _, _ = run(["sweep", path, "--omega-min", 1, "--omega-max", 2, "-o", out_csv,
                        "--plot", tmp_path / "no-such-folder" / "K.png"], capsys)
    assert status == 2
    assert out_csv.read_text() == "old contents\n"


def test_plot_into_a_missing_folder_names_the_requested_path(tmp_path, capsys):
    """The message names the file the user asked for, not the hidden temporary file.

    (Bug at the time of writing: stderr reads
    ``…/no-such-folder/.K.png.XXXXXXXX.tmp.png: error: no such file``.)
    """
    path = write(tmp_path, "ok.mcir", GOOD)
    png = tmp_path / "no-such-folder" / "K.png"
    status, _, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 2, "--plot", png],
                         capsys)
    assert status == 2
    assert "error" in err and str(png) in err
    assert ".tmp" not in err


def test_unsupported_plot_format_is_a_user_error(tmp_path, capsys):
    """An image extension matplotlib cannot write is the user's mistake (exit 2), not a bug.

    (Bug at the time of writing: ``--plot K.xyz`` exits 1 with "internal
    error: ValueError: Format 'xyz' is not supported", after writing the CSV.)
    """
    path = write(tmp_path, "ok.mcir", GOOD)
    out_csv = tmp_path / "out.csv"
    status, _, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 2, "-o", out_csv,
                          "--plot", tmp_path / "K.xyz"], capsys)
    assert status == 2
    assert "internal error" not in err and "xyz" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ok.mcir"]


def test_output_path_that_is_a_folder(tmp_path, capsys):
    """``-o`` naming an existing folder: exit 2, the message names that folder, no temporary left.

    (Bug at the time of writing: stderr names the hidden temporary file,
    ``…/.outdir.XXXXXXXX.tmp: error: is a directory, expected a file``, and
    that temporary file stays behind in the parent folder.)
    """
    path = write(tmp_path, "ok.mcir", GOOD)
    (tmp_path / "outdir").mkdir()
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 2,
                            "-o", tmp_path / "outdir"], capsys)
    assert status == 2
    assert str(tmp_path / "outdir") in err and ".tmp" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ok.mcir", "outdir"]
    assert list((tmp_path / "outdir").iterdir()) == []


def test_csv_and_plot_to_the_same_file_is_refused(tmp_path, capsys):
    """``-o K.png --plot K.png`` would lose one of the two outputs: a user error, nothing written.

    (Bug at the time of writing: exit 0, "CSV written to K.png" and "plot
    written to K.png", and the CSV is silently replaced by the picture.)
    """
    path = write(tmp_path, "ok.mcir", GOOD)
    same = tmp_path / "K.png"
    status, out, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 2,
                            "-o", same, "--plot", same], capsys)
    assert status == 2
    assert "K.png" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ok.mcir"]


def test_csv_gets_ordinary_file_permissions(tmp_path, capsys):
    """The atomic temporary file (mode 0600) must not hand its mode to the output.

    (Bug at the time of writing: ``outputs.atomic_path`` renames a
    ``mkstemp`` file, so every CSV and plot is ``-rw-------`` whatever the umask.)
    """
    path = write(tmp_path, "ok.mcir", GOOD)
    out_csv = tmp_path / "out.csv"
    old = os.umask(0o022)
    try:
        status, _, err = run(["sweep", path, "--omega-min", 1, "--omega-max", 2,
                              "-o", out_csv], capsys)
    finally:
        os.umask(old)
    assert status == 0, err
    assert out_csv.stat().st_mode & 0o777 == 0o644


# --------------------------------------------------------------------------
# internal errors: exit 1, one message, no traceback
# --------------------------------------------------------------------------

def _boom(args):
    raise RuntimeError("boom in the handler")


def test_internal_error_exit_1_without_traceback(monkeypatch, capsys):
    monkeypatch.setattr(circuit_commands, "cmd_sweep", _boom)
    status, out, err = run(["sweep", STB, "--omega-min", 1, "--omega-max", 2], capsys)
    assert status == 1
    assert out == ""
    assert err.startswith("mechcirc: internal error: RuntimeError: boom in the handler\n")
    assert "Traceback" not in err
    assert "--debug" in err


def test_internal_error_in_check_exit_1(monkeypatch, capsys):
    monkeypatch.setattr(circuit_commands, "cmd_check", _boom)
    status, _, err = run(["check", STB], capsys)
    assert status == 1
    assert "internal error" in err and "Traceback" not in err


def test_interrupt_exit_130(monkeypatch, capsys, tmp_path):
    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(circuit_commands, "cmd_sweep", interrupted)
    status, out, err = run(["sweep", STB, "--omega-min", 1, "--omega-max", 2,
                            "-o", tmp_path / "K.csv"], capsys)
    assert status == 130
    assert err == "mechcirc: interrupted\n"
    assert not (tmp_path / "K.csv").exists()


def test_debug_shows_the_exception(monkeypatch, capsys):
    monkeypatch.setattr(circuit_commands, "cmd_check", _boom)
    with pytest.raises(RuntimeError, match="boom in the handler"):
        cli.main(["--debug", "check", str(STB)])


def test_internal_error_by_subprocess_has_no_traceback(tmp_path):
    """A real interpreter: an exception inside the handler still ends in exit 1 and one message."""
    code = ("import sys\n"
            "from mechcirc.cli import circuit_commands as cc\n"
            "def boom(args):\n"
            "    raise RuntimeError('boom')\n"
            "cc.cmd_check = boom\n"
            "from mechcirc.cli import main\n"
            "sys.exit(main(['check', 'netlists/stb_heald.mcir']))\n")
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=SUBPROCESS_TIMEOUT)
    assert proc.returncode == 1
    assert "mechcirc: internal error: RuntimeError: boom" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_error_lines_stay_short_and_do_not_quote_other_files(tmp_path, capsys):
    """A study whose netlist is a secret file, a huge option value, a huge token: every
    error is one short line, and the secret file's text is not in it (issue 23 §6)."""
    secret = tmp_path / "shadow"
    secret.write_text("root:$6$hunter2$abcdefgh:19000:0:99999:7:::\n")
    spec = tmp_path / "s.toml"
    spec.write_text(f'netlist = "{secret}"\n[omega]\nmin = 1\nmax = 10\npoints = 3\n'
                    "[grid]\neta1 = [0.8]\n")
    status, _, err = run(["study", spec, "--workers", "1"], capsys)
    assert status == 2 and "not a netlist" in err and "hunter2" not in err
    status, _, err = run(["sweep", STB, "--omega-min", 1, "--omega-max", 10,
                          "--method", "x" * 50_000], capsys)      # argparse quotes choices
    assert status == 2 and len(err) < 400 and "x…" + "x" * 25 + "' (50,000 characters)" in err
    long = write(tmp_path, "long.mcir", "mass m a 0 1\n" + "z" * 90_000 + " k a 0 1\n" + GOOD)
    status, _, err = run(["check", long], capsys)
    assert status == 2 and len(err) < 400 and "(90,000 characters)" in err
