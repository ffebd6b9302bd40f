"""Plots of sweep results, element forces and measurements; matplotlib is imported inside.

Each ``plot_*`` function returns the matplotlib Figure it drew on.  Every
axis carries its unit, the title names the netlist, and the file format
follows the extension given to :func:`mechcirc.cli._common.save_figure`
(PNG, SVG, PDF, ...).
"""

from __future__ import annotations


def _pyplot():
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _mark_resonances(axes, resonances, legend_ax):
    labelled = set()
    for r in resonances:
        style = "-" if r.kind == "resonance" else "--"
        label = None if r.kind in labelled else ("resonance (K = 0)" if r.kind == "resonance"
                                                  else "anti-resonance (K = ∞)")
        labelled.add(r.kind)
        for ax in axes:
            ax.axvline(r.omega_d or r.omega, color="0.5", lw=0.8, ls=style,
                       label=label if ax is legend_ax else None)
    if resonances:
        legend_ax.legend(loc="best", fontsize="small")


def _mark_peak(ax, peak) -> None:
    """The exact peak of |Q0| (a :class:`mechcirc.sweep.Peak`): a dot at the located
    maximum, or a triangle at the top of the axis at every undamped resonance (∞)."""
    if peak is None or peak.quantity != "Q0":
        return
    if peak.unbounded:
        for i, w in enumerate(peak.poles):
            ax.plot([w], [1.0], marker="^", color="C3", ls="none",
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label="|Q0| = ∞ (undamped)" if i == 0 else None)
    else:
        ax.plot([peak.omega], [peak.value], marker="o", color="C3", ls="none",
                label=f"peak {peak.value:.4g} N at {peak.omega:.6g} rad/s")
    ax.legend(loc="best", fontsize="small")


def plot_sweep(result, title: str | None = None, resonances=(), peak=None):
    """Bode-style |K| [m/(N·s)] and arg K [deg], and |Q0| [N], against ω [rad/s].

    ``resonances`` (from :func:`mechcirc.resonances.find_resonances`) are drawn
    as vertical lines: solid for K = 0, dashed for K = ∞.  Flagged points
    (on or within rounding of a pole or zero) are marked with crosses.
    ``peak`` (from :func:`mechcirc.sweep.peak`) marks the exact maximum of |Q0|,
    or ∞ at each undamped resonance.  Returns the Figure.
    """
    import numpy as np

    plt = _pyplot()
    fig, (ax_k, ax_p, ax_q) = plt.subplots(3, 1, sharex=True, figsize=(7, 8),
                                           gridspec_kw={"height_ratios": [3, 2, 3]})
    omega = result.omega
    positive = omega > 0
    with np.errstate(all="ignore"):
        absK, absQ = np.abs(result.K), np.abs(result.Q0)
        phase = np.degrees(np.angle(result.K))
    ax_k.loglog(omega[positive], absK[positive], color="C0")
    ax_k.set_ylabel("|K| [m/(N·s)]")
    ax_p.semilogx(omega[positive], phase[positive], color="C2")
    ax_p.set_ylabel("arg K [deg]")
    ax_p.set_ylim(-190, 190)
    ax_p.set_yticks([-180, -90, 0, 90, 180])
    ax_q.loglog(omega[positive], absQ[positive], color="C1")
    ax_q.set_ylabel("|Q0| [N]")
    ax_q.set_xlabel("ω [rad/s]")
    flagged = positive & (result.flags != 0) & np.isfinite(absK) & (absK > 0)
    if flagged.any():
        ax_k.loglog(omega[flagged], absK[flagged], "x", color="C3", label="flagged point")
        ax_k.legend(loc="best", fontsize="small")
    _mark_resonances((ax_k, ax_p, ax_q), resonances, ax_q)
    _mark_peak(ax_q, peak)
    for ax in (ax_k, ax_p, ax_q):
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"{result.name}: kinematic characteristic and force amplitude")
    fig.tight_layout()
    return fig


