"""The linearised sley's modes (SleyMode): their frequencies; the former name Mode is gone."""

import math
import warnings

import numpy as np
import pytest

import mechcirc.sley
from mechcirc.sley import SleyMode, eigenfrequencies, linearise, preset


def test_missing_names_and_the_former_name_are_attribute_errors():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(AttributeError, match="has no attribute 'Modes'"):
            mechcirc.sley.Modes                     # noqa: B018
        with pytest.raises(AttributeError, match="has no attribute 'Mode'"):
            mechcirc.sley.Mode                      # noqa: B018


@pytest.mark.parametrize("drive", ["one-side", "both-sides"])
def test_frequencies_against_the_matrices(drive):
    """omega_n solves det(K − ω²M) = 0 (undamped), f_hz = omega_n/2π, and the eigenvalue
    solves det(λ²M + λC + K) = 0; omega_n is not |λ| for this damping (why it is not
    Resonance.omega)."""
    p = preset(drive, 3)
    lin = linearise(p, 0.3)
    for m in eigenfrequencies(p, 0.3):
        assert isinstance(m, SleyMode)
        w = m.omega_n
        undamped = np.linalg.det(lin.K - w * w * lin.M) / np.linalg.det(lin.K)
        lam = m.eigenvalue
        damped = np.linalg.det(lam * lam * lin.M + lam * lin.C + lin.K) / np.linalg.det(lin.K)
        # achieved ≤ 4e-13; ω off by 1e-6 relative gives ≥ 1.7e-6
        assert abs(undamped) < 1e-9 and abs(damped) < 1e-9
        assert m.f_hz == pytest.approx(w / (2 * math.pi), rel=2 ** -52)
        assert m.omega_d == lam.imag and m.zeta == pytest.approx(-lam.real / abs(lam), rel=1e-15)
        assert 1e-5 < abs(abs(lam) / w - 1) < 2.3e-3
