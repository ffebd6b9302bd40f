"""Figures for the kinematics: four-bar transfer functions, synthesis, frame loading, linkages.

matplotlib is imported inside each function (and only its object-oriented
``Figure``, never ``pyplot``), so importing this module is cheap and works on
any backend, Agg included.  The convention of :mod:`mechcirc.plotting`:
multi-panel plots take ``fig=`` (an empty Figure or SubFigure to fill, see
:func:`mechcirc.plotting.new_panels`; a new constrained-layout Figure by
default) or ``ax=`` (their main panel only), single-panel ones ``ax=``; each
returns what it drew on and never clears or deletes what the caller drew.  Saving is the caller's
business (the CLI uses :func:`mechcirc.cli._common.save_figure`).  Angles are
plotted in degrees.
"""

from __future__ import annotations

import math

import numpy as np

from ..plotting import laid_out, new_panels
from ..units import convert_frequency

__all__ = ["plot_fourbar", "plot_synthesis", "draw_design", "plot_frame_loading", "plot_shaking", "plot_linkage"]


def _figure(rows, cols, size, fig, caller: str, ax=None, **subplots_kw):
    """:func:`mechcirc.plotting.new_panels` with this module's constrained layout."""
    return new_panels(fig, rows, cols, caller=caller, figsize=size, layout="constrained",
                      ax=ax, **subplots_kw)


def plot_fourbar(fourbar, omega: float | None = None, n: int = 721, *, ax=None, fig=None):
    """φ4, μ, ν (or ε4T = ν ω² when ``omega`` [rad/s] is given) and γ against θ.

    Dead centres are marked on every panel when the linkage is a crank-rocker.

    Parameters
    ----------
    fourbar : FourBar
        The linkage to plot.
    omega : float, optional
        Crank speed [rad/s].
    n : int
        Points over a revolution.
    ax : matplotlib.axes.Axes, optional
        Draw only the φ4 panel there (and not use ``fig``).
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one to fill with the four panels; a new one by default.

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on: ``ax``, else ``fig`` (empty) or a new Figure.
    """
    lo, hi = fourbar.crank_range()
    th = np.linspace(lo, hi, n)
    th = th if fourbar.crank_rotates_fully else th[1:-1]
    st = fourbar.evaluate(th)              # (no warning at a crossing's 0/0: evaluate's own)
    deg = np.degrees(th)
    fig, axes = _figure(4, 1, (7, 9), fig, "plot_fourbar", ax)
    acc = st.nu * omega ** 2 if omega else st.nu
    crossings = fourbar.branch_crossings()
    if crossings:
        # the closed form switches branch at a crossing: μ, ν not drawn within 1° (±1e15 jumps)
        near = np.any([np.abs((th - tc + math.pi) % (2 * math.pi) - math.pi) < math.radians(1.0)
                       for tc in crossings], axis=0)
        st = type(st)(**{**st.__dict__, "mu": np.where(near, np.nan, st.mu)})
        acc = np.where(near, np.nan, acc)
    panels = [(np.degrees(st.phi4), "φ4 [deg]"), (st.mu, "μ = dφ4/dθ [1]"),
              (acc, "ε4T = ν·ω² [rad/s²]" if omega else "ν = d²φ4/dθ² [1/rad]"),
              (np.degrees(st.gamma), "γ [deg]")]
    for a, (y, label) in zip(axes[:, 0], panels):
        a.plot(deg, y, lw=1.4)
        a.set_ylabel(label)
        a.grid(alpha=0.3)
    if fourbar.is_full_turn_crank_rocker:
        for dc, style in zip(fourbar.dead_centres(), ("--", ":")):
            for a in axes[:, 0]:
                a.axvline(math.degrees(dc.theta), color="k", ls=style, lw=0.8,
                          label=f"{dc.kind} dead centre")
        axes[0, 0].legend(loc="best", fontsize="small")
    for k, tc in enumerate(crossings):
        for a in axes[:, 0]:
            a.axvline(math.degrees(tc), color="r", ls="-.", lw=0.8,
                      label="branch crossing (μ, ν undefined)" if k == 0 else None)
    if crossings:
        axes[1, 0].legend(loc="best", fontsize="small")
    axes[-1, 0].set_xlabel("crank angle θ [deg]")
    fig.suptitle(f"four-bar a={fourbar.crank:g} b={fourbar.coupler:g} c={fourbar.rocker:g} "
                 f"d={fourbar.frame:g} ({fourbar.linkage_type}, branch {fourbar.branch:+d})")
    return laid_out(False, fig, ax, axes)


