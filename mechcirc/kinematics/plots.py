"""Figures for the kinematics: four-bar transfer functions, synthesis, frame loading, linkages.

matplotlib is imported inside each function (and only its object-oriented
``Figure``, never ``pyplot``), so importing this module is cheap and works on
any backend, Agg included.  Each function draws on ``fig`` when given (the
convention of :mod:`mechcirc.plotting`: multi-panel plots take ``fig=``,
single-panel ones also ``ax=``) or on a new ``matplotlib.figure.Figure``, and
returns what it drew on; saving is the caller's business (the CLI uses
:func:`mechcirc.cli._common.save_figure`).  Angles are plotted in degrees.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plot_fourbar", "plot_synthesis", "plot_frame_loading", "plot_linkage"]


def _figure(rows, cols, size, fig=None):
    if fig is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=size, layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
    return fig, axes


def plot_fourbar(fourbar, omega: float | None = None, n: int = 721, *, fig=None):
    """φ4, μ, ν (or ε4T = ν ω² when ``omega`` [rad/s] is given) and γ against θ.

    Dead centres are marked on every panel when the linkage is a crank-rocker.
    """
    lo, hi = fourbar.crank_range()
    th = np.linspace(lo, hi, n)
    if not fourbar.crank_rotates_fully:
        th = th[1:-1]
    st = fourbar.evaluate(th)
    deg = np.degrees(th)
    fig, ax = _figure(4, 1, (7, 9), fig)
    acc = st.nu * omega ** 2 if omega else st.nu
    panels = [(np.degrees(st.phi4), "φ4 [deg]"), (st.mu, "μ = dφ4/dθ [1]"),
              (acc, "ε4T = ν·ω² [1/s²]" if omega else "ν = d²φ4/dθ² [1/rad]"),
              (np.degrees(st.gamma), "γ [deg]")]
    for a, (y, label) in zip(ax[:, 0], panels):
        a.plot(deg, y, lw=1.4)
        a.set_ylabel(label)
        a.grid(alpha=0.3)
    if fourbar.linkage_type == "crank-rocker" and fourbar.crank_rotates_fully:
        for dc, style in zip(fourbar.dead_centres(), ("--", ":")):
            for a in ax[:, 0]:
                a.axvline(math.degrees(dc.theta), color="k", ls=style, lw=0.8,
                          label=f"{dc.kind} dead centre")
        ax[0, 0].legend(loc="best", fontsize="small")
    ax[-1, 0].set_xlabel("crank angle θ [deg]")
    fig.suptitle(f"four-bar a={fourbar.crank:g} b={fourbar.coupler:g} c={fourbar.rocker:g} "
                 f"d={fourbar.frame:g} ({fourbar.linkage_type}, branch {fourbar.branch:+d})")
    return fig


def plot_synthesis(designs, n: int = 721, *, fig=None):
    """Patent-style figures: transmission angle and dimensionless rocker acceleration ν against θ.

    θ is measured from the front dead centre of each design, so the curves line up.
    """
    fig, ax = _figure(2, 1, (7, 7), fig)
    for k, des in enumerate(designs):
        fb = des.fourbar()
        front, _ = fb.dead_centres()
        th = front.theta + np.linspace(0, 2 * math.pi, n)
        st = fb.evaluate(th)
        label = f"#{k + 1}: {des.a:.1f}/{des.b:.1f}/{des.c:.1f}/{des.d:.1f} mm"
        deg = np.degrees(th - front.theta)
        ax[0, 0].plot(deg, np.degrees(st.gamma), lw=1.2, label=label)
        ax[1, 0].plot(deg, st.nu, lw=1.2, label=label)
    ax[0, 0].axhline(45, color="r", ls="--", lw=0.8, label="γ = 45° (eq. 3)")
    ax[0, 0].set_ylabel("transmission angle γ [deg]")
    ax[1, 0].set_ylabel("rocker acceleration d²Φ/dθ² [1/rad]")
    ax[1, 0].set_xlabel("crank angle from the front dead centre [deg]")
    for a in ax[:, 0]:
        a.grid(alpha=0.3)
    ax[0, 0].legend(fontsize="small", loc="best")
    fig.suptitle("beat-up four-bar synthesis (CN104178888)")
    return fig


def plot_frame_loading(result, *, fig=None):
    """Shaking force (components and magnitude), driving torque and shaking moments against θ."""
    fig, ax = _figure(3, 1, (7, 8), fig)
    deg = np.degrees(result.theta)
    S = result.shaking_force
    ax[0, 0].plot(deg, S[:, 0], label="S_x")
    ax[0, 0].plot(deg, S[:, 1], label="S_y")
    ax[0, 0].plot(deg, result.shaking_force_magnitude, "k", label="|S|")
    ax[0, 0].set_ylabel("shaking force [N]")
    ax[1, 0].plot(deg, result.torque, label="T")
    ax[1, 0].set_ylabel("crank torque [N·m]")
    ax[2, 0].plot(deg, result.T_a, label="T_a (about A)")
    ax[2, 0].plot(deg, result.T_d, label="T_d (about D)")
    ax[2, 0].set_ylabel("shaking moment [N·m]")
    ax[2, 0].set_xlabel("crank angle θ [deg]")
    for a in ax[:, 0]:
        a.grid(alpha=0.3)
        a.legend(fontsize="small", loc="best")
    return fig


def plot_linkage(linkage, state, paths=None, *, ax=None, fig=None):
    """The linkage drawn at ``state``, with traced point paths ``{point: (n, 2) array}``.

    On ``ax`` when given (and then returns it), else on ``fig`` or a new Figure
    (returned).
    """
    if ax is not None:
        a = ax
    else:
        fig, axes = _figure(1, 1, (7, 7), fig)
        a = axes[0, 0]
    if paths:
        for p, xy in paths.items():
            a.plot(xy[:, 0], xy[:, 1], lw=0.8, alpha=0.7)
    for name, pts in linkage.links.items():
        xy = np.array([state.points[p] for p in pts] + [state.points[pts[0]]])
        if len(pts) > 2:
            a.fill(xy[:, 0], xy[:, 1], alpha=0.25)
        a.plot(xy[:, 0], xy[:, 1], "-o", lw=2, ms=4)
        mid = xy[:-1].mean(axis=0)
        a.annotate(name, mid, fontsize="small", ha="center")
    g = np.array([state.points[p] for p in linkage.ground])
    a.plot(g[:, 0], g[:, 1], "k^", ms=10)
    for p, x in state.points.items():
        a.annotate(p, x, textcoords="offset points", xytext=(4, 4), fontsize="x-small")
    a.set_aspect("equal")
    a.grid(alpha=0.3)
    a.set_title(f"{linkage.name} at θ = {math.degrees(state.theta):.4g}°")
    return a if ax is not None else fig
