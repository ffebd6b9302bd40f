"""Plots of a scene's motion over a revolution (matplotlib imported inside)."""

from __future__ import annotations

__all__ = ["plot_motion"]


def plot_motion(result, names=None, fig=None):
    """Accelerations (top) and elastic forces (bottom) against the crank angle.

    Parameters
    ----------
    result : SceneMotion
    names : list of str, optional
        Outputs to draw (default: every ``BODY.acceleration`` that is not
        identically zero, and every ``ELEMENT.force``).
    fig : matplotlib Figure, optional
        Drawn into (cleared); a new one by default.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import numpy as np
    from matplotlib.figure import Figure

    fig = fig or Figure(figsize=(8, 7))
    fig.clf()
    if names is None:
        names = [k for k, v in result.values.items()
                 if (k.endswith(".acceleration") and np.any(v != 0)) or k.endswith(".force")]
    unknown = [n for n in names if n not in result.values]
    if unknown:
        raise ValueError(f"no output {unknown[0]!r}; outputs: {', '.join(result.values)}")
    deg = np.degrees(result.crank_angle)
    top, bottom = fig.subplots(2, 1, sharex=True)
    for n in names:
        ax = bottom if n.endswith((".force", ".moment", ".deformation")) else top
        ax.plot(deg, result.values[n], lw=0.8, label=n)
    top.set_ylabel("angular acceleration [1/s²]")
    bottom.set_ylabel("force [N] or moment [N·m]")
    bottom.set_xlabel("crank angle [deg]")
    for ax in (top, bottom):
        if ax.lines:
            ax.legend(loc="upper right", fontsize=7)
        ax.grid(alpha=0.3)
    top.set_title(f"{result.name}: revolution {result.revolution} at Ω = {result.omega:g} rad/s",
                  fontsize=10)
    return fig
