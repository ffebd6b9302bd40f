"""Plots draw the API's numbers, with units on every axis and the netlist's name."""

from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from mechcirc.forces import element_forces
from mechcirc.plotting import plot_forces, plot_study, plot_sweep

REPO = Path(__file__).resolve().parents[1]
STB = REPO / "netlists" / "stb_heald.mcir"


@pytest.fixture(scope="module")
def stb_sweep():
    c = mechcirc.load(STB)
    omega = np.geomspace(10, 1e4, 300)
    return c, c.sweep(omega), c.resonances(omega_max=1e4)


def test_bode_panels_draw_K_phase_and_Q0(stb_sweep):
    c, s, found = stb_sweep
    fig = plot_sweep(s, resonances=found)
    ax_k, ax_p, ax_q = fig.axes
    assert [ax.get_ylabel() for ax in fig.axes] == ["|K| [m/(N·s)]", "arg K [deg]", "|Q0| [N]"]
    assert ax_q.get_xlabel() == "ω [rad/s]"
    assert "stb_heald" in fig._suptitle.get_text()
    x, y = ax_k.lines[0].get_data()
    np.testing.assert_array_equal(x, s.omega)
    np.testing.assert_array_equal(y, np.abs(s.K))
    np.testing.assert_allclose(ax_p.lines[0].get_ydata(), np.degrees(np.angle(s.K)))
    np.testing.assert_array_equal(ax_q.lines[0].get_ydata(), np.abs(s.Q0))
    # one vertical marker per resonance in every panel, at its frequency
    for ax in fig.axes:
        marks = sorted(line.get_xdata()[0] for line in ax.lines[1:]
                       if len(set(line.get_xdata())) == 1)
        assert marks == pytest.approx(sorted(r.omega_d or r.omega for r in found))


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
    from mechcirc.study import parse_spec, run_study

    spec = parse_spec({"netlist": str(STB), "analysis": "resonances",
                       "grid": {"eta1": [0.7, 0.8, 0.9]}})
    result = run_study(spec, workers=1)
    fig = plot_study(result, spec.params, "resonance_1")
    ax = fig.axes[0]
    x, y = ax.lines[0].get_data()
    assert list(x) == [0.7, 0.8, 0.9]
    assert list(y) == [r["resonance_1"] for r in result.rows]
    assert ax.get_ylabel() == "resonance_1 [rad/s]" and ax.get_xlabel() == "eta1"
