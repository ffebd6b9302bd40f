"""A transient's ``error`` includes the drive's interpolation error.

A drive in time (a Python function, a table) enters the exact propagation
piecewise linear between the grid's samples; the bound of that interpolation
error, carried to x through the worst-case gain ∫|Cx e^{Aτ} B| dτ, is part of
``TransientResult.error``.  References: the same equations written here by hand
and integrated by scipy's DOP853 at rtol 1e-12 with the drive evaluated exactly
(a table: integrated piece by piece between its points).
"""

import math

import numpy as np
from scipy.integrate import solve_ivp

import mechcirc
from mechcirc.transient import transient
from mechcirc.transient.propagate import ROUNDING_PER_STEP
from mechcirc.transient.waveform import Waveform

M, K, C = 1.0, (2 * math.pi * 5) ** 2, 0.5          # a 5 Hz SDOF, lightly damped
SDOF = f"mass m1 a 0 {M}\nspring k1 a 0 {K!r}\ndamper c1 a 0 {C}\ndrive F a 0 force=1\n"


def _force(t):
    return 100.0 * np.sin(2 * math.pi * 3.0 * t) ** 2


def _sdof_ref(f, times, pieces=None):
    """x(t) of m ẍ + c ẋ + k x = f(t) from rest, DOP853 (between ``pieces`` points)."""
    edges = [0.0, *(pieces if pieces is not None else []), float(times[-1])]
    edges = sorted({e for e in edges if 0.0 <= e <= times[-1]})
    y, out = [0.0, 0.0], np.empty(times.size)
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (times >= a) & (times <= b)
        sol = solve_ivp(lambda t, z: [z[1], (f(t) - K * z[0] - C * z[1]) / M], (a, b), y,
                        method="DOP853", rtol=1e-12, atol=1e-15, t_eval=times[sel],
                        dense_output=True)
        out[sel] = sol.y[0]
        y = list(sol.sol(b))
    return out


def test_function_drive_error_bounds_true_error():
    # dt = 0.02 s (10 samples per period of the 5 Hz mode): the interpolation
    # error dominates.  Before, error was the rounding estimate only (2.7e-14)
    # while the true error was 1.0e-2; now 0.059, 5.9x the true error.
    for dt, true_expected in ((2e-2, 1.0e-2), (1e-3, 2.56e-5)):
        r = transient(mechcirc.parse(SDOF), 1.0, dt, waveform=_force)
        true = np.abs(r.node("a")[0] - _sdof_ref(_force, r.time)).max()
        assert math.isclose(true, true_expected, rel_tol=0.01)   # the case is what it says
        assert true <= r.error <= 30 * true                      # bound; 5.9x, 6.2x here
        assert any("interpolated linearly" in n for n in r.notes)


def test_a_function_drive_the_steps_do_not_resolve_is_measured_and_said():
    """u = sin²(30 t) (|ü| ≤ 1800) on a 2 kg / 800 N/m / 8 N·s/m mass: at dt = 0.1 s the
    samples alias the drive, whose second differences said its interpolation error was at
    most 0.00498 (the real one 0.99) and ``error`` 3.8e-5 against a true x error of
    9.6e-4 (the new-user pass).  The gaps at the midpoints are measured too, and a note
    says the steps do not resolve the drive: the error now covers the true one (measured
    0.00759 against 9.59e-4)."""
    text = "mass m a 0 2\nspring k a 0 800\ndamper c a 0 8\ndrive F a 0 force=3\n"

    def u(t):
        return np.sin(30 * t) ** 2

    r = transient(mechcirc.parse(text), 2.0, 0.1, waveform=u)
    ref = solve_ivp(lambda t, y: [y[1], (u(t) - 800 * y[0] - 8 * y[1]) / 2], (0, 2.0),
                    [0.0, 0.0], t_eval=r.time, method="DOP853", rtol=1e-12, atol=1e-15,
                    max_step=1e-3).y[0]
    true = np.abs(r.node("a")[0] - ref).max()
    assert math.isclose(true, 9.59e-4, rel_tol=0.01)         # the case is what it says
    assert true <= r.error
    assert any("the steps do not resolve the drive" in n for n in r.notes)


def test_a_grid_dt_does_not_divide_ends_where_a_note_says():
    r = transient(mechcirc.parse(SDOF), 1.0, 0.3, waveform="step")
    assert math.isclose(r.time[-1], 0.9)
    assert any("the grid ends at 0.9 s: t_end/dt = 3.33333 rounded to 3 steps" in n
               for n in r.notes)
    assert not any("grid ends" in n for n in transient(mechcirc.parse(SDOF), 1.0, 0.25,
                                                         waveform="step").notes)


