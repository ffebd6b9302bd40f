"""Plots of sweep results; matplotlib is imported inside each function.

Each ``plot_*`` function returns the matplotlib Figure it drew on.
"""

from __future__ import annotations


def _pyplot():
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_sweep(result, title: str | None = None, resonances=()):
    """|K| [m/(N·s)] and |Q0| [N] against ω [rad/s] on log axes; returns the Figure.

    ``resonances`` (from :func:`mechcirc.resonances.find_resonances`) are drawn
    as vertical lines: solid for K = 0, dashed for K = ∞.  Flagged points
    (on or within rounding of a pole or zero) are marked with crosses.
    """
    import numpy as np

    plt = _pyplot()
    fig, (ax_k, ax_q) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    omega = result.omega
    positive = omega > 0
    with np.errstate(all="ignore"):
        absK, absQ = np.abs(result.K), np.abs(result.Q0)
    ax_k.loglog(omega[positive], absK[positive], color="C0")
    ax_k.set_ylabel("|K| [m/(N·s)]")
    ax_q.loglog(omega[positive], absQ[positive], color="C1")
    ax_q.set_ylabel("|Q0| [N]")
    ax_q.set_xlabel("ω [rad/s]")
    flagged = positive & (result.flags != 0) & np.isfinite(absK) & (absK > 0)
    if flagged.any():
        ax_k.loglog(omega[flagged], absK[flagged], "x", color="C3", label="flagged point")
        ax_k.legend(loc="best", fontsize="small")
    labelled = set()
    for r in resonances:
        style = "-" if r.kind == "resonance" else "--"
        label = None if r.kind in labelled else ("resonance (K = 0)" if r.kind == "resonance"
                                                  else "anti-resonance (K = ∞)")
        labelled.add(r.kind)
        for ax in (ax_k, ax_q):
            ax.axvline(r.omega_d or r.omega, color="0.5", lw=0.8, ls=style,
                       label=label if ax is ax_q else None)
    if resonances:
        ax_q.legend(loc="best", fontsize="small")
    for ax in (ax_k, ax_q):
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"{result.name}: kinematic characteristic and force amplitude")
    fig.tight_layout()
    return fig
