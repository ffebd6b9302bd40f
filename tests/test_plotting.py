"""Plots draw the API's numbers, with units on every axis and the netlist's name."""

from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from mechcirc.forces import element_forces
from mechcirc.plotting import plot_forces, plot_study, plot_sweep
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def stb_sweep():
    c = mechcirc.load(STB)
    omega = np.geomspace(10, 1e4, 300)
    return c, c.sweep(omega), c.resonances(omega_max=1e4)


def _root_marks(ax, style=None) -> list:
    """x of the roots' vertical lines on ``ax`` (with line style ``style``, or any):
    lines of segments (x, 0)–(x, 1) in the axes' height, broken by NaN."""
    out = []
    for line in ax.lines:
        x, y = (np.asarray(v, float) for v in line.get_data())
        if y.size and np.array_equal(y, np.tile([0, 1, np.nan], max(y.size // 3, 1)),
                                     equal_nan=True):
            assert np.array_equal(x[0::3], x[1::3]) and np.isnan(x[2::3]).all()
            if style is None or line.get_linestyle() == style:
                out += list(x[0::3])
    return sorted(out)


def test_sweep_axes_label_decades_in_plain_text(stb_sweep):
    """Decades as 10ⁿ text (no mathtext parse), no minor ticks on a y axis over 3 decades."""
    from mechcirc.plotting import _decade_label

    assert [_decade_label(v) for v in (1e-3, 1.0, 100.0, 1e12, 2.5, 0.0)] == \
        ["10⁻³", "10⁰", "10²", "10¹²", "2.5", "0"]
    c, s, found = stb_sweep
    fig = plot_sweep(s, resonances=found)
    fig.canvas.draw()                           # tick labels are made at drawing
    ax_k, ax_p, ax_q = fig.axes
    labels = [t.get_text() for t in ax_q.get_xticklabels() + ax_k.get_yticklabels()]
    assert "10³" in labels and not any("$" in t for t in labels)
    lo, hi = ax_k.get_ylim()
    assert np.log10(hi / lo) > 3 and len(ax_k.yaxis.get_minorticklocs()) == 0
    # The frequency axis keeps its minor grid, as one line collection per panel
    # at 2…9 × 10ⁿ inside the view, its lines one path broken by NaN; the panels
    # above the last (no x tick labels) have no x Tick objects: their decades'
    # grid lines are in that path and their tick marks one line of markers, at
    # the last panel's ticks.
    lo, hi = ax_q.get_xlim()
    want = sorted(x for x in np.outer(np.arange(2, 10), 10.0 ** np.arange(-1, 5)).ravel()
                  if lo <= x <= hi)
    decades = [10.0 ** e for e in range(-1, 6) if lo <= 10.0 ** e <= hi]
    assert len(want) > 10 and list(ax_q.xaxis.get_majorticklocs()) == decades
    for ax in fig.axes:
        (lc,) = [c for c in ax.collections if type(c).__name__ == "LineCollection"]
        (path,) = (p.vertices for p in lc.get_paths())
        assert np.array_equal(path[0::3, 0], path[1::3, 0]) and np.isnan(path[2::3]).all()
        assert (path[0::3, 1] == 0).all() and (path[1::3, 1] == 1).all()
        got = sorted(path[0::3, 0])
        np.testing.assert_allclose(got, sorted(want + decades * (ax is not ax_q)), rtol=1e-12)
    for ax in (ax_k, ax_p):
        assert len(ax.xaxis.get_majorticklocs()) == 0 and ax.get_xlim() == (lo, hi)
        (marks,) = [line for line in ax.lines if line.get_marker() == 3]     # TICKDOWN
        assert list(marks.get_xdata()) == decades


def test_bode_panels_draw_K_phase_and_Q0(stb_sweep):
    c, s, found = stb_sweep
    fig = plot_sweep(s, resonances=found, refine=False)     # the sweep's own points
    ax_k, ax_p, ax_q = fig.axes
    assert [ax.get_ylabel() for ax in fig.axes] == ["|K| [m/(N·s)]", "arg K [deg]", "|Q0| [N]"]
    assert ax_q.get_xlabel() == "ω [rad/s]"
    assert "stb_heald" in fig._suptitle.get_text()
    x, y = ax_k.lines[0].get_data()
    np.testing.assert_array_equal(x, s.omega)
    np.testing.assert_array_equal(y, np.abs(s.K))
    np.testing.assert_allclose(ax_p.lines[0].get_ydata(), np.degrees(np.angle(s.K)))
    np.testing.assert_array_equal(ax_q.lines[0].get_ydata(), np.abs(s.Q0))
    # one vertical marker per root in every panel, at its frequency: solid for a
    # resonance, dashed for an anti-resonance
    for ax in fig.axes:
        for style, kind in (("-", "resonance"), ("--", "antiresonance")):
            assert _root_marks(ax, style) == pytest.approx(
                sorted(r.omega_d or r.omega for r in found if r.kind == kind), rel=1e-12)


def test_force_bars_are_the_table(stb_sweep):
    c, _, _ = stb_sweep
    rows, *_ = element_forces(c, 300.0)
    fig = plot_forces(rows, omega=300.0, name=c.name)
    ax = fig.axes[0]
    heights = [p.get_height() for p in ax.patches][:len(rows)]
    assert heights == pytest.approx([r.Q_abs for r in rows], rel=1e-12)
    assert ax.get_ylabel() == "|Q| [N]" and ax.get_yscale() == "log"   # 7.1 N … 0.048 N
    assert [t.get_text() for t in ax.get_xticklabels()] == [r.name for r in rows]
    assert "stb_heald" in ax.get_title() and "300 rad/s" in ax.get_title()


@pytest.mark.parametrize("ext, magic", [("png", b"\x89PNG"), ("svg", b"<?xml"),
                                        ("pdf", b"%PDF")])
def test_format_follows_the_extension(tmp_path, capsys, ext, magic):
    path = tmp_path / f"K.{ext}"
    assert cli.main(["sweep", str(STB), "--omega-min", "10", "--omega-max", "1e4", "--log",
                     "--points", "50", "--plot", str(path)]) == 0
    assert path.read_bytes()[:len(magic)] == magic


def test_study_plot_one_parameter():
    from mechcirc.study import column_units, parse_spec, run_study

    spec = parse_spec({"netlist": str(STB), "analysis": "resonances",
                       "grid": {"eta1": [0.7, 0.8, 0.9]}})
    result = run_study(spec, workers=1)
    fig = plot_study(result, spec.params, "resonance_1", units=column_units(spec))
    ax = fig.axes[0]
    x, y = ax.lines[0].get_data()
    assert list(x) == [0.7, 0.8, 0.9]
    assert list(y) == [r["resonance_1"] for r in result.rows]
    assert ax.get_ylabel() == "resonance_1 [rad/s]" and ax.get_xlabel() == "eta1"
    # The units are the study's: a mass parameter [kg] and a count [1] (no unit shown).
    units = {"eta1": "kg", "resonance_1": "1"}
    ax3 = plot_study(result, spec.params, "resonance_1", ax=_axes()[1], units=units)
    assert ax3.get_xlabel() == "eta1 [kg]" and ax3.get_ylabel() == "resonance_1"
    fig2, ax2 = _axes()
    assert plot_study(result, spec.params, "resonance_1", ax=ax2) is ax2
    assert list(ax2.lines[0].get_ydata()) == list(y)


# ---------------------------------------------------------------------------
# One plotting convention (issue 15 §6, issue 17 §3): ax= / fig=, return what was
# drawn on, never switch the backend.

def _axes():
    from matplotlib.figure import Figure

    fig = Figure()
    return fig, fig.add_subplot()


def test_plot_sweep_on_a_given_axes(stb_sweep):
    c, s, found = stb_sweep
    fig, ax = _axes()
    assert plot_sweep(s, ax=ax, resonances=found, refine=False) is ax
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), np.abs(s.K))
    assert _root_marks(ax) == pytest.approx(sorted(r.omega_d or r.omega for r in found))
    assert s.plot(ax=_axes()[1]) is not None


