"""Kinematics figures: they draw the API's numbers (matplotlib's Agg canvas, no display)."""

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from mechcirc.kinematics import FourBar, LinkMass, frame_loading, load_linkage, synthesize
from mechcirc.kinematics.plots import (plot_fourbar, plot_frame_loading, plot_linkage,
                                       plot_synthesis)


def test_plot_fourbar_draws_eps4T():
    fb = FourBar(29, 37, 188, 189)
    fig = plot_fourbar(fb, omega=100.0)
    ax = fig.axes
    assert len(ax) == 4
    x, y = ax[2].lines[0].get_data()
    np.testing.assert_allclose(y, fb.nu(np.radians(x)) * 1e4, rtol=1e-12)
    assert max(y) == pytest.approx(2914.6, abs=1.0)      # grid close to the true peak
    # a double-rocker plots over its reachable window only
    fig = plot_fourbar(FourBar(30, 10, 30, 25))
    x, _ = fig.axes[0].lines[0].get_data()
    lo, hi = FourBar(30, 10, 30, 25).crank_range()
    assert math.degrees(lo) < x.min() and x.max() < math.degrees(hi)


def test_plot_frame_loading_draws_the_shaking_force():
    fb = FourBar(0.035, 0.0578, 0.1556, 0.16275)
    th = np.linspace(0, 2 * math.pi, 91)
    res = frame_loading(fb, th, 60.0, rocker=LinkMass(15.0, (0.1, 0.02), 0.08))
    fig = plot_frame_loading(res)
    x, y = fig.axes[0].lines[2].get_data()
    np.testing.assert_allclose(y, res.shaking_force_magnitude)
    fig.canvas.draw()                     # renders on Agg without error


def test_plot_synthesis_and_linkage(tmp_path):
    res = synthesize("light", 25.0, limit=2)
    fig = plot_synthesis(res.designs)
    assert len(fig.axes[1].lines) == 3    # two designs and the 45° limit
    # the first panel draws design 1 at its dead centres: B on the crank circle at θ_front
    fb = res.designs[0].fourbar()
    front, back = fb.dead_centres()
    x, y = fig.axes[0].lines[0].get_data()
    np.testing.assert_allclose([x[1], y[1]], [fb.crank * math.cos(front.theta),
                                              fb.crank * math.sin(front.theta)], atol=1e-12)
    x, y = fig.axes[0].lines[1].get_data()
    np.testing.assert_allclose([x[2], y[2]], [fb.frame + fb.rocker * math.cos(back.phi4),
                                              fb.rocker * math.sin(back.phi4)], atol=1e-12)
    lk = load_linkage(Path(__file__).resolve().parents[2] / "examples" / "fnf_sixbar.toml")
    st = lk.solve(0.2)
    fig = plot_linkage(lk, st, {"K": np.array([st.points["K"], st.points["K"] + 1])})
    fig.savefig(tmp_path / "x.png")
    assert (tmp_path / "x.png").stat().st_size > 1000


def test_plot_shaking_draws_the_polar_curve_and_magnitude():
    from mechcirc.kinematics.plots import plot_shaking

    fb = FourBar(0.035, 0.0578, 0.1556, 0.16275)
    th = np.linspace(0, 2 * math.pi, 91)
    res = frame_loading(fb, th, 60.0, rocker=LinkMass(15.0, (0.1, 0.02), 0.08))
    fig = plot_shaking(res)
    x, y = fig.axes[0].lines[0].get_data()
    np.testing.assert_allclose(x, res.shaking_force[:, 0])
    np.testing.assert_allclose(y, res.shaking_force[:, 1])
    np.testing.assert_allclose(fig.axes[1].lines[0].get_data()[1], np.hypot(x, y))
    fig.canvas.draw()
