"""TransientResult.to_dataframe (audit17): the run as a table, as Sweep.to_dataframe."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from reference.inputs import STB

from mechcirc.netlist import load, parse
from mechcirc.transient import transient


@pytest.mark.parametrize("velocities", [True, False])
def test_columns_are_the_arrays_of_the_result(velocities):
    """Every column is the result's own array, bit for bit, under write_csv's name
    (without velocities and element forces when the run did not keep them)."""
    r = transient(load(STB), 0.01, 1e-4, "harmonic:300", velocities=velocities,
                  elements=velocities)
    assert (r.v is None) != velocities
    df = r.to_dataframe()
    assert len(df) == r.time.size == 101
    np.testing.assert_array_equal(df["t"], r.time)
    for i, n in enumerate(r.nodes):
        np.testing.assert_array_equal(df[f"x({n})"], r.x[:, i])
        if velocities:
            np.testing.assert_array_equal(df[f"v({n})"], r.v[:, i])
    for j, e in enumerate(r.elements):
        np.testing.assert_array_equal(df[f"F({e})"], r.force[:, j])
    np.testing.assert_array_equal(df["F(drive)"], r.drive_force)     # a velocity drive
    assert len(df.columns) == 1 + len(r.nodes) * (2 if velocities else 1) \
        + r.force.shape[1] + 1
    assert not any(c.startswith("v(") for c in df.columns) or velocities
    # each column's unit, keyed by column as Sweep.to_dataframe keys them (audit20)
    unit = {"t": "s", "x": "m", "v": "m/s", "F": "N"}
    assert df.attrs["units"] == {c: unit[c[0]] for c in df.columns}


def test_force_drive_gives_the_drive_velocity():
    r = transient(parse("mass m1 A 0 2\nspring k1 A 0 800\ndrive Q A 0 force=1\n"), 0.1,
                  1e-3, "step")
    df = r.to_dataframe()
    np.testing.assert_array_equal(df["v(drive)"], r.drive_velocity)
    assert "F(drive)" not in df.columns


def test_without_pandas_the_error_says_what_is_needed(monkeypatch):
    r = transient(parse("mass m1 A 0 2\nspring k1 A 0 800\ndrive Q A 0 force=1\n"), 0.01,
                  1e-3, "step")
    monkeypatch.setitem(sys.modules, "pandas", None)       # import pandas raises ImportError
    with pytest.raises(ImportError, match=r"to_dataframe needs pandas \(pip install pandas\)"):
        r.to_dataframe()


def test_the_csv_reads_back_every_value_as_written():
    """write_csv wrote 12 digits: an exact run's columns lost theirs (the force sum of a
    damped mass gave its drive back only to 5e-12).  17 digits: each value bit for bit."""
    import io

    r = transient(load(STB), 0.01, 1e-4, "harmonic:300")
    fh = io.StringIO()
    r.write_csv(fh)
    back = np.loadtxt(io.StringIO(fh.getvalue()), delimiter=",", skiprows=1)
    np.testing.assert_array_equal(back, np.column_stack(list(r.columns().values())))


def test_an_element_force_a_run_did_not_keep_says_so():
    """elements=False: 'no element named k1 (elements: none)' for an element that is there."""
    from mechcirc.errors import UnknownNameError

    c = parse("mass m a 0 2\nspring k1 a 0 800\ndrive F a 0 force=3\n")
    with pytest.raises(UnknownNameError, match="in this run, which kept none \\(elements=True"):
        transient(c, 0.1, 1e-3, "step", elements=False).element_force("k1")
    assert transient(c, 0.1, 1e-3, "step").element_force("k1").shape == (101,)


def test_a_run_without_a_drive_is_labelled_by_its_elements_units():
    """A rotary netlist with no drive (an .ic only) was labelled in m and m/s."""
    rotary = parse("mass J a 0 2 kg*m^2\nspring kt a 0 800 N*m/rad\n.ic a x=10 deg\n",
                   require_drive=False)
    assert transient(rotary, 0.1, 1e-3).units["x"] == "rad"
    plain = parse("mass m a 0 2\nspring k a 0 800\n.ic a x=0.01\n", require_drive=False)
    assert transient(plain, 0.1, 1e-3).units["x"] == "m"