def test_sweep_plot_delegate_and_fig(stb_sweep):
    from matplotlib.figure import Figure

    _, s, _ = stb_sweep
    fig = Figure()
    assert s.plot(fig=fig) is fig and len(fig.axes) == 3
    assert isinstance(s.plot(), Figure)


def test_force_drive_plots_the_velocity_response():
    c = mechcirc.parse("mass m a 0 2\nspring k a 0 800\ndamper d a 0 4\n"
                       "drive F a 0 force=3\n")
    w = np.geomspace(1, 100, 50)
    s = c.sweep(w)
    fig = plot_sweep(s)
    ax_q = fig.axes[2]
    # independent: v0 = F0 / (r + jωm + k/(jω)) for the parallel m, k, r
    expected = np.abs(3 / (4 + 1j * w * 2 + 800 / (1j * w)))
    np.testing.assert_allclose(ax_q.lines[0].get_ydata(), expected, rtol=1e-12)
    assert ax_q.get_ylabel().startswith("|v0|")
    assert "velocity response" in fig._suptitle.get_text()


def test_forces_on_axes_and_legend_swatches_match_bars(stb_sweep):
    from matplotlib.colors import to_rgba

    c, _, _ = stb_sweep
    rows, *_ = element_forces(c, 300.0)
    fig, ax = _axes()
    assert plot_forces(rows, omega=300.0, ax=ax) is ax
    legend = ax.get_legend()
    colour_of = {t.get_text(): h.get_facecolor() for t, h in
                 zip(legend.get_texts(), legend.legend_handles)}
    for row, bar in zip(rows, ax.patches):
        assert to_rgba(colour_of[row.kind]) == to_rgba(bar.get_facecolor())
    assert len(set(colour_of.values())) == len(colour_of) >= 2