def draw_design(design, ax):
    """The four-bar of ``design`` on ``ax``: both dead-centre positions and the swing arc.

    Lengths in mm; A at the origin, D on the x axis.  Returns ``ax``.

    Parameters
    ----------
    design : Design
        A synthesised design.
    ax : matplotlib.axes.Axes
        Drawn on.

    Returns
    -------
    matplotlib.axes.Axes
    """
    fb = design.fourbar()
    front, back = fb.dead_centres()
    a, c, d = fb.crank, fb.rocker, fb.frame
    for dc, style, colour in ((front, "-", "C0"), (back, "--", "C1")):
        _, B, C, _ = fb.joints(dc.theta)
        ax.plot([0, B[0], C[0], d], [0, B[1], C[1], 0], style, color=colour, lw=2, marker="o",
                ms=4, label=f"{dc.kind} dead centre (θ = {math.degrees(dc.theta):.1f}°)")
    lo, hi = sorted((front.phi4, back.phi4))
    arc = np.linspace(lo, hi, 60)
    ax.plot(d + c * np.cos(arc), c * np.sin(arc), color="k", lw=1,
            label=f"swing Ψ = {design.swing_deg:.2f}°")
    th = np.linspace(0, 2 * math.pi, 121)
    ax.plot(a * np.cos(th), a * np.sin(th), color="0.6", lw=0.8)
    ax.plot([0, d], [0, 0], "k^", ms=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel="x [mm]", ylabel="y [mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small", loc="best")
    ax.get_title() or ax.set_title(f"#1: a={design.a:.2f} b={design.b:.2f} c={design.c:.2f} "
                                   f"d={design.d:.2f} mm")
    return ax


def plot_synthesis(designs, n: int = 721, fig=None, *, ax=None):
    """Patent-style figures beside the best design drawn.

    Left: ``designs[0]`` at both dead centres with its swing (:func:`draw_design`).
    Right: transmission angle and dimensionless rocker acceleration ν against θ
    for every design, θ measured from each design's front dead centre so the
    curves line up.  Draws on ``fig`` when given; returns the figure.

    Parameters
    ----------
    designs : sequence of Design
        The designs, best first.
    n : int
        Points of each design's curves over a revolution.
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one to fill with both panels; a new one by default.
    ax : matplotlib.axes.Axes, optional
        Draw only the best design (:func:`draw_design`) there (nothing else of its
        figure is touched); ``fig`` is then not used.

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on (``ax`` when given; else ``fig``, it must be empty, or a
        new Figure): the best design on the left, the curves of all on the right.
    """
    fig, ((left, right),) = _figure(1, 2, (12, 7), fig, "plot_synthesis", ax,
                                    width_ratios=(1, 1.3))
    draw_design(designs[0], left)
    grid = right.get_subplotspec().subgridspec(2, 1)
    right.remove()                  # ours, just made: its slot holds two panels
    pn = [fig.add_subplot(grid[0]), None]
    pn[1] = fig.add_subplot(grid[1], sharex=pn[0])
    for k, des in enumerate(designs):
        fb = des.fourbar()
        front, _ = fb.dead_centres()
        th = front.theta + np.linspace(0, 2 * math.pi, n)
        st = fb.evaluate(th)
        label = f"#{k + 1}: {des.a:.1f}/{des.b:.1f}/{des.c:.1f}/{des.d:.1f} mm"
        deg = np.degrees(th - front.theta)
        pn[0].plot(deg, np.degrees(st.gamma), lw=1.2, label=label)
        pn[1].plot(deg, st.nu, lw=1.2, label=label)
    pn[0].axhline(45, color="r", ls="--", lw=0.8, label="γ = 45° (eq. 3)")
    pn[0].set_ylabel("transmission angle γ [deg]")
    pn[1].set(ylabel="rocker acceleration d²Φ/dθ² [1/rad]",
              xlabel="crank angle from the front dead centre [deg]")
    for a in pn:
        a.grid(alpha=0.3)
    pn[0].legend(fontsize="small", loc="best")
    fig.suptitle("beat-up four-bar synthesis (CN104178888)")
    return laid_out(False, fig, ax, np.array([[left]]))


def plot_frame_loading(result, *, ax=None, fig=None):
    """Shaking force (components and magnitude), driving torque and shaking moments against θ.

    Parameters
    ----------
    result : FrameLoading
        Its shaking force, crank torque and shaking moments are drawn.
    ax : matplotlib.axes.Axes, optional
        Draw only the shaking force panel there (nothing else of its figure is
        touched); ``fig`` is then not used.
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one to fill (three panels); a new 7 × 8 in one by default.

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on (``ax`` when given; else ``fig``, it must be empty, or a
        new Figure): its three panels stacked.
    """
    fig, axes = _figure(3, 1, (7, 8), fig, "plot_frame_loading", ax)
    S = result.shaking_force
    _curves(axes[0, 0], result.theta, "shaking force [N]", ("S_x", S[:, 0]), ("S_y", S[:, 1]),
            ("|S|", result.shaking_force_magnitude, "k"))
    _curves(axes[1, 0], result.theta, "crank torque [N·m]", ("T", result.torque))
    _curves(axes[2, 0], result.theta, "shaking moment [N·m]", ("T_a (about A)", result.T_a),
            ("T_d (about D)", result.T_d))
    axes[2, 0].set_xlabel("crank angle θ [deg]")
    fig.suptitle(_loading_title(result))
    return laid_out(False, fig, ax, axes)


