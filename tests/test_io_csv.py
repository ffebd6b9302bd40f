"""mechcirc.io_csv: the CSV of a sweep reads back to the sweep's numbers."""

import numpy as np
import pytest

from mechcirc import parse
from mechcirc.io_csv import write_sweep_csv

NET = "drive F 1 0 force=2\nmass m 1 0 3\nspring k 1 0 300\ndamper c 1 0 0.5\n"


def test_csv_round_trips_every_column_to_the_last_bit(tmp_path):
    c = parse(NET)
    s = c.sweep(np.linspace(1.0, 20.0, 7))
    path = tmp_path / "K.csv"
    write_sweep_csv(s, path)
    head = path.read_text().splitlines()[0]
    assert head == "omega,K_re,K_im,Q0_re,Q0_im,v0_re,v0_im,flag"
    t = np.loadtxt(path, delimiter=",", skiprows=1)
    assert t.shape == (7, 8)
    # %.17g is exact for binary64: equality, not a tolerance
    assert np.array_equal(t[:, 0], s.omega)
    assert np.array_equal(t[:, 1] + 1j * t[:, 2], s.K)
    assert np.array_equal(t[:, 3] + 1j * t[:, 4], s.Q0)
    assert np.array_equal(t[:, 5] + 1j * t[:, 6], s.v0)
    assert np.array_equal(t[:, 7], s.flags)
    # K of a parallel mass–spring–damper, from its closed form
    w = s.omega
    assert np.allclose(s.K, 1 / (0.5 + 1j * (3 * w - 300 / w)), rtol=1e-13, atol=0)


def test_a_failed_write_through_atomic_path_leaves_no_file(tmp_path):
    from mechcirc.outputs import atomic_path

    class Broken:
        omega = np.ones(3)
        K = np.ones(2, complex)      # columns of unequal length: savetxt raises mid-write
        Q0 = np.ones(3, complex)
        flags = np.zeros(3, int)

        class drive:
            kind = "velocity"

    path = tmp_path / "K.csv"
    with pytest.raises(ValueError), atomic_path(path) as tmp:
        write_sweep_csv(Broken(), tmp)
    assert list(tmp_path.iterdir()) == []