def test_plots_never_switch_the_backend(stb_sweep):
    import matplotlib

    _, s, _ = stb_sweep
    before = matplotlib.get_backend()
    src = (REPO / "mechcirc" / "plotting.py").read_text() + \
        (REPO / "mechcirc" / "scene" / "cycle.py").read_text()
    assert "matplotlib.use(" not in src and "import matplotlib.pyplot" not in src
    plot_sweep(s)
    assert matplotlib.get_backend() == before


def test_cycle_plot_unit_and_labels():
    from matplotlib.figure import Figure

    from mechcirc.scene import load_scene
    from mechcirc.scene.cycle import cycle_map, plot_cycle

    scene = load_scene(REPO / "examples" / "heald_scene.toml")
    cmap = cycle_map(scene, points=6, harmonics=3)
    W = cmap.natural_frequencies()
    for unit, scale in (("rad/s", 1.0), ("Hz", 1 / (2 * np.pi)), ("rpm", 60 / (2 * np.pi))):
        fig = plot_cycle(cmap, fig=Figure(), unit=unit)
        a1 = fig.axes[0]
        assert f"[{unit}]" in a1.get_ylabel()
        np.testing.assert_allclose(a1.lines[0].get_ydata(), W[:, 0] * scale, rtol=1e-12)
        labels = [t.get_text() for t in a1.texts]
        assert labels == [f"{h}·Ω" for h in cmap.harmonics]
        named = [ln.get_label() for ln in a1.get_legend().get_lines()]
        assert all(f"resonance {k + 1}" in named for k in range(W.shape[1]))
    with pytest.raises(ValueError, match="rpm"):
        plot_cycle(cmap, unit="kHz")