def _loading_title(result) -> str:
    """The title of a :class:`FrameLoading`'s plots: its crank speed."""
    return (f"frame loading at ω = {result.omega:.4g} rad/s "
            f"({convert_frequency(result.omega, 'rad/s', 'rpm'):.4g} rpm)")


def _curves(a, theta, ylabel: str, *curves):
    """Curves ``(label, y[, format])`` against the crank angle ``theta`` [rad] (drawn in
    degrees) on ``a``, with their legend and a grid; ``ylabel`` names the axis."""
    deg = np.degrees(theta)
    for label, y, *fmt in curves:
        a.plot(deg, y, *fmt, label=label)
    a.set_ylabel(ylabel)
    a.grid(alpha=0.3)
    a.legend(fontsize="small", loc="best")


def plot_shaking(result, fig=None, *, ax=None):
    """The patent's Figs. 5–6 for a :class:`FrameLoading`, and the loads behind them.

    Four panels: the shaking force S on the frame as a polar curve (the locus
    of its tip, S_y against S_x, one point per crank angle), |S| against the
    crank angle, the bearing forces |F_A| and |F_D|, and the driving torque
    with the shaking moments T_a, T_d.  Draws on ``fig`` (a matplotlib
    ``Figure``) when given, else on a new one; returns the figure.

    Parameters
    ----------
    result : FrameLoading
        Its shaking force, bearing forces, torque and moments are drawn.
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one for the four panels (2 × 2); a new one by default.
    ax : matplotlib.axes.Axes, optional
        Draw only the polar curve there (nothing else of its figure is touched);
        ``fig`` is then not used.

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on (``ax`` when given; else ``fig``, it must be empty, or a
        new Figure): its four panels in a 2 × 2 grid.
    """
    fig, axes = _figure(2, 2, (10, 8), fig, "plot_shaking", ax)
    deg, S = np.degrees(result.theta), result.shaking_force
    mag = result.shaking_force_magnitude
    a = axes[0, 0]
    a.plot(S[:, 0], S[:, 1], lw=1.4)
    a.plot([0], [0], "k+", ms=10)
    k = int(np.argmax(mag))
    a.plot([0, S[k, 0]], [0, S[k, 1]], "r-", lw=1,
           label=f"max |S| = {mag[k]:.4g} N at θ = {deg[k]:.1f}°")
    a.set_aspect("equal", adjustable="datalim")
    a.set(xlabel="S_x [N]", ylabel="S_y [N]",
          title="shaking force on the frame, polar curve (Fig. 5)")
    a.legend(fontsize="small", loc="best")
    a = axes[0, 1]
    a.plot(deg, mag, "k", lw=1.4)
    a.set(ylabel="|S| [N]", title="shaking force magnitude (Fig. 6)")
    _curves(axes[1, 0], result.theta, "bearing force [N]",
            ("|F_A| (crankshaft bearing)", np.hypot(*result.F_A.T)),
            ("|F_D| (rocking-shaft bearing)", np.hypot(*result.F_D.T)))
    _curves(axes[1, 1], result.theta, "moment [N·m]", ("T (driving torque)", result.torque),
            ("T_a (about A)", result.T_a), ("T_d (about D)", result.T_d))
    for a in (axes[0, 1], axes[1, 0], axes[1, 1]):
        a.set_xlabel("crank angle θ [deg]")
    for a in (axes[0, 0], axes[0, 1]):
        a.grid(alpha=0.3)
    fig.suptitle(_loading_title(result))
    return laid_out(False, fig, ax, axes)


def plot_linkage(linkage, state, paths=None, *, ax=None, fig=None):
    """The linkage drawn at ``state``, with traced point paths ``{point: (n, 2) array}``.

    On ``ax`` when given (and then returns it), else on ``fig`` or a new Figure
    (returned).

    Parameters
    ----------
    linkage : Linkage
        The linkage to draw.
    state : LinkageState
        The position drawn (:meth:`Linkage.solve` at one θ).
    paths : dict[str, ndarray], optional
        Point name → its traced path, shape (n, 2).
    ax : matplotlib.axes.Axes, optional
        Drawn on when given.
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one to draw in (without ``ax``); a new one by default.

    Returns
    -------
    matplotlib.axes.Axes or matplotlib.figure.Figure
        What it drew on: ``ax`` when given, else ``fig`` (it must be empty) or the
        new Figure.
    """
    fig, axes = _figure(1, 1, (7, 7), fig, "plot_linkage", ax)
    a = axes[0, 0]
    for xy in (paths or {}).values():
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
    unit = getattr(linkage, "units", "") or "length"
    a.set(xlabel=f"x [{unit}]", ylabel=f"y [{unit}]")
    a.get_title() or a.set_title(f"{linkage.name} at θ = {math.degrees(state.theta):.4g}° "
                                 "(first crank)")
    return laid_out(False, fig, ax, axes)
