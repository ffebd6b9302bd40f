"""One test per bug the fuzz harness found (issue 8); each failed before its fix."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import mechcirc
from mechcirc.cli import main
from mechcirc.errors import GeometryError, MechcircError, NetlistError, SolverError, TopologyError
from mechcirc.kinematics.linkage import load_linkage, parse_linkage
from mechcirc.sweep import FLAG_OK

FNF = """
[points]
O1 = [124.0, -27.0]
A  = [124.0, -2.0]
O2 = [76.0, -22.0]
B  = [76.0, -2.0]
C  = [74.0, 85.0]
E  = [126.0, 85.0]
K  = [100.0, 130.0]
O6 = [30.0, 130.0]
[ground]
points = ["O1", "O2", "O6"]
[links]
crank1   = ["O1", "A"]
crank2   = ["O2", "B"]
coupler3 = ["A", "C"]
link4    = ["C", "E", "K"]
coupler5 = ["B", "E"]
output6  = ["O6", "K"]
[[cranks]]
link = "crank1"
omega = 20.0
[[cranks]]
link = "crank2"
omega = -30.0
"""


def test_fnf_text_is_valid():
    assert parse_linkage(FNF).solve(0.3).theta == 0.3


# ----------------------------------------------------------------- linkage files
@pytest.mark.parametrize("table, replacement", [
    ("[points]", "points = 3"), ("[ground]", 'ground = "A"'), ("[links]", "links = [1.0, 2.0]"),
])
def test_table_of_the_wrong_kind_is_a_located_error(table, replacement):
    body = FNF.replace(table + "\n", "[unused_" + table[1:] + "\n")
    with pytest.raises(NetlistError) as err:
        parse_linkage(replacement + "\n" + body, "fnf.toml")
    name = table.strip("[]")
    assert err.value.message.startswith(f"{name!r} must be a {table} table, got ")
    assert (err.value.line, err.value.col) == (1, 1)


@pytest.mark.parametrize("old, new, line, fragment", [
    ('points = ["O1", "O2", "O6"]', 'points = ["O1", "O2", [1.0]]', 12, "in [ground]"),
    ('points = ["O1", "O2", "O6"]', 'points = ["O1", "O2", {a = 1}]', 12, "in [ground]"),
    ('B  = [76.0, -2.0]', 'B  = [1' + '0' * 400 + ', -2.0]', 6, "must be [x, y]"),
    ('omega = 20.0', 'omega = 1' + '0' * 400, 22, "omega must be a nonzero number"),
    ('link = "crank1"', 'link = ["crank1"]', 21, "unknown link"),
])
def test_linkage_value_of_the_wrong_kind_is_a_located_error(old, new, line, fragment):
    text = FNF.replace(old, new, 1)
    assert text != FNF
    with pytest.raises(NetlistError) as err:
        parse_linkage(text, "fnf.toml")
    assert fragment in err.value.message
    assert len(err.value.message) < 200           # huge values are cut short
    assert err.value.line == line and err.value.col >= 1


def test_cranks_must_be_tables():
    text = FNF.split("[[cranks]]")[0].replace("[points]", "cranks = [1, 2]\n[points]")
    with pytest.raises(NetlistError) as err:
        parse_linkage(text, "fnf.toml")
    assert err.value.message == "'cranks' must be a [[cranks]] table, got [1, 2]"
    assert err.value.line == 2


def test_integer_beyond_python_digit_limit_is_a_located_error():
    text = FNF.replace("omega = 20.0", "omega = " + "1" * 5000)
    with pytest.raises(NetlistError, match="thousands of digits") as err:
        parse_linkage(text)
    assert (err.value.line, err.value.col) == (22, 9)


def test_linkage_file_not_utf8_is_located(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_bytes(b'name = "x"\nunits = "\xff"\n')
    with pytest.raises(NetlistError, match="not valid UTF-8") as err:
        load_linkage(path)
    assert (err.value.line, err.value.col) == (2, 10)


def test_tiny_first_crank_speed_is_refused_quickly_not_a_hang():
    lk = parse_linkage(FNF.replace("omega = 20.0", "omega = 1e-300"))
    with pytest.raises(GeometryError, match="continuation steps.*the limit is 100000"):
        lk.solve(0.3)


# ----------------------------------------------------------------- netlists at float64's edges
def test_lever_ratio_above_1e154_does_not_overflow_python_floats():
    c = mechcirc.parse("drive V a 0 velocity=1\nlever L a 0 b 0 ratio=1e300\nmass m b 0 1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = c.sweep([1.0, 10.0])
    # K = K_m / r² = (-j/ω) / 1e600 underflows to 0: flagged, not an OverflowError.
    assert np.all(s.K == 0) and np.all(s.flags == 1)


def test_value_times_eta_underflowing_to_zero_is_flagged():
    c = mechcirc.parse("drive V a 0 velocity=1\nmass m a b 0.4 eta=5e-324\nspring k b 0 10\n")
    s = c.sweep([0.5, 2.0])
    assert np.all(np.isinf(s.K)) and np.all(s.flags == 1)


def test_huge_masses_do_not_break_the_singularity_check():
    # Two masses of 1e308 make trace(M) = inf; the frequency scale must stay finite.
    text = ("drive V a 0 velocity=1\nmass m1 a b 1e308\nmass m2 b c 1e308\nspring k c 0 1e6\n"
            "spring k2 a c 5\nspring k3 b 0 7\n")
    c = mechcirc.parse(text)
    s = c.sweep([1.0, 100.0], method="nodal")
    assert np.all((s.flags != FLAG_OK) | np.isfinite(s.K))
    assert np.isfinite(s.error).all() or np.all(s.flags[~np.isfinite(s.error)] != FLAG_OK)


def test_resonances_of_an_overflowing_product_name_the_element():
    c = mechcirc.parse("drive V a 0 velocity=1\nmass m a b 1e308 eta=1e5\nspring k b 0 1\n")
    with pytest.raises(NetlistError, match="value × eta .* overflows float64") as err:
        c.resonances()
    assert (err.value.line, err.value.col) == (2, 1)


def test_resonance_at_1e_minus_181_rad_per_s_is_found():
    """Scales 1e-200 N/m and 1e181 kg: sqrt(k/m) underflowed to 0 and divided by it."""
    text = ("drive V 0 n2 force=0.1\nspring e1 0 n2 2.2e-200\ndamper e2 0 n2 5.2\n"
            "mass e3 0 n2 3.8e181\n")
    found = mechcirc.parse(text).resonances()
    # Overdamped m, c, k in parallel: s = -c/m (the other root, -k/c, is below the
    # rigid-body cut).  K = 1/(sm + c + k/s) is infinite there: an anti-resonance.
    assert [r.kind for r in found] == ["antiresonance"]
    assert found[0].omega == pytest.approx(5.2 / 3.8e181, rel=1e-12)
    assert found[0].zeta == 1.0


def test_self_looped_lever_with_nothing_loaded_is_a_topology_error():
    text = ("mass e0 n1 0 3\nlever L0 n3 n4 n4 n3 ratio=1\ndamper e1 n3 n1 1\n"
            "drive V n4 n3 force=1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(TopologyError, match="nothing between the drive's nodes"):
            mechcirc.parse(text).sweep([1.0])


# ----------------------------------------------------------------- command line
@pytest.mark.parametrize("argv", [
    ["synth", "--plot", "{d}/x.s1p"],
    ["fourbar", "--crank", "1", "--coupler", "3", "--rocker", "3", "--frame", "3",
     "--plot", "{d}/x.xyz"],
    ["linkage", "examples/fnf_sixbar.toml", "--plot", "{d}/x.csv"],
    ["simulate", "--revolutions", "1", "--points", "36", "--plot", "{d}/x.txt"],
])
def test_unsupported_plot_format_is_a_user_error_before_any_work(tmp_path, capsys, argv,
                                                                  monkeypatch):
    import pathlib

    monkeypatch.chdir(pathlib.Path(__file__).resolve().parents[1])
    argv = [a.replace("{d}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "unsupported plot format" in err and "internal error" not in err
    assert list(tmp_path.iterdir()) == []


def test_synth_limit_below_one_is_refused(capsys):
    with pytest.raises(SystemExit) as exit_:      # a usage error: argparse exits
        main(["synth", "--limit", "0"])
    assert exit_.value.code == 2
    assert "--limit: must be at least 1, got 0" in capsys.readouterr().err


def test_crosscheck_reports_unmeasurable_ringing_instead_of_crashing(capsys):
    """Variant 2 of Table 1 rings too little to count crossings: (b) is noted, (a), (c) stand."""
    assert main(["crosscheck", "--variant", "2"]) == 0
    out = capsys.readouterr().out
    assert "(b) ringing after beat-up: not measured" in out
    assert "zero crossing(s) of the pulse response" in out
    assert "(c) harmonic forcing" in out


def test_series_of_terms_that_are_all_exactly_zero_is_zero_not_a_crash():
    """Long-run seed 1018381: value·η = 1e308·31 = ∞ makes the only term 1/∞ = 0."""
    c = mechcirc.parse("drive V n6 n7 force=1\nmass e1 n7 n6 1e308 eta=31\n")
    s = c.sweep([0.0, 1.0, 1e3])
    assert np.all(s.K == 0) and np.all(s.flags == 1)


def test_locking_linkage_is_reported_quickly():
    """Long-run seed 1009246 (O1 moved to y = 327): 3.7 s to find the lock, now well under 2 s.

    Newton gives up as soon as its residual grows, instead of iterating 30
    times at every halving of the step; the lock angle is unchanged.
    """
    import time

    lk = parse_linkage(FNF.replace("O1 = [124.0, -27.0]", "O1 = [124.0, 327.0]"))
    t0 = time.perf_counter()
    with pytest.raises(GeometryError, match=r"locks near θ = 14\.4171°"):
        lk.solve(0.3)
    assert time.perf_counter() - t0 < 2.0


@pytest.mark.parametrize("theta", ["inf", "1e400", "nan", "-inf"])
def test_crosscheck_refuses_a_non_finite_theta(theta, capsys):
    """Long-run CLI fuzz (17 of 3,000 command lines): --theta inf was a math domain error."""
    with pytest.raises(SystemExit) as exit_:      # a usage error: argparse exits
        main(["crosscheck", f"--theta={theta}"])
    assert exit_.value.code == 2
    assert "--theta: " in (err := capsys.readouterr().err) and "is not a finite number" in err
