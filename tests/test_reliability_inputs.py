"""Issue 16 §2–§4: user errors (exit 2, located), bounded work, output safety.

Each case was an internal error, a silent wrong answer, unbounded work or an
unsafe output before; each test checks the refusal (or the bound) itself.
"""

from __future__ import annotations

import csv
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mechcirc.cli import main
from mechcirc.errors import InputError, MechcircError, NetlistError
from mechcirc.sources import line_col, locate_path, split_lines

ROOT = Path(__file__).resolve().parents[1]
STB = str(ROOT / "netlists" / "stb_heald.mcir")
SCENE = ROOT / "examples" / "heald_scene.toml"
STUDY = ROOT / "examples" / "study_stb.toml"


def run(argv, capsys):
    """(status, stdout, stderr) of the CLI in-process; argparse's exits count as statuses."""
    try:
        status = main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def assert_user_error(argv, capsys, *needles):
    status, out, err = run(argv, capsys)
    assert status == 2, (status, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err                        # one line, no warnings before it
    assert "internal error" not in err and "Traceback" not in err
    for needle in needles:
        assert needle in err, err
    return err


# ------------------------------------------------------------------ §2 numbers on the CLI
@pytest.mark.parametrize("value", ["0", "-1", "inf", "nan", "1e400"])
def test_forces_omega_out_of_domain_is_a_user_error(value, capsys):
    assert_user_error(["forces", STB, f"--omega={value}"], capsys, "--omega")


@pytest.mark.parametrize("argv, needle", [
    (["--omega", "1e300"], "--omega"),
    (["--omega", "nan"], "--omega"),
    (["--omega", "inf"], "--omega"),
])
def test_fourbar_omega_must_be_finite_and_bounded(argv, needle, capsys):
    assert_user_error(["fourbar", "--crank", "29", "--coupler", "37", "--rocker", "188",
                       "--frame", "189", *argv], capsys, needle)


@pytest.mark.parametrize("lengths", [("1e308", "37", "188", "189"),
                                     ("1e50", "37", "188", "189"),
                                     ("1e-300", "37", "188", "189"),
                                     ("1e308", "1e308", "1e308", "1e308")])
def test_fourbar_extreme_lengths_are_refused_before_any_work(lengths, capsys):
    a, b, c, d = lengths
    assert_user_error(["fourbar", "--crank", a, "--coupler", b, "--rocker", c, "--frame", d],
                      capsys, "--")


@pytest.mark.parametrize("option", ["--omega-min", "--omega-max"])
@pytest.mark.parametrize("value", ["nan", "-1", "inf"])
def test_compare_band_must_be_finite_and_non_negative(option, value, tmp_path, capsys):
    s1p = tmp_path / "m.s1p"
    s1p.write_text("# Hz Z RI R 1\n1 0.001 0.002\n2 0.001 0.003\n")
    assert_user_error(["compare", STB, s1p, f"{option}={value}"], capsys, option)


@pytest.mark.parametrize("value", ["nan", "-1", "0", "inf"])
def test_resonances_omega_max_must_be_positive_and_finite(value, capsys):
    assert_user_error(["resonances", STB, f"--omega-max={value}"], capsys, "--omega-max")


def test_simulate_set_value_is_checked(capsys):
    assert_user_error(["simulate", "--set", "C2=1e308"], capsys, "--set C2")
    assert_user_error(["simulate", "--set", "C2=nan"], capsys, "--set C2")


# ------------------------------------------------------------------ §2 scene files
def _scene(tmp_path, old, new, count=1):
    text = SCENE.read_text()
    assert text.count(old) >= count, old
    path = tmp_path / "s.toml"
    path.write_text(text.replace(old, new, count))
    return path, text.replace(old, new, count)


@pytest.mark.parametrize("old, new, key", [
    ('units = "mm"', "units = [-12]", "units"),
    ('link = "rodCD"', 'link = ["rodCD"]', "link"),                       # elastic.link
    ('direction = [0.0, 1.0]', 'direction = [0.0, 1.0]\npoint = ["M"]', None),
    ('[drive]\nname = "ripple"\nlink = "crank"', '[drive]\nname = "ripple"\nlink = ["crank"]',
     "link"),                                                             # drive.link
    ("stiffness = 2.0e6", "stiffness = " + "9" * 400, "stiffness"),
    ("mass = 3.0", "mass = " + "9" * 400, "mass"),
])
def test_scene_values_of_the_wrong_kind_are_located_user_errors(old, new, key, tmp_path,
                                                                  capsys):
    from mechcirc.scene import load_scene

    path, text = _scene(tmp_path, old, new)
    with pytest.raises(NetlistError) as info:
        load_scene(path)
    err = info.value
    assert 1 <= err.line <= len(split_lines(text)), err
    if key:
        assert split_lines(text)[err.line - 1].lstrip().startswith(key), err
    assert len(str(err)) < 400                       # a 400-digit integer is cut short
    assert_user_error(["scene", path, "--theta", "10"], capsys, f"{path}:{err.line}:")


def test_scene_loads_point_as_a_list(tmp_path):
    from mechcirc.scene import parse_scene

    text = SCENE.read_text()
    i = text.index("[[loads]]")
    j = text.index('point = "M"', i)
    text = text[:j] + 'point = ["M"]' + text[j + len('point = "M"'):]
    with pytest.raises(NetlistError, match="point"):
        parse_scene(text, "s.toml")


def test_scene_build_at_nan_is_a_mechcirc_error():
    from mechcirc.scene import build, load_scene

    scene = load_scene(SCENE)
    for theta in (math.nan, math.inf):
        with pytest.raises(MechcircError):
            build(scene, theta)
    with pytest.raises(ValueError):          # InputError is also a ValueError
        build(scene, math.nan)


def test_forces_api_refuses_bad_omega_with_input_error():
    import mechcirc
    from mechcirc.forces import element_forces

    c = mechcirc.load(STB)
    for w in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(InputError):
            element_forces(c, w)


# ------------------------------------------------------------------ §2 study specs
def _spec(tmp_path, old, new):
    text = STUDY.read_text().replace("../netlists/", str(ROOT / "netlists") + "/")
    assert old in text, old
    text = text.replace(old, new, 1)
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path, text


@pytest.mark.parametrize("old, new, line_starts", [
    ("points = 400", "points = " + "9" * 300, "points"),
    ("eta1 = [0.7, 0.8, 0.9]", "eta1 = [0.7, " + "9" * 310 + "]", "eta1"),
    ('max = "1500Hz"', "max = [1]", "max"),
    ('analysis = "sweep"', "analysis = 5", "analysis"),
    ("num = 6}", "num = 1000000000}", "eta2"),
    ("num = 6}", "num = -3}", "eta2"),
    ("log = true", "log = true\nbogus = 1", "bogus"),        # an unknown key in [omega]
])
def test_study_spec_errors_carry_file_line_col(old, new, line_starts, tmp_path, capsys):
    from mechcirc.study import load_spec

    path, text = _spec(tmp_path, old, new)
    with pytest.raises(NetlistError) as info:
        load_spec(path)
    err = info.value
    assert err.source == str(path) and err.line >= 1, err
    line = split_lines(text)[err.line - 1]
    assert line.lstrip().startswith(line_starts), (err, line)
    assert len(str(err)) < 400
    assert_user_error(["study", path], capsys, f"{path}:{err.line}:")


def test_study_axis_of_a_billion_values_is_refused_before_it_is_built(tmp_path):
    from mechcirc.study import load_spec

    path, _ = _spec(tmp_path, "num = 6}", "num = 1000000000}")
    t0 = time.perf_counter()
    with pytest.raises(NetlistError, match="num must be an integer from 1 to 500,000"):
        load_spec(path)
    assert time.perf_counter() - t0 < 5        # not a 1e9-element list first


def test_study_grid_product_over_the_limit(tmp_path):
    from mechcirc.study import load_spec

    path, _ = _spec(tmp_path, "eta1 = [0.7, 0.8, 0.9]", "eta1 = {min = 0.5, max = 1, num = 2000}")
    text = path.read_text().replace("num = 6}", "num = 1000}")
    path.write_text(text)
    with pytest.raises(NetlistError, match="the grid has 2,000,000 points, the limit is"):
        load_spec(path)


def test_study_work_limit(tmp_path):
    from mechcirc.study import load_spec

    path, _ = _spec(tmp_path, "num = 6}", "num = 100000}")
    path.write_text(path.read_text().replace("points = 400", "points = 100000"))
    with pytest.raises(NetlistError, match="evaluations, the limit is"):
        load_spec(path)


def test_study_spec_not_utf8_is_located(tmp_path, capsys):
    path = tmp_path / "spec.toml"
    path.write_bytes(b'netlist = "x.mcir"\n# caf\xe9\n')
    err = assert_user_error(["study", path], capsys)
    assert f"{path}:2:6:" in err and "UTF-8" in err


# ------------------------------------------------------------------ §2 line counting
@pytest.mark.parametrize("brk", ["\x0c", "\x0b", "\r", "\x85", "\u2028", "\u2029", "\x1c"])
def test_only_newlines_end_lines(brk, tmp_path, capsys):
    """A form feed, VT, lone CR, NEL or U+2028 is no line break (as wc -l and editors)."""
    text = f"mass m1 a 0 1{brk}\nspring k1 a 0 oops\ndrive V a 0 velocity=1\n"
    path = tmp_path / "ff.mcir"
    path.write_text(text, encoding="utf-8")
    n_lines = path.read_bytes().count(b"\n")             # what wc -l prints
    with pytest.raises(NetlistError) as info:
        import mechcirc

        mechcirc.load(path)
    assert info.value.line == 2 <= n_lines


def test_line_past_the_end_is_never_reported(tmp_path):
    import mechcirc

    text = "mass m1 a 0 1\x0cspring k1 a 0 oops\ndrive V a 0 velocity=1\n"
    with pytest.raises(NetlistError) as info:
        mechcirc.parse(text, "ff.mcir")
    assert info.value.line <= text.count("\n")


def test_split_lines_and_line_col():
    assert split_lines("a\r\nb\n") == ["a", "b"]
    assert split_lines("a\rb\x0cc\u2028d") == ["a\rb\x0cc\u2028d"]
    assert split_lines("") == [] and split_lines("\n") == [""]
    assert line_col("ab\ncd", 4) == (2, 2)


def test_locate_path_finds_inline_table_keys():
    text = "[grid]\neta1 = [1, 2]\neta2 = {min = 1, max = 2, num = 6}\n[omega]\nmin = 1\n"
    assert locate_path(text, ("grid", "eta2", "num")) == (3, 27)
    assert locate_path(text, ("omega", "min")) == (5, 1)
    assert locate_path(text, ("omega",)) == (4, 1)


# ------------------------------------------------------------------ §3 limits
@pytest.mark.parametrize("extra, what", [
    (["--plot", "K.png"], "--plot"),
    (["--json"], "--json"),
    (["--method", "nodal"], "--method nodal"),
])
def test_sweep_point_limits_per_output(extra, what, tmp_path, capsys):
    from mechcirc.limits import MAX_JSON_POINTS, MAX_NODAL_POINTS, MAX_PLOT_POINTS

    limit = {"--plot": MAX_PLOT_POINTS, "--json": MAX_JSON_POINTS,
             "--method nodal": MAX_NODAL_POINTS}[what]
    extra = [str(tmp_path / e) if e.endswith(".png") else e for e in extra]
    t0 = time.perf_counter()
    assert_user_error(["sweep", STB, "--omega-min", "10", "--omega-max", "1e4",
                       "--points", str(limit + 1), *extra], capsys, what, f"{limit}")
    assert time.perf_counter() - t0 < 10          # refused before the sweep


@pytest.mark.parametrize("argv, needle", [
    (["simulate", "--revolutions", "1000000"], "limit of 1,000"),
    (["simulate", "--points", "1000000000"], "limit of 1,000,000"),
    (["scene", str(SCENE), "--cycle", "--points", "100000"], "limit of 1,440"),
])
def test_time_domain_and_cycle_sizes_are_bounded(argv, needle, capsys):
    assert_user_error(argv, capsys, needle)


def test_formula_on_a_large_network_without_a_tree_is_refused_at_once(tmp_path, capsys):
    pytest.importorskip("sympy")
    lines = ["drive V n0_0 0 velocity=1"]
    k = 0
    for i in range(3):
        for j in range(3):
            n = f"n{i}_{j}"
            if j < 2:
                lines.append(f"spring k{k} {n} n{i}_{j + 1} {100 + k}")
                k += 1
            if i < 2:
                lines.append(f"damper c{k} {n} n{i + 1}_{j} {1 + k}")
                k += 1
            lines.append(f"mass m{k} {n} 0 {1 + k}")
            k += 1
    path = tmp_path / "grid.mcir"
    path.write_text("\n".join(lines) + "\n")
    t0 = time.perf_counter()
    assert_user_error(["formula", path], capsys, "21 elements", "--method nodal")
    assert time.perf_counter() - t0 < 10


def test_formula_bridge_by_cramer_matches_a_numeric_solve():
    """The determinant form equals K from an independent dense complex solve at sampled ω."""
    sp = pytest.importorskip("sympy")
    import numpy as np

    import mechcirc
    from mechcirc.interop.formula import formula_and_values

    text = ("spring k1 a b 1000\nspring k2 a c 2000\ndamper c3 b c 5\nmass m4 b 0 1\n"
            "mass m5 c 0 2\nspring k6 c 0 300\ndrive V a 0 velocity=1\n")
    K, values = formula_and_values(mechcirc.parse(text))
    f = sp.lambdify(sp.Symbol("omega", positive=True), K.subs(values), "numpy")
    for w in (0.7, 13.0, 55.5, 400.0):
        # Nodal admittance (velocity drive: unit velocity at a; K = v/Q = 1/Q):
        # unknown node velocities b, c; force at a from the elements at a.
        yk = lambda k: k / (1j * w)                                     # noqa: E731
        A = np.array([[yk(1000) + 5 + 1j * w * 1, -5],
                      [-5, yk(2000) + 5 + 1j * w * 2 + yk(300)]])
        rhs = np.array([yk(1000), yk(2000)])
        vb, vc = np.linalg.solve(A, rhs)
        Q = yk(1000) * (1 - vb) + yk(2000) * (1 - vc)
        assert abs(complex(f(w)) - 1 / Q) <= 1e-12 * abs(1 / Q)


# ------------------------------------------------------------------ §4 study output safety
def _tiny_spec(tmp_path, n=6):
    from mechcirc.study import parse_spec

    net = tmp_path / "n.mcir"
    net.write_text(".param m=2\nmass m1 a 0 m\nspring k a 0 100\ndrive V a 0 velocity=1\n")
    return parse_spec({"netlist": str(net), "omega": {"min": 1, "max": 30, "points": 7},
                       "grid": {"m": [1.0 + i for i in range(n)]}}, source="t.toml")


def test_study_keeps_the_old_output_until_the_new_one_is_complete(tmp_path):
    from mechcirc.study import journal_path, run_study

    spec = _tiny_spec(tmp_path)
    out = tmp_path / "out.csv"
    out.write_text("old table\n")
    seen = []

    def stop(n):
        seen.append(n)
        assert out.read_text() == "old table\n"          # untouched while running
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(spec, output=out, workers=1, batch_size=1, on_rows=stop)
    assert out.read_text() == "old table\n"
    assert Path(journal_path(out)).exists()
    r = run_study(spec, output=out, workers=1, resume=True)
    assert r.skipped == 2 and not Path(journal_path(out)).exists()
    assert out.read_text().startswith("index,m,status")


def test_resume_recomputes_every_cut_journal_row(tmp_path):
    """Cut the journal at every byte of its last row: each resume gives the full table."""
    from mechcirc.study import journal_path, run_study

    spec = _tiny_spec(tmp_path, n=3)
    full = tmp_path / "full.csv"
    run_study(spec, output=full, workers=1)
    out = tmp_path / "out.csv"
    seen = []

    def stop(n):
        seen.append(n)
        if len(seen) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(spec, output=out, workers=1, batch_size=1, on_rows=stop)
    journal = Path(journal_path(out))
    whole = journal.read_bytes()
    last_start = whole.rstrip(b"\n").rfind(b"\n") + 1
    cuts = range(last_start, len(whole))
    for cut in cuts:
        journal.write_bytes(whole[:cut])
        r = run_study(spec, output=out, workers=1, resume=True)
        assert out.read_bytes() == full.read_bytes(), cut
        # The row cut short was run again, never kept truncated; a row that
        # lost only its line terminator is complete (its checksum says so).
        complete = whole[cut:].strip(b"\r\n") == b""
        assert r.skipped == (3 if complete else 2), (cut, r.skipped)


def test_resume_from_a_finished_table_with_a_damaged_row(tmp_path):
    from mechcirc.study import read_rows, run_study

    spec = _tiny_spec(tmp_path, n=3)
    out = tmp_path / "out.csv"
    run_study(spec, output=out, workers=1)
    good = out.read_bytes()
    rows = list(csv.reader(good.decode().splitlines()))
    rows[2][-2] = "n"                                   # a cut 'nan' or number
    out.write_text("\n".join(",".join(r) for r in rows) + "\n")
    assert len(read_rows(out, spec.columns)) == 2
    r = run_study(spec, output=out, workers=1, resume=True)
    assert r.skipped == 2 and out.read_bytes() == good


def _children(pid):
    try:
        out = subprocess.run(["ps", "-o", "pid=", "--ppid", str(pid)], capture_output=True,
                             text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError):
        pytest.skip("ps is not available")
    return [int(x) for x in out.split()]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux process table")
def test_study_workers_die_with_their_parent(tmp_path):
    net = tmp_path / "n.mcir"
    net.write_text(".param m=2\nmass m1 a 0 m\nspring k a 0 100\ndrive V a 0 velocity=1\n")
    spec = tmp_path / "s.toml"
    spec.write_text(f'netlist = "{net}"\n[omega]\nmin = 1\nmax = 30\npoints = 100000\n'
                    "[grid]\nm = {min = 1, max = 2, num = 4000}\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-m", "mechcirc", "study", str(spec), "-o",
                             str(tmp_path / "o.csv"), "--workers", "2"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = []
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(workers) < 2:
        time.sleep(0.2)
        workers = _children(proc.pid)
        if proc.poll() is not None:
            pytest.skip("the study finished before it could be killed")
    assert len(workers) >= 2
    proc.kill()
    proc.wait()
    deadline = time.monotonic() + 10
    alive = workers
    while alive and time.monotonic() < deadline:
        time.sleep(0.2)
        alive = [w for w in alive if _alive(w)]
    assert not alive, f"workers {alive} outlived their parent"


def _alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


# ------------------------------------------------------------------ §4 start-up interrupt
def test_sigint_during_start_up_prints_no_mechcirc_traceback(tmp_path):
    """Ctrl-C at any moment of start-up: 'interrupted' or done, never a traceback from
    mechcirc's code (Python's own first few tens of ms are outside mechcirc's reach)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    for delay in (0.12, 0.2, 0.3, 0.45):
        p = subprocess.Popen([sys.executable, "-m", "mechcirc", "check", STB], env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        time.sleep(delay)
        p.send_signal(signal.SIGINT)
        err = p.communicate(timeout=60)[1].decode()
        if "Traceback" in err:
            # Only Python's own start-up (site, the import system) may be in it.
            assert f'File "{ROOT / "mechcirc"}' not in err, err
        elif p.returncode == -signal.SIGINT:
            # Killed by the default action before the interpreter installed its own
            # handler (seen under load): nothing may have been printed.
            assert err == "", err
        else:
            assert p.returncode in (0, 130), (p.returncode, err)
