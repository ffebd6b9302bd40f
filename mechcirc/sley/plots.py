"""Plots of sley simulations: the curves of Mrázek's Figs. 4–9 (matplotlib imported inside)."""

from __future__ import annotations

import math

__all__ = ["plot_result"]


def plot_result(result, fig=None, *, ax=None):
    """ε2P, ε4P with ε4T, and M2V (M5V, ε5P for both sides) against crank angle.

    Parameters
    ----------
    result : SleyResult
        A simulated sley (:func:`mechcirc.sley.simulate`).
    fig : matplotlib Figure or SubFigure, optional
        An empty one to fill (:func:`mechcirc.plotting.new_panels`); a new one by default.
    ax : matplotlib.axes.Axes, optional
        Draw only the crank accelerations there (nothing else of its figure is
        touched); ``fig`` is then not used.

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on: ``ax`` when given, else ``fig`` (it must be empty) or the new Figure.
    """
    import numpy as np
    from ..plotting import laid_out, new_panels

    fig, grid = new_panels(fig, 3, caller="plot_result", figsize=(8, 9), sharex=True, ax=ax)
    axes, deg = grid[:, 0], np.degrees(result.crank_angle)
    # the cranks' panels: crank 2P, and crank 5P when there is one (both sides)
    for panel, ylabel, curves in (
            (axes[0], "crank acceleration [rad/s²]",
             (("ε2P (crank 2P)", result.eps2P), ("ε5P (crank 5P)", result.eps5P))),
            (axes[2], "driving moment [N·m]", (("M2V", result.M2V), ("M5V", result.M5V)))):
        for label, y in curves:
            if y is not None:
                panel.plot(deg, y, lw=0.8, label=label)
        panel.set_ylabel(ylabel)
    panel = axes[1]
    panel.plot(deg, result.eps4P, lw=0.8, label="ε4P (sley)")
    panel.plot(deg, result.eps4T, lw=1.2, ls="--", color="k", label="ε4T = ν ω² (rigid)")
    lo = math.degrees(result.phiP - result.params.alpha / 2) % 360
    for a, label in ((lo, "beat-up window"), (lo - 360, None)):
        b = a + result.alpha_deg
        if result.params.M0 > 0 and max(a, 0) < min(b, 360):     # wrapped at 0°/360°
            panel.axvspan(max(a, 0), min(b, 360), color="0.9",
                          label=label and f"{label} (α = {result.alpha_deg:g}°)")
    panel.set_ylabel("sley acceleration [rad/s²]")
    axes[2].set_xlabel("crank angle φ2 [deg]")
    p = result.params
    fig.suptitle(f"{p.label or p.drive}: revolution {result.revolution}, ω = {p.omega:g} rad/s, "
                 f"ϕ = {p.clearance:g} rad, M0 = {p.M0:g} N·m, α = {result.alpha_deg:g}°",
                 fontsize=10)
    for a in axes:
        a.legend(loc="upper right", fontsize=8)
        a.grid(alpha=0.3)
        a.set_xlim(0, 360)
    return laid_out(False, fig, ax, grid)
