"""Plots of a scene: its motion over a revolution, a mode drawn on the linkage
(matplotlib imported inside)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError, MechcircError, did_you_mean

__all__ = ["plot_mode", "plot_motion"]


def plot_motion(result, names=None, fig=None, *, ax=None):
    """Accelerations (top) and elastic forces (bottom) against the crank angle.

    Parameters
    ----------
    result : SceneMotion
        A simulated scene (:func:`mechcirc.scene.simulate_scene`).
    names : list of str, optional
        Outputs to draw (default: every ``BODY.acceleration`` that is not
        identically zero, and every ``ELEMENT.force``).
    fig : matplotlib Figure or SubFigure, optional
        An empty figure to draw the panels in (:func:`mechcirc.plotting.new_panels`);
        by default a new one.
    ax : matplotlib.axes.Axes, optional
        Draw only the accelerations there (nothing else of its figure is touched);
        ``fig`` is then not used.

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        ``ax`` when given, else ``fig`` (it must be empty) or the new Figure:
        accelerations above, forces and moments below, against the crank angle.
    """
    from ..plotting import laid_out, new_panels

    if names is None:
        names = [k for k, v in result.values.items()
                 if (k.endswith(".acceleration") and np.any(v != 0)) or k.endswith(".force")]
    unknown = [n for n in names if n not in result.values]
    if unknown:
        raise InputError(f"no output {unknown[0]!r}{did_you_mean(unknown[0], result.values)} "
                         f"(outputs: {', '.join(result.values)})")
    deg = np.degrees(result.crank_angle)
    fig, axes = new_panels(fig, 2, caller="plot_motion", figsize=(8, 7), sharex=True, ax=ax)
    (top,), (bottom,) = axes
    for n in names:
        panel = bottom if n.endswith((".force", ".moment", ".deformation")) else top
        panel.plot(deg, result.values[n], lw=0.8, label=n)
    top.set_ylabel("angular acceleration [rad/s²]")
    bottom.set_ylabel("force [N] or moment [N·m]")
    bottom.set_xlabel("crank angle [deg]")
    for panel in (top, bottom):
        if panel.lines:
            panel.legend(loc="upper right", fontsize=7)
        panel.grid(alpha=0.3)
    top.set_title(f"{result.name}: revolution {result.revolution} at Ω = {result.omega:g} rad/s",
                  fontsize=10)
    return laid_out(False, fig, ax, axes)


def plot_mode(scene, theta: float, n: int = 1, *, kind: str = "resonance", ax=None,
              exaggeration: float = 0.1):
    """Mode ``n`` of the scene's circuit at crank rotation ``theta`` drawn on its linkage.

    The circuit (:func:`~mechcirc.scene.build`) has one node a rigid part,
    whose velocity ξ is the part's motion in drive units; in the mode
    (:func:`mechcirc.modes.modes`, largest ξ real 1) each point P of a part
    moves with Re(ξ)·(dP/dθ)/r₀, dP/dθ its rigid velocity per unit crank
    speed and r₀ the drive's (:attr:`SceneCircuit.drive_ratio`); ground points
    stay.  Those displacements, scaled so that the largest is
    ``exaggeration`` × the linkage's size, are drawn over the rigid linkage
    (grey); elastic links dashed, as they deform.

    Parameters
    ----------
    scene : Scene
        The scene to draw.
    theta : float
        Crank rotation from the pose [rad].
    n : int
        Which mode, 1 = the lowest of ``kind`` with a shape.
    kind : {"resonance", "antiresonance"}
        Drive held (K = 0) or released (K = ∞).
    ax : matplotlib Axes, optional
        Drawn on; a new Figure's by default.
    exaggeration : float
        Largest drawn displacement as a fraction of the linkage's size.

    Returns
    -------
    matplotlib.axes.Axes or matplotlib.figure.Figure
        What it drew on: ``ax`` when given, else the new Figure (the
        convention of :mod:`mechcirc.plotting`).  Each line's gid is
        ``"rigid:LINK"`` or ``"mode:LINK"``.

    Raises
    ------
    MechcircError
        No such mode (the message says how many there are), or it is
        overdamped (no shape).
    """
    mode, state, raw = _mode_displacements(scene, theta, n, kind)
    lk = scene.linkage
    big = max(float(np.hypot(*d)) for d in raw.values())
    k = exaggeration * lk.length_scale() / big if big > 0 else 0.0
    from ..plotting import one_panel

    fig, ax, made = one_panel(ax, (7, 6))
    _draw_displaced(ax, scene, state, {p: k * np.asarray(d) for p, d in raw.items()})
    r = mode.resonance
    ax.get_title() or ax.set_title(f"{kind} {n}: ωn = {r.omega:.6g} rad/s, ζ = {r.zeta:.3g}, at "
                                   f"θ = {math.degrees(theta):.6g}° (largest displacement "
                                   f"drawn {exaggeration:.0%} of the linkage)", fontsize=9)
    ax.set(aspect="equal", xlabel=f"x [{lk.units}]", ylabel=f"y [{lk.units}]")
    return fig if made else ax


def _draw_displaced(ax, scene, state, moves):
    """The linkage in ``state`` (grey) and its points displaced by ``moves`` (point →
    displacement [linkage units]), elastic links dashed; the ground points as triangles."""
    lk, elastic = scene.linkage, {e.link for e in scene.elastic}
    for link, pts in lk.links.items():
        ring = list(pts) + ([pts[0]] if len(pts) > 2 else [])
        rigid = np.array([state.points[p] for p in ring])
        moved = rigid + np.array([moves[p] for p in ring])
        ls = "--" if link in elastic else "-"
        ax.plot(*rigid.T, color="0.7", lw=1.5, ls=ls, gid=f"rigid:{link}")
        ax.plot(*moved.T, "o" + ls, color="C0" if link not in elastic else "C3", ms=3,
                lw=1.5, gid=f"mode:{link}")
    g = np.array([state.points[p] for p in lk.ground])
    ax.plot(*g.T, "k^", ms=7, gid="ground")


def _mode_displacements(scene, theta: float, n: int, kind: str):
    """Mode ``n`` of ``kind`` at ``theta``, the linkage's state there, and each point's
    displacement in the mode [linkage units] (see :func:`plot_mode`)."""
    from ..modes import modes
    from .model import build

    if kind not in ("resonance", "antiresonance"):
        raise ValueError(f"kind must be 'resonance' or 'antiresonance', got {kind!r}")
    model = build(scene, theta)
    found = [m for m in modes(model.circuit) if m.resonance.kind == kind]
    if not (isinstance(n, int) and 1 <= n <= len(found)):
        raise MechcircError(f"{scene.source}: no {kind} {n} at θ = {math.degrees(theta):.6g}°: "
                            f"the circuit has {len(found)} (ask 1 to {len(found)})")
    mode = found[n - 1]
    if not mode.shape:
        raise MechcircError(f"{scene.source}: {kind} {n} has no shape: {mode.note}")
    lk = scene.linkage
    state = lk.solve(float(theta))
    nodes, raw = list(model.parts), {}
    for p in state.points:
        part = scene.part_of_point(p)
        xi = 0.0 if part is None else mode.shape.get(nodes[part], 0.0).real
        raw[p] = xi * np.asarray(state.velocities[p], float) * scene.length_scale / (
            lk.cranks[0].omega * model.drive_ratio)
    return mode, state, raw
