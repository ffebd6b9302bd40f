"""User-facing loose ends: names checked before a long run, plots returning what they drew on.

* ``mechcirc transient --element NAME`` refuses an unknown element (with "did you
  mean") before it integrates, not after the whole run;
* ``mechcirc.scene.plots.plot_mode`` without ``ax=`` returns the Figure it made,
  like every single-panel plot of mechcirc;
* every public plot function's Returns section says what it returns.
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

import pytest
from cli_helpers import run

REPO = Path(__file__).resolve().parents[1]


def test_transient_unknown_element_is_refused_before_integrating(tmp_path, capsys, monkeypatch):
    import mechcirc.transient

    calls = []
    real = mechcirc.transient.transient
    monkeypatch.setattr(mechcirc.transient, "transient",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    png, csv = tmp_path / "t.png", tmp_path / "t.csv"
    net = REPO / "examples/msl_backlash.mcir"
    status, out, err = run(["transient", net, "--t-end", "1", "--dt", "1e-3", "--plot", png,
                            "-o", csv, "--element", "sd", "--element", "ebb"], capsys)
    assert status == 2, err
    assert "unknown element 'ebb'; did you mean 'eb'? (given to --element; the netlist has " \
        "J1, eb, eb_damping, J2, sd, sd_damping)" in err
    assert calls == [] and not png.exists() and not csv.exists() and out == ""
    # --element without --plot: also told before the run
    status, _, err = run(["transient", net, "--t-end", "1", "--element", "eb"], capsys)
    assert status == 2 and "--plot" in err and calls == []
    # a right name runs (the wrapper is reached once)
    status, _, err = run(["transient", net, "--t-end", "0.01", "--dt", "1e-3", "--plot", png,
                          "--element", "eb"], capsys)
    assert status == 0, err
    assert calls == [1] and png.read_bytes()[:4] == b"\x89PNG"


def test_check_names_lists_at_most_twenty_names():
    import mechcirc
    from mechcirc.cli._common import SHOWN_NAMES, check_names
    from mechcirc.errors import MechcircError

    text = "drive F n0 0 force=1\n" + "".join(
        f"spring k{i} n{i} n{i + 1} 100\nmass m{i} n{i + 1} 0 1\n" for i in range(30))
    known = [e.name for e in mechcirc.parse(text).elements]
    check_names(["k3", "m29"], known)           # known names pass
    check_names(None, known)
    with pytest.raises(MechcircError) as err:
        check_names(["k3", "kk29"], known)
    msg = str(err.value)
    assert "unknown element 'kk29'" in msg and "did you mean 'k29'?" in msg
    listed = msg.split("the netlist has ")[1]
    assert listed.count(",") == SHOWN_NAMES and listed.endswith("... (60 in all))")


def test_sweep_node_and_element_names_are_checked_before_the_sweep(capsys, monkeypatch):
    import mechcirc.cli.circuit_commands as cc

    calls = []
    real = cc._run_sweep
    monkeypatch.setattr(cc, "_run_sweep", lambda *a: calls.append(1) or real(*a))
    net = REPO / "netlists/stb_heald.mcir"
    base = ["sweep", net, "--omega-min", "10", "--omega-max", "1e4"]
    status, _, err = run([*base, "--node", "AA"], capsys)
    assert status == 2 and "unknown node 'AA'; did you mean 'A'? (given to --node" in err
    status, _, err = run([*base, "--element", "k44"], capsys)
    assert status == 2 and "unknown element 'k44'; did you mean 'k4'? (given to --element" in err
    status, _, err = run([*base, "--sensitivity", "eta5"], capsys)
    assert status == 2 and "no element, lever or .param named 'eta5'; did you mean" in err
    assert calls == []
    status, _, err = run([*base, "--sensitivity", "etaC", "--sensitivity", "k0", "--points",
                          "3", "--node", "A", "--element", "k4"], capsys)
    assert status == 0 and calls == [1], err       # the right names pass, and it sweeps


def test_scene_plot_mode_without_ax_returns_its_figure():
    from matplotlib.figure import Figure

    from mechcirc.scene import load_scene
    from mechcirc.scene.plots import plot_mode

    fig = plot_mode(load_scene(REPO / "examples/heald_scene.toml"), 0.7, 1)
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    gids = {ln.get_gid() for ln in fig.axes[0].lines}
    assert "ground" in gids and any(g.startswith("mode:") for g in gids)
    assert any(g.startswith("rigid:") for g in gids)


def _plot_functions():
    for mod in ("mechcirc.plotting", "mechcirc.scene.plots", "mechcirc.scene.cycle",
                "mechcirc.sley.plots", "mechcirc.kinematics.plots"):
        m = importlib.import_module(mod)
        for name in dir(m):
            f = getattr(m, name)
            if name.startswith(("plot_", "draw_")) and callable(f) and f.__module__ == mod:
                yield f"{mod}.{name}", f


def _returns(f) -> str:
    doc = inspect.getdoc(f) or ""
    head = "Returns\n-------\n"
    assert head in doc, f.__qualname__
    body = doc.split(head, 1)[1]
    return body.split("\n\n")[0] if "\n\n" in body else body


def test_every_plot_functions_returns_section_says_what_it_returns():
    """``ax=None`` → Axes or a new Figure; ``fig=`` → the given (empty) Figure or SubFigure."""
    seen = 0
    for name, f in _plot_functions():
        params = inspect.signature(f).parameters
        text = _returns(f)
        if "ax" in params:
            assert "Axes" in text, (name, text)
            if params["ax"].default is None:          # without ax it makes a Figure
                assert "Figure" in text, (name, text)
        if "fig" in params:
            assert "``fig``" in text and "empty" in text, (name, text)
        seen += 1
    assert seen >= 19


def test_result_plot_methods_say_fig_must_be_empty():
    from mechcirc import Sweep
    from mechcirc.periodic import PeriodicResult
    from mechcirc.transient import TransientResult

    for cls in (Sweep, TransientResult, PeriodicResult):
        doc = " ".join((inspect.getdoc(cls.plot) or "").split())
        assert "*empty* Figure or SubFigure" in doc and "refused" in doc, cls
