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


def plot_sweep(result, title: str | None = None):
    """|K| [m/(N·s)] and |Q0| [N] against ω [rad/s] on log axes; returns the Figure."""
    import numpy as np

    plt = _pyplot()
    fig, (ax_k, ax_q) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    omega = result.omega
    positive = omega > 0
    ax_k.loglog(omega[positive], np.abs(result.K[positive]), color="C0")
    ax_k.set_ylabel("|K| [m/(N·s)]")
    ax_q.loglog(omega[positive], np.abs(result.Q0[positive]), color="C1")
    ax_q.set_ylabel("|Q0| [N]")
    ax_q.set_xlabel("ω [rad/s]")
    for ax in (ax_k, ax_q):
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"{result.name}: kinematic characteristic and force amplitude")
    fig.tight_layout()
    return fig
