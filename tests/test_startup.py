"""What a single command pays before it computes: lazy imports and no compile wait.

The speed itself is measured by ``benchmarks/bench_startup.py`` and
``benchmarks/bench_bound_cost.py``; these tests check only what those
speed-ups must not change: which modules a sweep loads, and that the default
path gives the numpy path's numbers, bit for bit, while numba's cache is cold.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import _jit, _tree_eval, reduction
from reference.inputs import STB

ROOT = Path(__file__).resolve().parents[1]


def test_a_sweep_with_flags_loads_no_scipy_matplotlib_or_numba(light_imports):
    # load + sweep + error bound + flags: the frequency-domain core is numpy only
    # (one process with the other light-import checks: tests/conftest.py, light_imports).
    loaded = {m.split(".")[0] for m in light_imports["sweep with flags"]}
    assert not loaded & {"scipy", "matplotlib", "numba", "networkx", "pandas"}, loaded


@pytest.fixture
def cold_kernel(monkeypatch):
    """The default path as in a fresh process whose numba cache holds no kernel;
    returns the list of warm-up statements started (recorded, none run)."""
    from mechcirc import nodal

    started = []
    monkeypatch.setattr(_jit, "COMPILED", None)
    monkeypatch.setattr(_tree_eval, "_KERNEL", [])
    monkeypatch.setattr(nodal, "_KERNELS", [])
    monkeypatch.setattr(_tree_eval, "KERNEL_MIN_WORK", 1)      # every call is "large"
    monkeypatch.setattr(nodal, "KERNEL_MIN_WORK", 1)
    monkeypatch.setattr(_jit, "in_cache", lambda *dispatchers: False)
    monkeypatch.setattr(_jit, "warm_in_background", started.append)
    return started


def _numpy_path(tree, omega, error):
    saved = _jit.COMPILED
    _jit.COMPILED = False
    try:
        return reduction.evaluate(tree, omega, error=error)
    finally:
        _jit.COMPILED = saved


def _corpus():
    sys.path.insert(0, str(ROOT / "tests"))
    from reference import sp_corpus

    rng = np.random.default_rng(26)
    trees = [sp_corpus.random_tree(rng, int(rng.integers(1, 30)), damped=d)
             for _ in range(15) for d in (0.0, 0.3)]
    return [sp_corpus.to_circuit(t) for t in trees] + \
        [mechcirc.load(ROOT / "netlists" / n) for n in ("stb_heald.mcir", "heald_damped.mcir")]


def test_a_cold_kernel_is_not_waited_for(cold_kernel):
    pytest.importorskip("numba")
    omega = np.concatenate([[0.0, np.inf], np.geomspace(1e-2, 1e4, 50)])
    for c in _corpus():
        K, rho = reduction.evaluate(c.tree, omega, error=True)
        K0, rho0 = _numpy_path(c.tree, omega, True)
        # Not the compiled kernel (a few ulps apart), the numpy path itself, to the bit.
        assert K.tobytes() == K0.tobytes() and rho.tobytes() == rho0.tobytes()
        assert reduction.evaluate(c.tree, omega).tobytes() == K0.tobytes()
        s = c.sweep(omega[2:])
        assert s.error.tobytes() == _numpy_path(c.tree, omega[2:], True)[1].tobytes()
    # A warm-up process asked for (once per process: warm_in_background's own
    # set, replaced here by the recording list), nothing compiled here.
    assert set(cold_kernel) == {"from mechcirc._tree_eval import warm_kernel; warm_kernel()"}
    assert _tree_eval._KERNEL == []


def test_a_cached_kernel_is_loaded(cold_kernel, monkeypatch):
    pytest.importorskip("numba")
    monkeypatch.setattr(_jit, "in_cache", lambda *dispatchers: True)
    c = mechcirc.load(STB)
    omega = np.linspace(10, 1000, 40)
    K, rho = reduction.evaluate(c.tree, omega, error=True)
    assert _tree_eval._KERNEL and _tree_eval._KERNEL[0] is not None
    assert cold_kernel == []
    _jit.COMPILED = True
    K1, rho1 = reduction.evaluate(c.tree, omega, error=True)
    assert K.tobytes() == K1.tobytes() and rho.tobytes() == rho1.tobytes()


def test_the_cache_check_sees_numbas_index(monkeypatch):
    numba = pytest.importorskip("numba")
    monkeypatch.delenv("MECHCIRC_NO_WARM", raising=False)     # (the suite sets it)

    @numba.njit(cache=True)
    def never_compiled(x):      # defined here, compiled nowhere: not in any cache
        return x + 0.5

    assert _jit.in_cache(never_compiled) is False
    assert _jit.in_cache(object()) is True      # no cache to ask: load as before
    monkeypatch.setenv("MECHCIRC_NO_WARM", "1")  # the rule off: compile on first use
    assert _jit.in_cache(never_compiled) is True


def test_a_cold_nodal_sweep_runs_numpy(cold_kernel):
    pytest.importorskip("numba")
    from mechcirc import nodal

    # A bridge (not series-parallel) past the dense limit: the sparse path.
    n = nodal.DENSE_LIMIT + 10
    lines = ["drive V a 0 velocity=1", "damper c a 0 2", "spring kb a n5 300"]
    lines += [f"mass m{i} {'a' if i == 0 else f'n{i}'} n{i + 1} {1 + i % 3}\n"
              f"spring k{i} n{i + 1} 0 {1e3 + i}" for i in range(n)]
    c = mechcirc.parse("\n".join(lines))
    omega = np.geomspace(1.0, 1e3, 30)
    K = nodal.mobility(c.nodal, omega)
    saved = _jit.COMPILED
    _jit.COMPILED = False
    try:
        K0 = nodal.mobility(c.nodal, omega)
    finally:
        _jit.COMPILED = saved
    assert K.tobytes() == K0.tobytes()
    assert set(cold_kernel) == {"from mechcirc.nodal import warm_kernels; warm_kernels()"}
    assert nodal._KERNELS == []


def test_the_warm_up_statements_run(cold_kernel, warm_up_run):
    pytest.importorskip("numba")
    from mechcirc import nodal

    c = mechcirc.load(STB)
    reduction.evaluate(c.tree, np.linspace(10, 1000, 5))
    lines = ["drive V a 0 velocity=1", "damper c a 0 2"]
    lines += [f"mass m{i} {'a' if i == 0 else f'n{i}'} n{i + 1} 1\nspring k{i} n{i + 1} 0 1e3"
              for i in range(nodal.DENSE_LIMIT + 5)]
    nodal.mobility(mechcirc.parse("\n".join(lines)).nodal, np.array([1.0, 2.0]))
    assert len(set(cold_kernel)) == 2
    # Each as the detached process runs it, here with numba's JIT off (the same
    # calls as plain Python, no compile), in the one process of every warm-up
    # statement (tests/conftest.py, warm_up_run; a statement missing there is a
    # KeyError: add it to the list): they import and run without error.
    for statement in sorted(set(cold_kernel)):
        assert warm_up_run[statement]["error"] is None, warm_up_run[statement]


def test_a_cold_kernel_batch_of_designs_runs_numpy(cold_kernel):
    pytest.importorskip("numba")
    from mechcirc import designs

    text = (".param k=1000\nmass m a b 1\nspring s b 0 k\ndamper c a 0 0.3\n"
            "mass m2 a 0 2\ndrive V a 0 velocity=1\n")
    params = {"k": np.geomspace(1e2, 1e4, 5)}
    omega = np.linspace(10, 1000, 40)
    s = designs(text, params).sweep(omega)
    assert _tree_eval._KERNEL == []            # nothing compiled here
    assert set(cold_kernel) == {"from mechcirc._tree_eval import warm_kernel; warm_kernel()"}
    _jit.COMPILED = False
    ref = designs(text, params).sweep(omega)
    assert s.K.tobytes() == ref.K.tobytes() and s.error.tobytes() == ref.error.tobytes()


def test_warm_in_background_runs_once_in_a_process_importing_this_copy(tmp_path, monkeypatch):
    import time

    monkeypatch.setattr(_jit, "_WARMING", set())
    monkeypatch.delenv("MECHCIRC_NO_WARM", raising=False)      # (the suite sets it)
    out = tmp_path / "where.txt"
    statement = ("import pathlib, mechcirc._jit as j; "
                 f"pathlib.Path({str(out)!r}).open('a').write(j.__file__ + '\\n')")
    _jit.warm_in_background(statement)
    _jit.warm_in_background(statement)          # once per process: not started again
    assert _jit._WARMING == {statement}
    for _ in range(6000):                       # a detached child: wait for its file
        if out.exists() and out.read_text().endswith("\n"):
            break
        time.sleep(0.1)
    lines = out.read_text().splitlines()
    assert lines == [str(Path(_jit.__file__).resolve())]


def test_no_warm_up_process_when_the_environment_says_so(monkeypatch):
    # MECHCIRC_NO_WARM=1: no detached process, and every kernel counts as cached
    # (compiled in-process on first use, numba's own default).
    import subprocess

    started = []
    monkeypatch.setattr(_jit, "_WARMING", set())
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: started.append(a))
    monkeypatch.setenv("MECHCIRC_NO_WARM", "1")
    _jit.warm_in_background("pass")
    assert started == [] and _jit._WARMING == set()
    monkeypatch.setenv("MECHCIRC_NO_WARM", "0")               # 0 or empty: warm as usual
    _jit.warm_in_background("pass")
    assert len(started) == 1 and _jit._WARMING == {"pass"}


def test_the_kernel_decision_counts_the_plan_without_building_it():
    # KERNEL_MIN_WORK is plan nodes × points: the count must be the plan's own.
    for c in _corpus() + [mechcirc.parse("drive V a 0 velocity=1\nmass m a 0 2\n"),
                          mechcirc.parse("drive V a 0 velocity=1\nlever L a 0 b 0 ratio=0.5\n"
                                         "spring k b 0 100\nmass m a 0 1\n")]:
        assert _tree_eval._plan_size(c.tree) == _tree_eval.plan(c.tree).kind.size


def _cli_modules(tmp_path, *extra):
    """The modules a ``mechcirc sweep`` of the bundled netlist loaded, and its output."""
    argv = ["mechcirc", "sweep", str(STB), "--omega-min", "10", "--omega-max", "10000",
            "--points", "400", "--log", "-o", str(tmp_path / "x.csv"), *extra]
    code = ("import sys, json, runpy\n"
            f"sys.argv = {argv!r}\n"
            "try:\n    runpy.run_module('mechcirc', run_name='__main__')\n"
            "except SystemExit as e:\n    status = e.code\n"
            "print(json.dumps([status, sorted(sys.modules)]))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT, timeout=600)
    *shown, last = out.stdout.splitlines()
    status, modules = json.loads(last)
    return status, set(modules), "\n".join(shown)


def test_the_sweep_command_with_its_exact_peak_loads_no_scipy(tmp_path):
    status, modules, shown = _cli_modules(tmp_path)
    assert status == 0
    # The exact peak was computed (the resonances), with numpy only.
    assert "undamped resonance at omega = 706.4543132, 915.0454617, 3641.187913" in shown
    tops = {m.split(".")[0] for m in modules}
    assert not tops & {"scipy", "matplotlib", "pandas", "networkx"}, tops
    assert "numpy.ma" not in modules        # np.unique / setdiff1d would import it
    # Only the sweep's own command module is imported and its parsers built.
    assert {m for m in modules if m.endswith("_commands")} == {"mechcirc.cli.circuit_commands"}


def test_the_sweep_plot_uses_no_pyplot_and_no_scipy(tmp_path):
    """``python -m mechcirc sweep ... -o CSV --plot PNG`` in a process of its own (its
    start-up as the command's): exit 0, the CSV's columns the API's sweep to the bit, a
    PNG, drawn without pyplot or SciPy.  (The CSV and PNG checks were a second process,
    tests/test_cli.py's test_sweep_by_subprocess_writes_csv_and_png: 1.3 s of CPU in CI.)"""
    status, modules, _ = _cli_modules(tmp_path, "--plot", str(tmp_path / "x.png"))
    assert status == 0 and (tmp_path / "x.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "matplotlib.backends.backend_agg" in modules
    assert not {"matplotlib.pyplot", "scipy"} & modules
    with open(tmp_path / "x.csv", newline="") as fh:
        header, *rows = list(csv.reader(fh))
    table = np.array(rows, dtype=float)
    assert ",".join(header) == "omega,K_re,K_im,Q0_re,Q0_im,flag" and table.shape == (400, 6)
    s = mechcirc.load(STB).sweep(np.geomspace(10, 1e4, 400))
    np.testing.assert_array_equal(table[:, 1] + 1j * table[:, 2], s.K)


def _systems():
    from mechcirc import nodal

    for c in _corpus():
        s = nodal.assemble(c)
        yield s
        yield nodal.held(s)
        yield nodal.assemble(c, whole=True)


def test_the_scipy_free_dense_matrices_are_the_sparse_ones():
    from mechcirc.nodal import KINDS

    n_lever = 0
    for s in _systems():
        n_lever += bool(len(s.stamps["lever"][0]))
        for k in KINDS:
            # Summed in the same order: equal to the bit (sign of zero aside).
            assert np.array_equal(s.dense(k), s.sparse(k).toarray())
            assert np.array_equal(s.diagonal(k), s.sparse(k).diagonal())
        assert s.size == s.M.shape[0] == s.dense("mass").shape[0]
    assert n_lever >= 3                       # the corpus has levers, and held systems


def test_the_scipy_free_constraint_basis_is_the_pivoted_qr_one():
    from mechcirc.resonances import constraint_basis

    rng = np.random.default_rng(7)
    rows = [np.array([[1.0, 0, -1, 0]]), np.array([[0, -1.0, 0, 1]]),
            np.array([[0.0, 0, 0, 0]]), np.array([[0.0, 1, 0, 0]])]
    rows += [np.where(rng.random((1, 6)) < 0.4, 0.0, rng.standard_normal((1, 6)))
             for _ in range(30)]
    rows += [np.round(rng.standard_normal((1, 5)), 1) for _ in range(30)]    # ties
    for G in rows + [np.zeros((0, 4))]:
        n = G.shape[1]
        Zd, Zs = constraint_basis(G, n, dense=True), constraint_basis(G, n).toarray()
        assert Zd.shape == Zs.shape and np.array_equal(Zd, Zs), G
        if Zd.size:
            assert np.abs(G @ Zd).max(initial=0.0) <= 1e-15 * np.abs(G).max(initial=1.0)


def test_small_undamped_resonances_without_scipy_agree_with_the_sparse_path(monkeypatch):
    from mechcirc import nodal
    from mechcirc.resonances import find_resonances

    compared = 0
    for c in _corpus():
        if any(e.kind == "damper" for e in c.elements) or c.nodal.size > nodal.DENSE_LIMIT:
            continue
        dense = find_resonances(c)
        with monkeypatch.context() as m:
            m.setattr(nodal, "DENSE_LIMIT", -1)          # the sparse (scipy) pencil
            ref = find_resonances(c)
        assert [r.kind for r in dense] == [r.kind for r in ref]
        for a, b in zip(dense, ref):
            # Both are polished on K; they differ only by where polishing started.
            assert abs(a.omega - b.omega) <= (a.error + b.error) * b.omega, (a, b)
        compared += len(ref)
    assert compared >= 20


def _subcommands(parser):
    import argparse

    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices


def test_the_command_table_names_the_module_of_every_command():
    # mechcirc CMD builds only COMMANDS[CMD]'s parsers: the table must say where
    # each command is registered, and name every one.
    import argparse
    import importlib

    from mechcirc.cli import COMMAND_MODULES, COMMANDS

    where = {}
    for name in COMMAND_MODULES:
        sub = argparse.ArgumentParser().add_subparsers()
        importlib.import_module(name).register(sub)
        where.update(dict.fromkeys(sub.choices, name))
    assert COMMANDS == where


def test_a_commands_own_parser_reads_and_helps_as_the_full_one():
    import shlex

    from mechcirc.cli import COMMANDS, build_parser

    full = build_parser()
    for name in COMMANDS:
        own = build_parser(name)
        assert list(_subcommands(own)) == [c for c in _subcommands(full)
                                           if COMMANDS[c] == COMMANDS[name]]
        assert _subcommands(own)[name].format_help() == _subcommands(full)[name].format_help()
        # The example of the command's help, parsed by both: the same values.
        line = next(t for t in (_subcommands(full)[name].epilog or "").splitlines()
                    if "mechcirc " in t)
        argv = shlex.split(line.split("mechcirc ", 1)[1])
        assert vars(own.parse_args(argv)) == vars(full.parse_args(argv))


@pytest.mark.parametrize("argv", [
    ["sweep", "x.mcir", "--omega-min", "1", "--omega-max", "2", "--plto", "a.png"],
    ["sweep", "--points", "many", "x.mcir"],
    ["sweep", "x.mcir"],
    ["--debug", "resonances", "x.mcir", "--omega-maks", "3"],
    ["transient", "--bogus"],
    ["swep", "x.mcir"],
])
def test_a_usage_error_reads_as_with_the_full_parser(argv, capsys):
    from mechcirc.cli import build_parser, main

    with pytest.raises(SystemExit) as exit_:
        main(argv)
    got = capsys.readouterr().err
    with pytest.raises(SystemExit) as full_exit:
        build_parser().parse_args(argv)
    assert exit_.value.code == full_exit.value.code == 2
    assert got == capsys.readouterr().err and "error" in got


def test_the_sweep_figure_builds_only_the_ticks_it_shows_and_one_legend(tmp_path):
    # The PNG command's figure: the log axes' major ticks are the decades inside
    # the view (a Tick object each, none beyond), labelled as before; the |Q0|
    # panel has one legend with the roots' lines and the peak's markers.
    import math

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from mechcirc._sweep import peak
    from mechcirc.plotting import plot_sweep

    c = mechcirc.load(STB)
    s = c.sweep(np.geomspace(10, 1e4, 400))
    found = c.resonances(omega_max=1e4 * (1 + 1e-9))
    fig = plot_sweep(s, resonances=found, peak=peak(s, resonances=found))
    FigureCanvasAgg(fig).draw()
    ax_k, ax_p, ax_q = fig.axes
    # the panels above the last have no x ticks (their decades: grid lines and tick
    # markers, tests/test_plotting.py)
    assert len(ax_k.xaxis.get_majorticklocs()) == len(ax_p.xaxis.get_majorticklocs()) == 0
    for axis in (ax_q.xaxis, ax_k.yaxis, ax_q.yaxis):
        lo, hi = sorted(axis.get_view_interval())
        locs = list(axis.get_majorticklocs())
        exponents = [math.log10(t) for t in locs]
        decades = range(math.ceil(math.log10(lo)), math.floor(math.log10(hi)) + 1)
        # every decade, or (a tall axis) every other one: all inside the view
        assert all(lo <= t <= hi for t in locs)
        assert {round(e) for e in exponents} <= set(decades)
        assert max(abs(e - round(e)) for e in exponents) < 1e-12
        assert len(locs) >= len(decades) // 2 >= 1
        assert len(axis.majorTicks) == len(locs)
        shown = [t.label1.get_text() for t in axis.majorTicks if t.label1.get_visible()]
        assert all(t.startswith("10") for t in shown)
    assert list(ax_q.xaxis.get_majorticklocs()) == [10.0, 100.0, 1e3, 1e4]
    assert [t.get_text() for t in ax_q.get_xticklabels()] == ["10¹", "10²", "10³", "10⁴"]
    assert list(ax_p.yaxis.get_majorticklocs()) == [-180, -90, 0, 90, 180]
    assert [t.get_text() for t in ax_q.get_legend().get_texts()] == \
        ["resonance (K = 0, at ω_d)", "anti-resonance (K = ∞, at ω_d)", "|Q0| = ∞ (undamped)"]
    assert ax_k.get_legend() is None and ax_p.get_legend() is None


@pytest.mark.parametrize("unit", ["rad/s", "Hz"])
def test_the_csv_rows_are_those_numpy_savetxt_writes(tmp_path, unit):
    # The sweep CSV formats its rows itself (faster): byte for byte what
    # np.savetxt writes for the same columns, also for a force drive, an extra
    # column with nan and tiny values, and the flags of points on a pole.
    import io
    import math

    from mechcirc.io_csv import write_sweep_csv

    f = mechcirc.parse("drive F a 0 force=2\nmass m a 0 1\nspring k a 0 1e4\ndamper d a 0 0.5")
    for circuit, omega in ((mechcirc.load(STB), np.geomspace(10, 1e4, 400)),
                           (f, np.concatenate([[0.0], np.linspace(1, 200, 250), [100.0]]))):
        s = circuit.sweep(omega)
        extra = {"x": np.abs(s.K) * 1e-300, "y": np.where(omega > 50, np.nan, omega)}
        write_sweep_csv(s, tmp_path / "s.csv", unit=unit, extra=extra)
        columns = [omega / (1 if unit == "rad/s" else 2 * math.pi), s.K.real, s.K.imag,
                   s.Q0.real, s.Q0.imag]
        columns += [s.v0.real, s.v0.imag] if circuit is f else []
        columns += [extra["x"], extra["y"], s.flags]
        ref = io.StringIO()
        np.savetxt(ref, np.column_stack(columns), delimiter=",",
                   fmt=["%.17g"] * (len(columns) - 1) + ["%d"])
        header, *rows = (tmp_path / "s.csv").read_text().splitlines(keepends=True)
        assert header.startswith("omega," if unit == "rad/s" else "f_Hz,")
        assert header.endswith(",x,y,flag\n")
        assert "".join(rows) == ref.getvalue()
    assert s.flags.any()                # the force drive's grid has flagged points


_BLAS_CHILD = """
import json, os, sys
sys.argv = ["mechcirc", "check", {stb!r}]
import mechcirc.cli as cli
numpy_then = []
set_blas = cli.one_blas_thread
def spy(environ):
    numpy_then.append("numpy" in sys.modules)
    return set_blas(environ)
cli.one_blas_thread = spy
status = cli.main()
print(json.dumps([status, os.environ.get("OPENBLAS_NUM_THREADS"), numpy_then,
                  "numpy" in sys.modules]))
"""


@pytest.mark.parametrize("given", [None, "3"])
def test_the_command_line_asks_for_one_blas_thread_unless_the_user_chose(given):
    # The process's own command line sets OPENBLAS_NUM_THREADS=1 before numpy is
    # imported (OpenBLAS reads it then), and keeps a value the user set.
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    out = subprocess.run([sys.executable, "-c", _BLAS_CHILD.format(stb=str(STB))],
                         capture_output=True, text=True, check=True, cwd=ROOT, env=env,
                         timeout=600)
    status, threads, numpy_then, numpy_after = json.loads(out.stdout.splitlines()[-1])
    assert status == 0 and numpy_then == [False] and numpy_after
    assert threads == ("1" if given is None else given)


def test_one_blas_thread_leaves_a_users_choice_and_a_host_program_alone(monkeypatch, capsys):
    from mechcirc.cli import BLAS_THREAD_VARIABLES, main, one_blas_thread

    env: dict[str, str] = {}
    assert one_blas_thread(env) and env == {"OPENBLAS_NUM_THREADS": "1"}
    for name in BLAS_THREAD_VARIABLES:      # any count the user gave OpenBLAS stands
        env = {name: "2"}
        assert not one_blas_thread(env) and env == {name: "2"}
    # A program calling main(argv), or main() after numpy is loaded: its environment
    # is not touched.
    for name in BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    assert main(["check", str(STB)]) == 0
    monkeypatch.setattr(sys, "argv", ["mechcirc", "check", str(STB)])
    assert main() == 0
    capsys.readouterr()
    assert not set(BLAS_THREAD_VARIABLES) & set(os.environ)


def test_a_parse_reads_its_own_line_not_the_last_ones(capsys):
    """The 'is not an option' hint of a missing required argument names the words of the
    line being parsed: a parser built after main() ran another line does not carry them."""
    from mechcirc.cli import build_parser, main

    with pytest.raises(SystemExit):
        main(["forces", "x.mcir", "--omga", "3"])
    assert "--omga is not an option" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        build_parser().parse_args(["forces", "x.mcir"])
    err = capsys.readouterr().err
    assert "required" in err and "--omga" not in err