def test_short_reprs(stb_sweep):
    c, s, _ = stb_sweep
    assert len(repr(c)) < 200 and "stb_heald" in repr(c) and "12 masses" in repr(c)
    big = c.sweep(np.geomspace(10, 1e4, 800))
    assert len(repr(big)) < 300 and "800 points" in repr(big)
    assert big._repr_html_().startswith("<pre>")


def test_kinematics_plots_take_fig_and_ax():
    from matplotlib.figure import Figure

    from mechcirc.kinematics.fourbar import FourBar
    from mechcirc.kinematics.linkage import load_linkage
    from mechcirc.kinematics.plots import plot_fourbar, plot_linkage

    fig = Figure()
    assert plot_fourbar(FourBar(29, 37, 188, 189), 100, fig=fig) is fig and len(fig.axes) == 4
    lk = load_linkage(REPO / "examples" / "fnf_sixbar.toml")
    state = lk.solve(0.0)
    fig, ax = _axes()
    assert plot_linkage(lk, state, ax=ax) is ax and ax.lines


def test_comparison_plot_on_a_given_figure():
    from matplotlib.figure import Figure

    from mechcirc.interop.skrf import compare
    from mechcirc.plotting import plot_comparison

    c = mechcirc.load(STB)
    result = compare(c, REPO / "docs" / "examples" / "measured.s1p")
    fig = Figure()
    assert plot_comparison(result, name=c.name, fig=fig) is fig and len(fig.axes) == 2
    np.testing.assert_allclose(fig.axes[0].lines[0].get_xdata(), result.omega)


def test_sweep_plot_marks_resonances_by_default():
    """Sweep.plot(ax=) draws the circuit's resonances in the band unless told not to."""
    from matplotlib.figure import Figure

    c = mechcirc.load(STB)
    s = c.sweep(np.geomspace(10, 1e4, 200))
    bare = Figure().add_subplot()
    s.plot(ax=bare, resonances=())
    marked = Figure().add_subplot()
    assert s.plot(ax=marked) is marked
    inband = [r.omega for r in c.resonances(omega_max=1e4) if r.omega >= 10]
    assert inband
    assert _root_marks(bare) == []
    assert _root_marks(marked) == pytest.approx(sorted(inband), rel=1e-12)


def test_sweep_plot_marks_damped_roots_at_omega_d_and_no_overdamped_one():
    """A damped chain's roots are drawn at ω_d (where the legend now says so; the tables
    give ω = |s|), and an overdamped root (ζ = 1: no frequency where K has an extreme) is
    not drawn: it was, at |s|, stretching the x axis far past the sweep (the new-user
    pass).  ω_d of the one underdamped resonance from its own ω and ζ."""
    from matplotlib.figure import Figure

    c = mechcirc.parse("drive V a 0 velocity=1\nspring k1 a b 1e4\nmass m b 0 1\n"
                       "damper c b d 30\nspring k2 d 0 1e4\n")
    found = c.resonances(omega_max=1e5)
    assert any(r.zeta == 1.0 for r in found) and any(r.zeta < 1 for r in found)
    ax = Figure().add_subplot()
    c.sweep(np.geomspace(10, 1e3, 100)).plot(ax=ax, resonances=found)
    want = sorted(r.omega * np.sqrt(1 - r.zeta ** 2) for r in found if r.zeta < 1)
    assert _root_marks(ax) == pytest.approx(want, rel=1e-9)
    assert ax.get_xlim()[1] < 2e3
    assert any("at ω_d" in t.get_text() for t in ax.get_legend().get_texts())


