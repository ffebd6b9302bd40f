"""The scripts under ``examples/`` run, and what they claim holds."""

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

from reference import stb_eq7
from cli_helpers import run_script

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "stb_eq7_check.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("stb_eq7_check", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_stb_eq7_example_runs_and_reports_agreement(capsys, monkeypatch):
    status, out, err = run_script(EXAMPLE, [], capsys, monkeypatch)
    assert status == 0, out + err
    assert err == ""
    m = re.search(r"max relative error away from poles: (\S+) \(tolerance 1e-12\)", out)
    assert m, out
    assert float(m.group(1)) <= 1e-12
    # Both parts ran, and each left out only a few points near poles.
    m1 = re.search(r"left out near them: (\d+) points", out)
    m2 = re.search(r"left out near poles or zeros: (\d+) of (\d+) points", out)
    assert m1 and int(m1.group(1)) < 200
    assert m2 and int(m2.group(2)) == 10_000 and int(m2.group(1)) < 100


def test_example_eq7_is_the_reference_eq7():
    """The example's own copy of eq. (7) agrees with tests/reference/stb_eq7.py."""
    ex = _load_example()
    rng = np.random.default_rng(11)
    for _ in range(20):
        p = ex.random_params(rng)
        omega = 10 ** rng.uniform(0, 4, size=30)
        np.testing.assert_allclose(ex.K_eq7(omega, p), stb_eq7.full_K(omega, p), rtol=1e-13)


def test_example_finds_the_poles_and_zeros():
    """Im K changes sign at every root the example reports, and nowhere else it samples.

    K of a lossless network is a reactance function: its poles and zeros
    alternate and Im K changes sign at each, so sampling Im K between
    consecutive roots (and beyond the ends) must give alternating signs.
    """
    ex = _load_example()
    rng = np.random.default_rng(5)
    for _ in range(50):
        p = ex.random_params(rng)
        roots = ex.poles_and_zeros(p)
        assert roots.size == 5          # numerator cubic and denominator quadratic in ω²
        probes = np.concatenate([[roots[0] / 2], np.sqrt(roots[:-1] * roots[1:]),
                                 [roots[-1] * 2]])
        signs = np.sign(stb_eq7.full_K(probes, p).imag)
        assert np.all(signs[1:] == -signs[:-1]), (roots, signs)
        dense = np.geomspace(roots[0] / 2, roots[-1] * 2, 4001)
        changes = np.count_nonzero(np.diff(np.sign(stb_eq7.full_K(dense, p).imag)))
        assert changes <= 5


@pytest.mark.parametrize("offset, kept", [(0.0, False), (5e-4, False), (2e-3, True)])
def test_example_near_pole_mask(offset, kept):
    ex = _load_example()
    roots = np.array([100.0, 1000.0])
    omega = np.array([100.0 * (1 + offset), 1000.0 * (1 - offset)])
    assert list(ex.away_from_poles(omega, roots)) == [kept, kept]
