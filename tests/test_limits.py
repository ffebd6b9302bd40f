"""mechcirc.limits — bounded work: hostile sizes finish within a bound or are refused quickly.

Expressions, netlist lines, sweep points per output, time-domain and cycle
sizes, study axes and grids: each limit is checked where it refuses.

The large cases (a 10⁶-element netlist, a 10⁷-point sweep) are measured in
``benchmarks/bench_bounds.py``; here are the quick ones.  Bounds are on CPU
time (``bounds.cpu_seconds_below``: a loaded machine stretches the wall clock,
not the work), generous but far below what the unbounded work would take; the
measured times are in ``docs/reliability.md``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mechcirc
import importlib
sweep_module = importlib.import_module("mechcirc._sweep")
from mechcirc.cli import main
from mechcirc.errors import NetlistError
from mechcirc.expressions import MAX_DEPTH, MAX_LENGTH, evaluate, parse_expression
from mechcirc.netlist import MAX_LINE_LENGTH
from bounds import cpu_seconds_below
from cli_helpers import assert_user_error
from reference.inputs import STB


def _refused(text: str, seconds: float = 1.0) -> NetlistError:
    """Refused with a NetlistError in under ``seconds`` of CPU (measured: ≤ 0.02 s)."""
    with cpu_seconds_below(seconds), pytest.raises(NetlistError) as err:
        mechcirc.parse(text)
    return err.value


def test_tower_of_powers_is_refused_at_its_operator():
    err = _refused("drive V a 0 velocity=1\nmass m a 0 {9**9**9}\n")
    assert err.message == "9.0 ** 387420489.0 overflows float64"
    assert (err.line, err.col) == (2, 14)


def test_nesting_beyond_the_depth_limit_is_refused_with_the_limit():
    deep = "(" * (MAX_DEPTH + 1) + "1" + ")" * (MAX_DEPTH + 1)
    err = _refused(f"drive V a 0 velocity=1\nmass m a 0 {{{deep}}}\n")
    assert err.message == f"expression nested more than {MAX_DEPTH} levels deep"
    assert (err.line, err.col) == (2, 13 + MAX_DEPTH)      # the first '(' too many
    ok = "(" * (MAX_DEPTH - 1) + "2" + ")" * (MAX_DEPTH - 1)
    assert evaluate(parse_expression(ok), {}) == 2.0
    minus = "-" * (MAX_DEPTH + 1) + "1"
    with pytest.raises(NetlistError, match=f"more than {MAX_DEPTH} levels"):
        parse_expression(minus)


def test_a_million_nested_parentheses_are_refused_by_length_at_once():
    text = "(" * 10**6 + "1" + ")" * 10**6
    with cpu_seconds_below(0.5), \
            pytest.raises(NetlistError, match=f"2000001 characters long, the limit is {MAX_LENGTH}"):
        parse_expression(text)                  # 0.003 s of CPU when measured


@pytest.mark.parametrize("literal", ["1" * 5000, "1e999999999", "9" * 309 + ".0"])
def test_literals_beyond_float64_are_refused(literal):
    err = _refused(f"drive V a 0 velocity=1\nmass m a 0 {literal}\n")
    assert "is too large for float64" in err.message and err.expected == \
        "a magnitude below 1.8e308"
    assert (err.line, err.col) == (2, 12)


def test_literal_below_float64_underflows_to_zero_and_is_refused_as_not_positive():
    err = _refused("drive V a 0 velocity=1\nmass m a 0 1e-400\n")
    assert err.message == "mass 'm' must be > 0 kg, got 0"


def test_ten_megabyte_line_is_refused_quickly_with_the_limit():
    line = "mass m a 0 " + "1" * (10 * 2**20)
    err = _refused(f"drive V a 0 velocity=1\n{line}\n", seconds=1.0)
    assert err.message == (f"line is {len(line)} characters long, the limit is "
                           f"{MAX_LINE_LENGTH}")
    assert (err.line, err.col) == (2, 1)


def test_long_flat_expression_within_the_limit_evaluates():
    text = "+".join(["1"] * 5000)                   # 9999 characters, a 5000-deep tree
    assert len(text) < MAX_LENGTH
    # A guard against quadratic or worse behaviour (0.03 s of CPU when measured), not a
    # speed test: CPU time, since 1 s of wall clock failed once at load 9 on 2 cores.
    with cpu_seconds_below(3.0):
        assert evaluate(parse_expression(text), {}) == 5000.0


def test_cli_refuses_more_than_ten_million_points(capsys, tmp_path):
    assert main(["sweep", str(STB), "--omega-min", "1", "--omega-max", "2",
                 "--points", "10000001"]) == 2
    assert "--points must be between 2 and 10000000 (a sweep spans --omega-min to --omega-max), got 10000001" in capsys.readouterr().err


def test_chunked_sweep_equals_one_piece(monkeypatch):
    """The series–parallel evaluation runs in chunks of CHUNK_POINTS; results are identical."""
    c = mechcirc.load(str(STB))
    omega = np.geomspace(1.0, 1e5, 1001)
    whole = c.sweep(omega)
    monkeypatch.setattr(sweep_module, "CHUNK_POINTS", 7)
    parts = c.sweep(omega)
    np.testing.assert_array_equal(parts.K, whole.K)
    np.testing.assert_array_equal(parts.error, whole.error)
    np.testing.assert_array_equal(parts.flags, whole.flags)


def test_tree_sweep_evaluates_in_chunks(monkeypatch):
    """No evaluation of the tree sees more than CHUNK_POINTS frequencies at once."""
    from mechcirc import reduction

    sizes = []
    real = reduction.evaluate

    def spy(tree, omega, **kw):
        sizes.append(np.size(omega))
        return real(tree, omega, **kw)

    monkeypatch.setattr(sweep_module, "evaluate", spy)
    monkeypatch.setattr(sweep_module, "CHUNK_POINTS", 1000)
    c = mechcirc.load(str(STB))
    s = c.sweep(np.linspace(1.0, 1e4, 4500))
    _ = s.flags
    assert max(sizes) == 1000 and sum(sizes) == 2 * 4500     # K, then the error estimate


def _chain(n: int, damped: bool) -> str:
    lines = ["drive V n0 0 velocity=1"]
    for i in range(n):
        lines.append(f"mass m{i} n{i} 0 {1 + i % 3}")
        lines.append(f"spring k{i} n{i} n{i + 1} {1000 + i % 7}")
    if damped:
        lines.append("damper c n0 0 0.5")
    return "\n".join(lines) + f"\nspring kend n{n} 0 100\n"


@pytest.mark.parametrize("damped, n", [(False, 2000), (True, 500)])
def test_resonances_of_a_network_beyond_the_size_limit_are_refused_at_once(damped, n,
                                                                           monkeypatch):
    """Refused before any eigen-solver runs (checked by making every solver fail if
    reached, not by a clock: a fresh environment's first solve also compiles)."""
    import mechcirc.resonances as res
    from mechcirc.errors import SolverError

    def reached(*args, **kwargs):
        raise AssertionError("an eigen-solver ran before the size check")

    for name in ("_undamped", "_damped", "_band_modes"):
        monkeypatch.setattr(res, name, reached)
    limit = res.MAX_UNKNOWNS_DAMPED if damped else res.MAX_UNKNOWNS
    c = mechcirc.parse(_chain(n, damped))
    with pytest.raises(SolverError, match=f"{n + 1} unknowns, the limit is {limit}"):
        c.resonances()


def test_sweep_json_of_a_large_network_still_sweeps(tmp_path, capsys):
    path = tmp_path / "chain.mcir"
    path.write_text(_chain(2500, False))
    assert main(["sweep", str(path), "--omega-min", "1", "--omega-max", "10",
                 "--points", "5", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["omega"]) == 5
    assert any("resonance markers left out" in w for w in doc["warnings"])


def _csv_peak(n: int, tmp_path, monkeypatch) -> int:
    """tracemalloc peak [bytes] of write_sweep_csv for an n-point sweep already computed."""
    import tracemalloc

    from mechcirc import io_csv
    from mechcirc.io_csv import write_sweep_csv

    # Formatting is not what is measured (and is slow under tracemalloc): the row
    # formatter only records the block it is given; the buffers the writer builds are
    # measured.
    monkeypatch.setattr(io_csv, "format_rows", lambda X, row: f"{X.shape}\n")
    s = mechcirc.load(STB).sweep(np.geomspace(1.0, 1e4, n))
    _ = s.flags, s.Q0, s.v0                       # computed before measuring
    tracemalloc.start()
    try:
        write_sweep_csv(s, tmp_path / "K.csv")
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_sweep_csv_is_written_in_bounded_memory(tmp_path, monkeypatch):
    """The writer's memory does not grow with the number of points.

    Stacking every column at once took 56 bytes per point (640 MB at 10⁷ points,
    1.14 GB RSS for `mechcirc sweep --points 10000000 -o K.csv`).
    """
    small = _csv_peak(300_000, tmp_path, monkeypatch)
    large = _csv_peak(1_200_000, tmp_path, monkeypatch)
    assert large < 1.5 * small, (small, large)


ROOT = Path(__file__).resolve().parents[1]


SCENE = ROOT / "examples" / "heald_scene.toml"


STUDY = ROOT / "examples" / "study_stb.toml"


def _spec(tmp_path, old, new):
    text = STUDY.read_text().replace("../netlists/", str(ROOT / "netlists") + "/")
    assert old in text, old
    text = text.replace(old, new, 1)
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path, text


def test_study_axis_of_a_billion_values_is_refused_before_it_is_built(tmp_path):
    from mechcirc.study import load_spec

    path, _ = _spec(tmp_path, "num = 6}", "num = 1000000000}")
    with cpu_seconds_below(5), \
            pytest.raises(NetlistError, match="num must be an integer from 1 to 1,000,000"):
        load_spec(path)                         # not a 1e9-element list first


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
    with cpu_seconds_below(10):                     # refused before the sweep
        assert_user_error(["sweep", STB, "--omega-min", "10", "--omega-max", "1e4",
                           "--points", str(limit + 1), *extra], capsys, what, f"{limit}")


@pytest.mark.parametrize("argv, needle", [
    (["simulate", "--revolutions", "1000000"], "limit of 1,000"),
    (["simulate", "--points", "1000000000"], "limit of 1,000,000"),
    (["scene", str(SCENE), "--cycle", "--points", "100000"], "limit of 1,440"),
])
def test_time_domain_and_cycle_sizes_are_bounded(argv, needle, capsys):
    assert_user_error(argv, capsys, needle)