def test_sweep_plot_is_refined_around_the_exact_roots(stb_sweep):
    """stb_heald's close pair 706.45 / 709.55 rad/s falls between two grid points
    (2.3 % apart): the plotted curve gets points within 1e-3 of every root, and the
    added points are the circuit's K (checked against the second solver, nodal)."""
    c, s, found = stb_sweep
    fig = plot_sweep(s, resonances=found)
    x, phase = fig.axes[1].lines[0].get_data()
    for r in found:
        assert np.min(np.abs(x / r.omega - 1)) < 1e-3, r
        assert np.min(np.abs(s.omega / r.omega - 1)) > 1e-3      # the grid alone has none
    added = ~np.isin(x, s.omega)
    assert added.sum() >= 2 * len(found)
    nodal = c.sweep(x[added], method="nodal")
    np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata()[added], np.abs(nodal.K),
                               rtol=1e-9)
    np.testing.assert_allclose(phase[added], np.degrees(np.angle(nodal.K)), atol=1e-6)
    # the pair is resolved: K (undamped, imaginary) changes sign at the zero and back at
    # the pole, so arg K is ±90° inside the pair and ∓90° on both sides of it; the grid
    # has no point inside it, the plotted curve several
    lo, hi = sorted(r.omega for r in found if 700 < r.omega < 720)
    assert not ((s.omega > lo) & (s.omega < hi)).any()
    inside, below, above = (x > lo) & (x < hi), (x < lo) & (x > 700), (x > hi) & (x < 720)
    assert inside.sum() >= 4
    assert np.ptp(phase[inside]) < 1e-6 and abs(phase[inside][0]) == pytest.approx(90)
    assert np.all(np.abs(phase[below] - phase[inside][0]) == pytest.approx(180))
    assert np.all(np.abs(phase[above] - phase[inside][0]) == pytest.approx(180))


def test_close_roots_get_labels_at_different_heights(stb_sweep):
    _, s, found = stb_sweep
    for where in (plot_sweep(s, resonances=found).axes[0],
                  plot_sweep(s, ax=_axes()[1], resonances=found)):
        labels = {round(float(t.get_text())): t.get_position()[1] for t in where.texts}
        assert set(labels) == {round(r.omega_d) for r in found}
        assert labels[706] != labels[710]                  # 0.44 % apart: staggered
        assert labels[3641] == labels[706]                 # far from any other: top row
        # on one row, labels stand ≥ 8 % of the (log) axis width apart: they do not overlap
        span = np.log(np.divide(*where.get_xlim()[::-1]))
        rows = {}
        for t in where.texts:
            rows.setdefault(t.get_position()[1], []).append(np.log(t.get_position()[0]))
        for xs in rows.values():
            assert np.all(np.diff(sorted(xs)) >= 0.08 * span)


@pytest.fixture(scope="module")
def msl_transient():
    from mechcirc.transient import transient

    return transient(mechcirc.load(REPO / "examples/msl_backlash.mcir"), 1.0, 1e-3)


def test_transient_plot_title_names_the_waveform():
    from mechcirc.transient import transient

    c = mechcirc.parse("drive V a 0 velocity=0.1\nmass m a b 1\nspring k b 0 1e4\n")
    fig = transient(c, 0.02, 1e-4, waveform="harmonic:300").plot()
    assert fig._suptitle.get_text() == "circuit: transient, velocity drive V, sin(300 rad/s·t)"
    step = transient(c, 0.02, 1e-4, waveform="step")
    assert step.waveform == "step" and step.plot()._suptitle.get_text().endswith("V, step")


def _hlines(ax):
    """y of the horizontal lines drawn across ``ax`` (axhline: x from 0 to 1 in axes units)."""
    return sorted(float(line.get_ydata()[0]) for line in ax.lines
                  if list(line.get_xdata()) == [0, 1] and len(set(line.get_ydata())) == 1)