def plot_forces(rows, omega: float, name: str = "circuit", title: str | None = None):
    """Bars of |Q| [N] per element (from :func:`mechcirc.forces.element_forces`) at ``omega``.

    Bars are coloured by element kind; the y axis is logarithmic when the
    forces span more than two decades.  Returns the Figure.
    """
    import numpy as np

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(max(5.0, 0.45 * len(rows) + 2), 4))
    colours = {"mass": "C0", "spring": "C1", "damper": "C2"}
    values = np.array([r.Q_abs for r in rows], dtype=float)
    ax.bar(range(len(rows)), values, color=[colours.get(r.kind, "C7") for r in rows])
    ax.set_xticks(range(len(rows)), [r.name for r in rows], rotation=45, ha="right")
    finite = values[np.isfinite(values) & (values > 0)]
    if finite.size and finite.max() > 100 * finite.min():
        ax.set_yscale("log")
    ax.set_ylabel("|Q| [N]")
    ax.set_xlabel("element")
    for kind, colour in colours.items():
        if any(r.kind == kind for r in rows):
            ax.bar([], [], color=colour, label=kind)
    ax.legend(loc="best", fontsize="small")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.set_title(title or f"{name}: element forces at ω = {omega:.6g} rad/s "
                          f"({omega / (2 * np.pi):.4g} Hz)")
    fig.tight_layout()
    return fig


def plot_comparison(comparison, name: str = "circuit", measured: str = "measured",
                    title: str | None = None):
    """A measured mobility over the model's: |K| [m/(N·s)] and arg K [deg] against ω [rad/s]."""
    import numpy as np

    plt = _pyplot()
    fig, (ax_k, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7, 6),
                                     gridspec_kw={"height_ratios": [3, 2]})
    w = comparison.omega
    with np.errstate(all="ignore"):
        for K, label, style in ((comparison.K_model, "model", "-"),
                                (comparison.K_measured, measured, "."),):
            ax_k.loglog(w, np.abs(K), style, label=label, ms=3)
            ax_p.semilogx(w, np.degrees(np.angle(K)), style, ms=3)
    ax_k.set_ylabel("|K| [m/(N·s)]")
    ax_p.set_ylabel("arg K [deg]")
    ax_p.set_ylim(-190, 190)
    ax_p.set_yticks([-180, -90, 0, 90, 180])
    ax_p.set_xlabel("ω [rad/s]")
    ax_k.legend(loc="best", fontsize="small")
    for ax in (ax_k, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"{name}: model against {measured}")
    fig.tight_layout()
    return fig


def plot_study(result, params, column: str, name: str = "study", title: str | None = None):
    """A study's ``column`` against its parameters; returns the Figure.

    One parameter: the column against it (points joined in order of the
    parameter).  Two or more: a scatter of the first two parameters coloured
    by the column (log colours when it spans more than two decades).  Failed
    points are drawn as grey crosses.
    """
    import numpy as np

    plt = _pyplot()
    ok = [r for r in result.rows if r["status"] == "ok" and r.get(column, "") != ""]
    bad = [r for r in result.rows if r["status"] != "ok"]
    unit = {"K_abs_min": " [m/(N·s)]", "K_abs_max": " [m/(N·s)]", "Q0_abs_max": " [N]",
            "omega_at_Q0_max": " [rad/s]", "n_flagged": ""}.get(
        column, " [rad/s]" if "resonance" in column else "")
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    if len(params) == 1:
        p = params[0]
        pts = sorted((r[p], r[column]) for r in ok)
        if pts:
            x, y = np.array(pts, dtype=float).T
            ax.plot(x, y, "o-", ms=3)
            if np.all(y > 0) and y.max() > 100 * y.min():
                ax.set_yscale("log")
        for r in bad:
            ax.axvline(r[p], color="0.6", lw=0.8, ls=":")
        ax.set_xlabel(p)
        ax.set_ylabel(column + unit)
    else:
        from matplotlib.colors import LogNorm

        px, py = params[:2]
        x = np.array([r[px] for r in ok], dtype=float)
        y = np.array([r[py] for r in ok], dtype=float)
        c = np.array([r[column] for r in ok], dtype=float)
        finite = np.isfinite(c)
        norm = LogNorm() if finite.any() and np.all(c[finite] > 0) and \
            c[finite].max() > 100 * c[finite].min() else None
        sc = ax.scatter(x[finite], y[finite], c=c[finite], norm=norm, s=18, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=column + unit)
        if bad:
            ax.plot([r[px] for r in bad], [r[py] for r in bad], "x", color="0.5",
                    label="failed point")
            ax.legend(loc="best", fontsize="small")
        ax.set_xlabel(px)
        ax.set_ylabel(py)
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title(title or f"{name}: {column} over {len(result.rows)} points")
    fig.tight_layout()
    return fig