def test_table_drive_off_grid_error_bounds_true_error():
    # Table points at 0.013 s spacing, grid step 0.01 s: the grid's linear
    # interpolation cuts the table's corners (exact gap, measured at its points).
    knots = np.arange(0.0, 1.0 + 1e-9, 0.013)
    vals = _force(knots)
    wave = Waveform("samples", times=tuple(knots), values=tuple(vals))
    r = transient(mechcirc.parse(SDOF), 1.0, 1e-2, waveform=wave)
    ref = _sdof_ref(lambda t: float(np.interp(t, knots, vals)), r.time, pieces=list(knots))
    true = np.abs(r.node("a")[0] - ref).max()
    assert true > 1e-5                                           # the drive error dominates
    assert true <= r.error <= 30 * true                      # bound; 16x here


def test_table_drive_on_grid_error_unchanged():
    # Table points on the grid: the first-order hold is the table itself, so
    # nothing is added; the error stays at the rounding level (1.10 × steps × 8ε ×
    # max|x| measured: the eigenvalues' errors from their residual add a little), and it
    # bounds the true error.
    knots = np.arange(0.0, 1.0 + 1e-9, 0.05)
    vals = _force(knots)
    wave = Waveform("samples", times=tuple(knots), values=tuple(vals))
    r = transient(mechcirc.parse(SDOF), 1.0, 1e-2, waveform=wave)
    x = r.node("a")[0]
    rounding = ROUNDING_PER_STEP * (r.time.size - 1) * np.abs(x).max()
    assert rounding <= r.error <= 2 * rounding
    assert not any("interpolated" in n for n in r.notes)
    ref = _sdof_ref(lambda t: float(np.interp(t, knots, vals)), r.time, pieces=list(knots))
    assert np.abs(x - ref).max() <= 1e-9 * np.abs(x).max()     # DOP853's own level


def test_velocity_drive_error_bounds_true_error():
    # A velocity drive: the drive's displacement X = ∫V is a state, so its
    # interpolation error adds up in time (the gain's integral sees that).
    m, k, c = 2.0, 4.0e3, 3.0
    net = f"drive V a 0 velocity=1\nspring k1 a b {k}\nmass m1 b 0 {m}\ndamper c1 b 0 {c}\n"

    def vel(t):
        return 0.3 * np.sin(2 * math.pi * 4.0 * t) * np.exp(-t)

    r = transient(mechcirc.parse(net), 1.0, 1e-2, waveform=vel)
    sol = solve_ivp(lambda t, z: [vel(t), z[2], (k * (z[0] - z[1]) - c * z[2]) / m],
                    (0, r.time[-1]), [0, 0, 0], method="DOP853", rtol=1e-12, atol=1e-15,
                    t_eval=r.time)
    xa, xb = r.node("a")[0], r.node("b")[0]
    true = max(np.abs(xa - sol.y[0]).max(), np.abs(xb - sol.y[1]).max())
    assert true > 1e-6
    assert true <= r.error <= 30 * true                      # bound; 13x here


def test_block_path_error_bounds_true_error():
    # Critical damping: the modal path is refused (a defective A), so the
    # drive's gain is formed by the block fallback too.
    c = 2 * math.sqrt(K * M)
    net = f"mass m1 a 0 {M}\nspring k1 a 0 {K!r}\ndamper c1 a 0 {c!r}\ndrive F a 0 force=1\n"
    r = transient(mechcirc.parse(net), 1.0, 2e-2, waveform=_force)
    assert any("block propagation" in n for n in r.notes)
    sol = solve_ivp(lambda t, z: [z[1], (_force(t) - K * z[0] - c * z[1]) / M],
                    (0, r.time[-1]), [0, 0], method="DOP853", rtol=1e-12, atol=1e-15,
                    t_eval=r.time)
    true = np.abs(r.node("a")[0] - sol.y[0]).max()
    assert true > 1e-5
    assert true <= r.error <= 30 * true                          # bound; 3.4x here


def test_clearance_run_says_the_drive_bound_is_not_in_its_error():
    # With a clearance x is not linear in the drive: no gain exists to carry
    # the bound, and the notes say so instead of the error silently leaving it out.
    net = SDOF.replace(f"spring k1 a 0 {K!r}", f"spring k1 a 0 {K!r} backlash=1e-3")
    r = transient(mechcirc.parse(net), 0.2, 2e-2, waveform=_force, rtol=1e-6)
    assert any("interpolated linearly" in n for n in r.notes)
    assert any("not in the error estimate" in n for n in r.notes)