def test_transient_plot_units_forces_and_clearance_band(msl_transient):
    """msl_backlash: a torque drive on inertias, total backlash 45° of spring eb."""
    r = msl_transient
    fig = r.plot(elements=["eb", "sd"])
    ax_x, ax_f, ax_e = fig.axes
    assert ax_x.get_ylabel() == "displacement x [rad]"
    assert ax_f.get_ylabel() == "element moment [N·m]"
    assert ax_e.get_ylabel() == "deformation eb [rad]" and ax_e.get_xlabel() == "t [s]"
    assert "msl_backlash" in fig._suptitle.get_text() and "drive T" in fig._suptitle.get_text()
    np.testing.assert_array_equal(ax_f.lines[1].get_ydata(), r.element_force("sd"))
    # the band ±B/2 with B = 45° from the netlist, in the panel's data coordinates
    assert _hlines(ax_e) == pytest.approx([-np.pi / 8, np.pi / 8], rel=1e-15)
    # deformation of eb (phi to ground) is x(phi)
    np.testing.assert_array_equal(ax_e.lines[0].get_ydata(), r.node("phi")[0])
    # contact phases shaded: the spans where |x(phi)| > B/2, a few of them over 1 s
    (shade,) = ax_e.collections
    assert shade.get_label() == "contact"
    inside = np.abs(r.node("phi")[0]) > np.pi / 8
    starts = np.count_nonzero(np.diff(inside.astype(int)) == 1) + inside[0]
    assert len(shade.get_paths()) == starts >= 5


def test_transient_plot_keeps_the_callers_axes_and_names_units(msl_transient):
    from matplotlib.figure import Figure

    from mechcirc.errors import MechcircError

    fig = Figure()
    top, bottom = fig.subfigures(2, 1)
    mine = top.add_subplot()
    mine.plot([0, 1], [0, 1])
    with pytest.raises(MechcircError, match="plot_transient.*already holds 1 Axes.*subfigure"):
        msl_transient.plot(fig=fig)            # its panels would cover the caller's
    assert msl_transient.plot(fig=bottom) is bottom
    assert mine in fig.axes and len(mine.lines) == 1 and len(fig.axes) == 3
    _, ax = _axes()
    assert msl_transient.plot(ax=ax, what="v") is ax
    assert ax.get_ylabel() == "velocity v [rad/s]" and "drive T" in ax.get_title()
    # a translational netlist says m
    from mechcirc.transient import transient

    c = mechcirc.parse("drive F a 0 force=1\nspring k a 0 100\nmass m a 0 1\n")
    lin = transient(c, 0.1, 1e-3, "step")
    fig = lin.plot(elements=["k"])
    assert [a.get_ylabel() for a in fig.axes] == ["displacement x [m]", "element force [N]"]


def test_transient_plot_refuses_an_unknown_name(msl_transient):
    from mechcirc.errors import MechcircError

    with pytest.raises(MechcircError, match="unknown element 'nope'.*J1, eb"):
        msl_transient.plot(elements=["nope"])
    with pytest.raises(MechcircError, match="unknown node 'q'"):
        msl_transient.plot(nodes=["q"])


@pytest.mark.parametrize("unit, per_rad_s", [("rad/s", 1.0), ("rpm", 60 / (2 * np.pi))])
def test_undamped_peak_marks_every_pole_on_one_line(stb_sweep, unit, per_rad_s):
    """Each undamped resonance in the band gets a triangle at the top of the |Q0|
    panel, all on one line of markers with one legend entry."""
    c, s, found = stb_sweep
    pk = s.peak()
    assert pk.unbounded and len(pk.poles) >= 2     # stb_heald: three in 10 … 1e4 rad/s
    fig = plot_sweep(s, resonances=found, peak=pk, unit=unit)
    ax_q = fig.axes[2]
    marks = [ln for ln in ax_q.get_lines() if ln.get_marker() == "^"]
    assert len(marks) == 1
    np.testing.assert_allclose(marks[0].get_xdata(), np.asarray(pk.poles) * per_rad_s,
                               rtol=1e-15)
    assert list(marks[0].get_ydata()) == [1.0] * len(pk.poles)     # the axis's top
    assert marks[0].get_transform() == ax_q.get_xaxis_transform()
    labels = [t.get_text() for t in ax_q.get_legend().get_texts()]
    assert labels.count("|Q0| = ∞ (undamped)") == 1
