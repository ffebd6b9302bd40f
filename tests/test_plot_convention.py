"""Every public plot function keeps the caller's drawing: one convention (mechcirc.plotting).

A multi-panel plot given ``fig=`` fills it only when it is empty (a Figure or a
SubFigure): a figure holding the caller's Axes is refused with an error naming
the function and what to pass, and the caller's Axes and artist are still
there.  Given an empty subfigure beside the caller's panel, it draws there and
returns it.  A plot given ``ax=`` draws on that Axes, returns it and adds no
Axes.  None of them touches pyplot.
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

import mechcirc
from mechcirc.errors import InputError, MechcircError
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]
SDOF = ("drive V T 0 motion=cycloidal rise=120 dwell=60 return=120 stroke=0.05\n"
        "spring k T a 2e5\nmass m a 0 1.5\ndamper c a 0 60\n")


@pytest.fixture(scope="module")
def made():
    """The inputs of every plot function, small."""
    from mechcirc.forces import element_forces
    from mechcirc.interop.skrf import compare
    from mechcirc.kinematics import FourBar, frame_loading, load_linkage, synthesize
    from mechcirc.modes import modes
    from mechcirc.periodic import periodic, speed_map
    from mechcirc.scene import load_scene
    from mechcirc.scene.cycle import cycle_map
    from mechcirc.scene.simulation import simulate_scene
    from mechcirc.sley import simulate
    from mechcirc.study import parse_spec, run_study
    from mechcirc.transient import transient

    c = mechcirc.load(STB)
    sdof = mechcirc.parse(SDOF)
    spec = parse_spec({"netlist": str(STB), "analysis": "resonances", "grid": {"eta1": [0.7, 0.9]}})
    fb = FourBar(0.035, 0.0578, 0.1556, 0.16275)
    lk = load_linkage(REPO / "examples" / "fnf_sixbar.toml")
    heald = load_scene(REPO / "examples" / "heald_scene.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        motion = simulate_scene(load_scene(REPO / "examples" / "mrazek_one_side.toml"),
                                revolutions=1, points=90, error_estimate=False)
        sley = simulate("one-side", 4, revolutions=1, points_per_revolution=90,
                        error_estimate=False)
    return {
        "circuit": c, "sweep": c.sweep(np.geomspace(10, 1e4, 40)),
        "transient": transient(mechcirc.parse("drive F a 0 force=1\nspring k a 0 100\n"
                                              "mass m a 0 1\n"), 0.1, 1e-3, "step"),
        "forces": element_forces(c, 300.0)[0],
        "comparison": compare(c, REPO / "docs" / "examples" / "measured.s1p"),
        "study": (run_study(spec, workers=1), spec.params),
        "periodic": periodic(sdof, 600), "speed_map": speed_map(sdof, 200, 1200, 5),
        "modes": modes(c), "fourbar": fb, "linkage": (lk, lk.solve(0.2)),
        "frame": frame_loading(fb, np.linspace(0, 2 * math.pi, 31), 60.0),
        "designs": synthesize("light", 25.0, limit=2).designs,
        "heald": heald, "cycle": cycle_map(heald, points=4, harmonics=2),
        "motion": motion, "sley": sley,
    }


def _multi(m):
    """(name, call with fig= or ax=) of every plot that draws several panels on a Figure
    (given ax=, only its main panel)."""
    from mechcirc.kinematics import plots as kp
    from mechcirc.plotting import (plot_comparison, plot_modes, plot_periodic, plot_sweep,
                                   plot_transient)
    from mechcirc.scene.cycle import plot_cycle
    from mechcirc.scene.plots import plot_motion
    from mechcirc.sley.plots import plot_result

    return [
        ("plot_sweep", lambda fig=None, ax=None: plot_sweep(m["sweep"], fig=fig, ax=ax)),
        ("plot_transient", lambda fig=None, ax=None: plot_transient(m["transient"], elements=["k"], fig=fig, ax=ax)),
        ("plot_comparison", lambda fig=None, ax=None: plot_comparison(m["comparison"], fig=fig, ax=ax)),
        ("plot_periodic", lambda fig=None, ax=None: plot_periodic(m["periodic"], fig=fig, ax=ax)),
        ("plot_modes", lambda fig=None, ax=None: plot_modes(m["modes"][:2], fig=fig, ax=ax)),
        ("plot_cycle", lambda fig=None, ax=None: plot_cycle(m["cycle"], fig=fig, ax=ax)),
        ("plot_motion", lambda fig=None, ax=None: plot_motion(m["motion"], fig=fig, ax=ax)),
        ("plot_result", lambda fig=None, ax=None: plot_result(m["sley"], fig=fig, ax=ax)),
        ("plot_fourbar", lambda fig=None, ax=None: kp.plot_fourbar(m["fourbar"], fig=fig, ax=ax)),
        ("plot_synthesis", lambda fig=None, ax=None: kp.plot_synthesis(m["designs"], n=61, fig=fig, ax=ax)),
        ("plot_frame_loading", lambda fig=None, ax=None: kp.plot_frame_loading(m["frame"], fig=fig, ax=ax)),
        ("plot_shaking", lambda fig=None, ax=None: kp.plot_shaking(m["frame"], fig=fig, ax=ax)),
        ("plot_linkage", lambda fig=None, ax=None: kp.plot_linkage(*m["linkage"], fig=fig, ax=ax)),
    ]


def _single(m):
    """(name, call with ax=) of every plot that draws on one given Axes."""
    from mechcirc.kinematics import plots as kp
    from mechcirc.plotting import (plot_forces, plot_mode, plot_speed_map, plot_study, plot_sweep,
                                   plot_transient)
    from mechcirc.scene import plots as sp
    from mechcirc.scene.cycle import plot_cycle

    return [
        ("plot_sweep", lambda ax: plot_sweep(m["sweep"], ax=ax)),
        ("plot_transient", lambda ax: plot_transient(m["transient"], ax=ax)),
        ("plot_forces", lambda ax: plot_forces(m["forces"], 300.0, ax=ax)),
        ("plot_study", lambda ax: plot_study(*m["study"], "resonance_1", ax=ax)),
        ("plot_speed_map", lambda ax: plot_speed_map(m["speed_map"], ax=ax)),
        ("plot_mode", lambda ax: plot_mode(m["modes"][0], ax=ax)),
        ("scene.plot_mode", lambda ax: sp.plot_mode(m["heald"], 0.0, ax=ax)),
        ("plot_cycle", lambda ax: plot_cycle(m["cycle"], ax=ax)),
        ("draw_design", lambda ax: kp.draw_design(m["designs"][0], ax)),
        ("plot_linkage", lambda ax: kp.plot_linkage(*m["linkage"], ax=ax)),
    ]


def _public_plot_functions() -> set[str]:
    """Names of every public function of mechcirc that draws (``plot_*``, ``draw_*``)."""
    import importlib

    names = set()
    for mod in ("mechcirc.plotting", "mechcirc.scene.plots", "mechcirc.scene.cycle",
                "mechcirc.sley.plots", "mechcirc.kinematics.plots"):
        m = importlib.import_module(mod)
        names |= {n for n in dir(m) if n.startswith(("plot_", "draw_")) and callable(getattr(m, n))
                  and getattr(getattr(m, n), "__module__", "") == mod}
    return names


@pytest.fixture(autouse=True)
def pyplot_untouched():
    """pyplot's figures and the backend are the same after as before (and pyplot is
    not imported by a plot function when it was not before)."""
    import matplotlib

    had = "matplotlib.pyplot" in sys.modules
    figures = sys.modules["matplotlib.pyplot"].get_fignums() if had else None
    backend = matplotlib.rcParams._get_backend_or_none()
    yield
    assert ("matplotlib.pyplot" in sys.modules) == had
    if had:
        assert sys.modules["matplotlib.pyplot"].get_fignums() == figures
    assert matplotlib.rcParams._get_backend_or_none() == backend


def _callers_figure():
    fig = Figure()
    mine = fig.add_subplot()
    line, = mine.plot([0, 1], [2, 3], gid="mine")
    return fig, mine, line


def test_every_public_plot_function_is_checked(made):
    checked = {n.rpartition(".")[2] for n, _ in _multi(made) + _single(made)}
    assert _public_plot_functions() == checked


def test_a_figure_holding_the_callers_axes_is_refused_and_kept(made):
    for name, call in _multi(made):
        fig, mine, line = _callers_figure()
        with pytest.raises(InputError, match=rf"^{name}: .*already holds 1 Axes.*fig=None.*"
                                             r"subfigure") as err:
            call(fig)
        assert isinstance(err.value, MechcircError) and isinstance(err.value, ValueError)
        assert fig.axes == [mine] and list(mine.lines) == [line], name
        np.testing.assert_array_equal(line.get_ydata(), [2, 3])


def test_an_empty_subfigure_beside_the_callers_axes_is_filled(made):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    for name, call in _multi(made):
        fig = Figure(figsize=(16, 8))
        left, right = fig.subfigures(1, 2)
        mine = left.add_subplot()
        line, = mine.plot([0, 1], [2, 3])
        assert call(right) is right, name
        assert right.axes and all(a.has_data() for a in right.axes[:1]), name
        assert fig.axes == [mine] + right.axes and list(mine.lines) == [line], name
        if name in ("plot_sweep", "plot_synthesis"):   # margins / a sub-grid set on a
            FigureCanvasAgg(fig).draw()                # SubFigure: it draws


def test_ax_is_drawn_on_and_returned_and_the_callers_artist_kept(made):
    for name, call in _single(made):
        fig, mine, line = _callers_figure()
        before = len(mine.get_children())
        assert call(mine) is mine, name
        assert line in mine.lines and len(mine.get_children()) > before, name
        assert fig.axes == [mine], name


def test_the_callers_title_and_legend_entries_are_kept(made):
    """Sweep.plot(ax=) and plot_forces(ax=) replaced the caller's title, and plot_forces
    its legend, the caller's own line's entry gone (the new-user pass); a title of the
    plot's own goes only where the caller has none."""
    for name, call in _single(made):
        fig, mine, line = _callers_figure()
        line.set_label("mine")
        mine.set_title("my title")
        call(mine)
        assert mine.get_title() == "my title", name
        legend = mine.get_legend()
        assert legend is None or "mine" in [t.get_text() for t in legend.get_texts()], name


