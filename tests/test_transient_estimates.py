"""Error estimates of the clearance integrator hold at every tolerance (issue 23 item 3).

The corpus (``tests/reference/transient_corpus.py``): a stiff stop, a soft
one, a micrometre clearance under a harmonic drive, a 10-mass chain with
gaps, a damped stop chattering under a constant force, the MSL example and a
drive given by samples.  The true error of x is measured against solve_ivp
(DOP853, rtol 1e-13) on equations written there by hand from the same
description — never against mechcirc's own runs.  By default a subset runs
(3 cases × 3 tolerances, a few seconds); ``MECHCIRC_TRANSIENT_CORPUS=full``
runs every case at rtol 1e-3 … 1e-10 (the table of docs/transient.md).
Before: the estimate was the difference from a run at 10× looser tolerance,
which repeated the same hmax-limited steps at loose tolerances (estimate 0 for a
true error of 8.1e-6 m on a stiff stop at rtol 1e-3), and the absolute
tolerance was rtol × 1 m whatever the size of the motion.
"""

import os

import numpy as np
import pytest
from reference import transient_corpus as tc

import mechcirc
from mechcirc.transient import transient

FULL = os.environ.get("MECHCIRC_TRANSIENT_CORPUS") == "full"
NAMES = list(tc.CASES) if FULL else ["soft stop", "µm clearance", "MSL backlash"]
RTOLS = tc.RTOLS if FULL else (1e-3, 1e-6, 1e-9)


@pytest.fixture(scope="module")
def rows():
    return tc.measure(NAMES, RTOLS)


def test_estimate_is_never_zero_and_bounds_the_true_error(rows):
    assert len(rows) == len(NAMES) * len(RTOLS)
    for name, rtol, est, true, spread, _, _ in rows:
        assert est > 0, (name, rtol)
        # (where the true error is below the references' own spread it is not measured:
        # the sampled drive's 8.4e-14 m against a spread of 5.4e-13 m, a distance that
        # shrinks as the reference is tightened: 1.4e-12, 4.5e-13, 8.4e-14, 7.0e-14 at
        # its rtol 1e-11 … 3e-14, while mechcirc's two runs agree to 5.7e-16)
        assert est >= true or true <= spread, (name, rtol, est, true, spread)
        # measured on the full corpus: estimate / true 2.9 … 448 where measured
        assert est <= 1e4 * max(true, spread), (name, rtol, est, true)
    # the references are accurate enough to measure most runs (true ≥ 10× their spread)
    assert sum(r[3] >= 10 * r[4] for r in rows) >= len(rows) // 2


def test_rtol_not_reached_is_said(rows):
    """A note says "not reached" exactly when the estimate exceeds rtol × max|x|, so
    whenever the true error does: never silently."""
    for name, rtol, _, true, spread, peak, said in rows:
        if true > rtol * peak and true > spread:      # (measured: as in the test above)
            assert said, (name, rtol, true / peak)


def test_absolute_tolerance_follows_the_size_of_the_motion():
    # µm motions at rtol 1e-6: with atol = rtol × 1 m the error was of the motion's size
    (_, _, _, true, _, peak, _), = tc.measure(["µm clearance"], (1e-6,))
    assert peak < 1e-5
    assert true <= 1e-6 * peak        # measured 8.1e-7 × peak


def test_rtol_outside_the_range_is_refused():
    c = mechcirc.parse(tc.netlist(tc.CASES["stiff stop"]), require_drive=False)
    for bad in (0.5, 1e-13):
        with pytest.raises(mechcirc.MechcircError, match="--rtol must be between"):
            transient(c, 0.01, 1e-4, rtol=bad)


def test_note_agrees_with_the_estimate():
    c = mechcirc.load("examples/msl_backlash.mcir")
    for rtol in (1e-3, 1e-8):
        r = transient(c, 1.0, 1e-3, rtol=rtol)
        said = any("not reached" in n for n in r.notes)
        assert said == (r.error > rtol * np.abs(r.x).max())