def test_plot_cycle_on_ax_draws_the_resonances_as_the_upper_panel(made):
    """The panel plot_cycle(ax=) draws is the Figure's upper panel, line for line."""
    from mechcirc.scene.cycle import plot_cycle

    fig, mine, _ = _callers_figure()
    plot_cycle(made["cycle"], ax=mine, unit="Hz")
    upper = plot_cycle(made["cycle"], unit="Hz").axes[0]
    drawn = [ln.get_xydata() for ln in mine.lines[1:]]
    assert len(drawn) == len(upper.lines)
    for a, b in zip(drawn, upper.lines):
        np.testing.assert_array_equal(a, b.get_xydata())
    W = made["cycle"].natural_frequencies()
    np.testing.assert_allclose(drawn[0][:, 1], W[:, 0] / (2 * math.pi), rtol=1e-12)


def test_ax_of_a_multi_panel_plot_is_its_main_panel_line_for_line(made):
    """Every multi-panel plot takes ax=: its first panel drawn there, as on its own Figure,
    labelled and titled, and nothing added to the caller's figure."""
    for name, call in _multi(made):
        if name in ("plot_sweep", "plot_cycle", "plot_linkage"):   # their own tests
            continue
        fig, mine, line = _callers_figure()
        assert call(ax=mine) is mine, name
        assert fig.axes == [mine] and line in mine.lines, name
        own = call().axes[0]
        drawn = [ln for ln in mine.lines if ln is not line]
        assert drawn and len(drawn) == len(own.lines), name
        for a, b in zip(drawn, own.lines):
            np.testing.assert_array_equal(a.get_xydata(), b.get_xydata(), err_msg=name)
        assert mine.get_xlabel() and mine.get_title(), name


def test_plot_modes_on_ax_draws_the_first_mode_that_vibrates():
    """New-user pass, session 28: plot_modes(found, ax=) drew found[0], which may be an
    overdamped root with no shape: the caller's Axes held only its note."""
    from mechcirc.modes import modes
    from mechcirc.plotting import plot_mode, plot_modes

    c = mechcirc.parse("drive V a 0 velocity=1\nmass m1 a 0 1.5\nspring k1 a b 2e5\n"
                       "damper c1 a b 50\nmass m2 b 0 0.8\nspring k2 b c 1e5\n"
                       "mass m3 c 0 0.5\ndamper c3 c 0 20\n")
    found = modes(c)
    assert not found[0].shape and found[1].shape          # an overdamped root first
    fig, mine, _ = _callers_figure()
    assert plot_modes(found, ax=mine) is mine and fig.axes == [mine]
    own = plot_mode(found[1]).axes[0]            # (plot_mode's own Figure of that mode)
    drawn = [ln for ln in mine.lines if ln.get_gid() != "mine"]
    assert len(drawn) == len(own.lines) > 0
    for a, b in zip(drawn, own.lines):
        np.testing.assert_array_equal(a.get_xydata(), b.get_xydata())
