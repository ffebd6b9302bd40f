"""Plots of sweep results, element forces and measurements; matplotlib is imported inside.

One convention for every plot function of mechcirc:

* a single-panel plot takes ``ax=None`` — given an Axes it draws there and
  returns that Axes (for notebooks: ``fig, ax = plt.subplots(); plot_forces(rows, 300,
  ax=ax)``); without one it makes a new ``matplotlib.figure.Figure`` and
  returns it;
* a multi-panel plot takes ``fig=None`` and returns the Figure it drew on.
  Its panels come from :func:`new_panels`: a new Figure by default, or the
  *empty* Figure or SubFigure given, which they fill (its size and layout
  engine stay the caller's).  A figure already holding Axes is refused with
  an :class:`~mechcirc.errors.InputError` rather than drawn over: pass
  ``fig=None`` or an empty subfigure of yours (``fig.subfigures()``).  Given
  ``ax=``, a multi-panel plot draws its main (first) panel there and returns
  that Axes, touching nothing else of the caller's figure (every plot function
  takes ``ax=``);
* nothing here deletes, clears or moves what the caller drew, touches
  pyplot's state or calls ``matplotlib.use``: figures are built with the
  object-oriented ``Figure``, so a notebook's backend is left alone and the
  CLI saves with ``fig.savefig``.

Every axis carries its unit, the title names the netlist, and the file format
follows the extension given to :func:`mechcirc.cli._common.save_figure`
(PNG, SVG, PDF, ...).  Objects that plot have a ``.plot()`` delegate
(:meth:`mechcirc.Sweep.plot`).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from .circuit import units_of
from .errors import InputError, MechcircError, did_you_mean
from .units import FREQUENCY_UNITS, in_unit

__all__ = ["new_panels", "one_panel", "plot_sweep", "plot_transient", "plot_forces", "plot_comparison", "plot_study", "plot_periodic",
           "plot_speed_map", "plot_mode", "plot_modes"]


def new_panels(fig, rows: int = 1, cols: int = 1, *, caller: str, figsize=(8.0, 6.0),
               layout: Literal["constrained", "compressed", "tight"] | None = None,
               ax=None, **subplots_kw):
    """The ``rows`` × ``cols`` panels of a plot, on ``fig`` or on a new Figure.

    The one place a plot function gets its Figure.  Panels are never drawn
    over the caller's: a Figure (or SubFigure) that already holds Axes or
    subfigures is refused, since adding the panels would cover them and
    making room would move or delete them.  A matplotlib user who wants the
    plot beside their own panels gives it a subfigure (``fig.subfigures()``),
    matplotlib's own way to compose multi-panel plots.

    Parameters
    ----------
    fig : matplotlib.figure.Figure or SubFigure or None
        None: a new pyplot-free Figure (any backend, never switched).
        Otherwise an empty Figure or SubFigure, which the panels fill; its
        size and layout engine are left as the caller set them.
    rows, cols : int
        The grid of panels.
    caller : str
        The plot function, named in the error.
    figsize : tuple of float
        Size [in] of a new Figure.
    layout : str, optional
        Layout engine of a new Figure (``"constrained"``, ``"tight"``).
    ax : matplotlib.axes.Axes, optional
        The caller's Axes as the main panel ``[0, 0]`` (``fig`` not used): the others
        go on a new Figure never shown, and nothing else of the caller's is touched.
    **subplots_kw
        Passed to ``Figure.subplots`` (``sharex``, ``gridspec_kw``, ...).

    Returns
    -------
    fig : matplotlib.figure.Figure or SubFigure
        The Figure drawn on.
    axes : numpy.ndarray of Axes, shape (rows, cols)

    Raises
    ------
    InputError
        ``fig`` already holds Axes or subfigures.
    """
    if fig is None or ax is not None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, layout=layout)
        if ax is not None:            # the main panel the caller's; the others never shown
            axes = fig.subplots(rows, cols, squeeze=False, **subplots_kw)
            axes[0, 0].remove()
            axes[0, 0] = ax
            return fig, axes
    elif fig.axes or fig.subfigs:
        raise InputError(
            f"{caller}: the figure given as fig= already holds {len(fig.axes)} Axes and "
            f"{len(fig.subfigs)} subfigures; the plot's {rows}×{cols} panels would cover them. "
            "Pass fig=None (a new Figure), an empty Figure, or an empty subfigure of yours "
            "(fig.subfigures()); a single panel goes on ax=")
    return fig, fig.subplots(rows, cols, squeeze=False, **subplots_kw)


def one_panel(ax, figsize):
    """The panel of a one-panel plot: the given Axes, or one on a new Figure.

    Parameters
    ----------
    ax : matplotlib.axes.Axes or None
        The caller's Axes, drawn on as it is.
    figsize : tuple of float
        Size [in] of a new Figure.

    Returns
    -------
    tuple
        ``(fig, ax, made)``: ``made`` is True for a new Figure (the plot then
        returns it, else ``ax``).
    """
    if ax is not None:
        return ax.figure, ax, False
    fig, axes = new_panels(None, caller="", figsize=figsize)
    return fig, axes[0, 0], True


def laid_out(made, fig, ax=None, axes=None):
    """A Figure made here laid out and returned; a given one (its layout the caller's) or ``ax``.

    ``axes``: the panels of a multi-panel plot whose main one is the caller's ``ax``
    (:func:`new_panels`), which then gets the bottom panel's x label and the plot's
    title where it has none of its own.
    """
    if made:
        fig.tight_layout()
        return fig
    if ax is not None and axes is not None:
        ax.get_xlabel() or ax.set_xlabel(axes[-1, 0].get_xlabel())
        ax.get_title() or ax.set_title(fig.get_suptitle())
    return fig if ax is None else ax


#: Refinement around each exact root: points at ω_r·(1 ± s·δ) for these s, with
#: δ the root's relative half-width ζ clipped to [REFINE_WIDTH[0], REFINE_WIDTH[1]].
REFINE_STEPS = (0.02, 0.1, 0.3, 1.0, 3.0)
REFINE_WIDTH = (1e-3, 0.02)
#: Labels of roots closer than this fraction of the axis width go on different rows.
LABEL_GAP = 0.08

def _refined(result, resonances):
    """(ω, K, flags, response) of ``result`` with exact points added around each root.

    The added points are evaluated by the circuit itself (:func:`mechcirc.sweep`
    with the sweep's method), so a close resonance/anti-resonance pair that the
    grid steps over is drawn through; without a circuit (or roots) the sweep as is.
    """
    force_drive = getattr(result.drive, "kind", "velocity") == "force"
    omega, K, flags = result.omega, result.K, result.flags
    R = result.v0 if force_drive else result.Q0
    circuit = getattr(result, "circuit", None)
    if circuit is None or not len(resonances) or omega.size < 2:
        return omega, K, flags, R
    lo, hi = float(np.min(omega)), float(np.max(omega))
    steps = np.concatenate([-np.array(REFINE_STEPS[::-1]), REFINE_STEPS])
    new = np.unique(np.concatenate([
        (r.omega_d or r.omega) * (1 + min(max(r.zeta, REFINE_WIDTH[0]), REFINE_WIDTH[1]) * steps)
        for r in resonances]))
    new = new[(new > lo) & (new < hi) & ~np.isin(new, omega)]
    if not new.size:
        return omega, K, flags, R
    # the circuit's own delegate
    extra = circuit.sweep(new, method=result.method, refine=getattr(result, "refine", True))
    order = np.argsort(np.concatenate([omega, new]), kind="stable")
    return tuple(np.concatenate([a, b])[order] for a, b in
                 ((omega, new), (K, extra.K), (flags, extra.flags),
                  (R, extra.v0 if force_drive else extra.Q0)))


def _label_resonances(ax, resonances, per_unit: float) -> None:
    """Each root's frequency written at the top of ``ax``, on the highest row where
    it stands at least :data:`LABEL_GAP` of the axis width from that row's last
    label, so the labels of a close pair never overlap."""
    from matplotlib.transforms import blended_transform_factory

    trans = blended_transform_factory(ax.transData, ax.transAxes)
    scale = np.log if ax.get_xscale() == "log" else (lambda v: v)
    lo, hi = (scale(v) for v in ax.get_xlim())
    last: list[float] = []                      # per row: position of its last label
    for w in sorted((r.omega_d or r.omega) / per_unit for r in resonances if r.zeta < 1):
        pos = (scale(w) - lo) / (hi - lo) if w > 0 and hi != lo else 0.0
        row = next((i for i, p in enumerate(last) if pos - p >= LABEL_GAP), len(last))
        last[row:row + 1] = [pos]
        ax.text(w, 0.96 - 0.09 * row, f"{w:.5g}", transform=trans, ha="center", va="top",
                fontsize="x-small", color="0.3",
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8})


def _mark_resonances(axes, resonances, legend_ax, per_unit: float = 1.0,
                     legend: bool = True):
    """Vertical lines at each root's ω_d, where K has its extreme (``per_unit`` rad/s per
    unit of the x axis; an overdamped root has none and is not drawn), one line per kind and
    panel (the roots' lines joined by NaN breaks, as ``axvline``
    would draw each); ``legend=False`` leaves ``legend_ax``'s legend to the caller
    (made once)."""
    from matplotlib.lines import Line2D

    for kind in dict.fromkeys(r.kind for r in resonances):     # in order of appearance
        at = [(r.omega_d or r.omega) / per_unit for r in resonances
              if r.kind == kind and r.zeta < 1]
        x = [v for w in at for v in (w, w, math.nan)]
        for ax in axes:
            ax.add_line(Line2D(
                x, [0.0, 1.0, math.nan] * len(at), transform=ax.get_xaxis_transform(),
                color="0.5", lw=0.8, ls="-" if kind == "resonance" else "--",
                label=("resonance (K = 0" if kind == "resonance" else "anti-resonance (K = ∞")
                + ", at ω_d)" if ax is legend_ax else ""))
    if resonances and legend:
        legend_ax.legend(loc="best", fontsize="small")


def _mark_peak(ax, peak, unit: str = "rad/s", force_unit: str = "N") -> None:
    """The exact peak of |Q0| (a :class:`mechcirc.Peak`): a dot at the located
    maximum, or a triangle at the top of the axis at every undamped resonance (∞)."""
    if peak is None or peak.quantity != "Q0":
        return
    if peak.unbounded:
        if len(peak.poles):             # one line of markers for all the poles
            ax.plot([in_unit(w, unit) for w in peak.poles], [1.0] * len(peak.poles),
                    marker="^", color="C3", ls="none", transform=ax.get_xaxis_transform(),
                    clip_on=False, label="|Q0| = ∞ (undamped)")
    else:
        ax.plot([in_unit(peak.omega, unit)], [peak.value], marker="o", color="C3", ls="none",
                label=f"peak {peak.value:.4g} {force_unit} at "
                      f"{in_unit(peak.omega, unit):.6g} {unit}")
    ax.legend(loc="best", fontsize="small")


def plot_sweep(result, title: str | None = None, resonances=(), peak=None, *, ax=None,
               fig=None, unit: str = "rad/s", extra=None, refine: bool = True):
    """Bode-style |K| and arg K [deg], and the drive's response, against frequency.

    The third panel is what the drive does not prescribe: |Q0| for a
    velocity drive, the velocity response |v0| = |F0·K| for a force drive
    (its title says so, with the drive's V0 or F0).  Units come from the drive
    (``result.units``: m/(N·s), N, m/s, or rad/(N·m·s), N·m, rad/s for a
    rotary drive).  ``resonances`` (from
    :meth:`mechcirc.circuit.Circuit.resonances`) are drawn as vertical lines:
    solid for K = 0, dashed for K = ∞.  Flagged points (on or within rounding
    of a pole or zero) are marked with crosses.  ``peak`` (from
    :func:`mechcirc.peak`) marks the exact maximum of |Q0|, or ∞ at each
    undamped resonance.

    Around each root passed in ``resonances`` the curves are refined: exact
    points (evaluated by the sweep's circuit with its method) are added at
    ω_r·(1 ± s·δ), s in :data:`REFINE_STEPS`, δ the root's damping ratio
    clipped to :data:`REFINE_WIDTH`, so the phase panel resolves a close
    resonance/anti-resonance pair the grid steps over.  Each root's frequency
    is written at the top of the |K| panel, the labels of roots closer than
    :data:`LABEL_GAP` of the axis width on different rows.

    Parameters
    ----------
    result : Sweep
    title : str, optional
    resonances : sequence of Resonance
    peak : Peak, optional
    ax : matplotlib Axes, optional
        Draw only |K| (with the flags and resonance lines) on this Axes and
        return it.
    fig : matplotlib Figure or SubFigure, optional
        An empty one to fill (see :func:`new_panels`); a new one by default.
    unit : {"rad/s", "Hz", "rpm"}
        Unit of the frequency axis: ω, f = ω/2π or n = 60·ω/2π.
    extra : dict, optional
        More panels below: y-axis label -> real array over the sweep's points
        (e.g. ``{"|v(B)| [m/s]": abs(result.node_velocity("B"))}``), drawn on
        the sweep's own points.
    refine : bool
        Add the exact points around the roots (default); False draws the
        sweep's points only.

    Returns
    -------
    The Axes ``ax`` when given, else ``fig`` (empty) or the new Figure (what it drew on).
    """
    w, K, flags, R = _refined(result, resonances if refine else ())
    with np.errstate(all="ignore"):     # (ω in unit, |K|, arg K [deg], |response|, flags)
        curves = in_unit(w, unit), np.abs(K), np.degrees(np.angle(K)), np.abs(R), flags
    if ax is not None:
        _draw_K(ax, result, curves, resonances, unit, mark=True)
        ax.get_title() or ax.set_title(title or f"{result.name}: kinematic characteristic K = v/Q")
        return ax
    return _bode_figure(fig, result, curves, resonances, peak, unit, dict(extra or {}), title)


def _bode_figure(fig, result, curves, resonances, peak, unit: str, extra: dict, title):
    """The panels of :func:`plot_sweep`: |K|, arg K, the response, ``extra``."""
    units = units_of(getattr(result, "drive", None))
    force_drive = getattr(result.drive, "kind", "velocity") == "force"
    omega, _, phase, absR, _ = curves
    positive = omega > 0
    fig, axes = new_panels(fig, 3 + len(extra), caller="plot_sweep", figsize=(7, 8 + 2.2 * len(extra)),
                           sharex=True, gridspec_kw={"height_ratios": [3, 2, 3] + [2] * len(extra)})
    axes = axes[:, 0]
    ax_k, ax_p, ax_q = axes[:3]
    _draw_K(ax_k, result, curves, resonances, unit)
    ax_p.semilogx(omega[positive], phase[positive], color="C2")
    ax_p.set(**_PHASE_AXIS)
    ax_q.loglog(omega[positive], absR[positive], color="C1")
    ax_q.set_ylabel(f"|v0| = |F0·K| [{units['v']}]" if force_drive else f"|Q0| [{units['Q']}]")
    own = in_unit(result.omega, unit)             # the extra panels: the sweep's own points
    for a, (label, values) in zip(axes[3:], extra.items()):
        with np.errstate(all="ignore"):
            a.loglog(own[own > 0], np.asarray(values)[own > 0], color="C4")
        a.set_ylabel(label)
    axes[-1].set_xlabel(_FREQUENCY_LABEL[unit])
    # One legend on the |Q0| panel for the roots' lines and the peak (made once).
    _mark_resonances(tuple(axes), resonances, ax_q, FREQUENCY_UNITS[unit][1],
                     legend=peak is None or peak.quantity != "Q0")
    _mark_peak(ax_q, peak, unit, units["Q"])
    for a in axes:
        a.grid(True, which="both", alpha=0.3)
    amp = result.drive.amplitude
    fig.suptitle(title or f"{result.name}: kinematic characteristic K = v/Q\nand " + (
        f"velocity response v0 = F0·K to the force drive F0 = {amp:g} {units['Q']}"
        if force_drive else f"force amplitude Q0 = V0/K, V0 = {amp:g} {units['v']}"))
    _light_log_axes(axes)
    # Fixed margins that hold every label (the panels share x: no tick labels
    # between them), so neither tight_layout nor a tight bounding box at
    # saving has to measure every tick label once more (≈ 0.3 s each).
    height = fig.bbox.height / fig.dpi      # [in]; a SubFigure's own, not its parent's
    fig.subplots_adjust(left=0.13, right=0.97, hspace=0.08, top=1 - 0.85 / height,
                        bottom=0.55 / height)
    return fig


#: The arg K panel's y axis (a sweep's and a comparison's).
_PHASE_AXIS = {"ylabel": "arg K [deg]", "ylim": (-190, 190), "yticks": [-180, -90, 0, 90, 180]}
_FREQUENCY_LABEL = {"rad/s": "ω [rad/s]", "Hz": "f [Hz]", "rpm": "n [rpm]"}


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _decade_label(x, pos=None) -> str:
    """``10⁻³`` for a power of ten, ``%g`` otherwise: plain text, not mathtext."""
    if x > 0:
        e = round(math.log10(x))
        if abs(x / 10.0 ** e - 1) < 1e-9:
            return "10" + str(e).translate(_SUPERSCRIPT)
    return f"{x:g}"


def _in_view(locator):
    """``locator`` giving only the ticks inside the view (matplotlib's log locators add
    a decade or more beyond each end, each a Tick object built, never drawn)."""
    from matplotlib.ticker import Locator

    class InView(Locator):
        def __init__(self, base):
            self.base = base

        def set_axis(self, axis):
            super().set_axis(axis)
            self.base.set_axis(axis)

        def __call__(self):
            lo, hi = sorted(self.axis.get_view_interval())
            slack = 1e-10 * (hi - lo)
            return [t for t in self.base() if lo - slack <= t <= hi + slack]

    for name in ("tick_values", "nonsingular", "view_limits"):      # the base's own
        setattr(InView, name, lambda self, v0, v1, name=name: getattr(self.base, name)(v0, v1))
    return locator if type(locator).__name__ == "InView" else InView(locator)


def _light_log_axes(axes, max_minor_decades: float = 3.0) -> None:
    """Cheaper log axes: decade labels as plain text, no minor ticks on a y axis
    spanning more than ``max_minor_decades`` decades, major ticks only inside the
    view, and the minor grid of a shared log x axis drawn as one line collection
    per panel holding one path (its lines joined by NaN breaks: transformed and
    drawn once, where a path per line is transformed on its own).

    matplotlib's default labels are mathtext (its parser is built on first use)
    and every minor tick is an object drawn with its grid line: on a sweep's
    |K| and |Q0| panels, spanning 4–10 decades, they cost more than the curves,
    and the x axis's 2…9 × 10ⁿ minor ticks, made for each panel, half the
    saving of the figure.  The minor grid lines stay where they were (same
    positions and style); only the short minor tick marks go.  Minor labels of
    an axis spanning less than a decade are left as they are.
    """
    from matplotlib.ticker import FuncFormatter, NullFormatter, NullLocator

    for a in axes:
        for axis in (a.xaxis, a.yaxis):
            if axis.get_scale() == "log":
                axis.set_major_formatter(FuncFormatter(_decade_label))
                axis.set_major_locator(_in_view(axis.get_major_locator()))
        lo, hi = a.get_ylim()
        if a.get_yscale() == "log" and lo > 0 and math.log10(hi / lo) > max_minor_decades:
            a.yaxis.set_minor_locator(NullLocator())
    lo, hi = axes[0].get_xlim()
    if axes[0].get_xscale() != "log" or not 0 < lo < hi or math.log10(hi / lo) <= 1:
        return
    from matplotlib import rcParams
    from matplotlib.axis import Ticker
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    at = [k * 10.0 ** e for e in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)))
          for k in range(2, 10) if lo <= k * 10.0 ** e <= hi]
    axes[0].xaxis.set_minor_locator(NullLocator())     # shared by the panels
    decades = list(axes[-1].xaxis.get_majorticklocs())
    for a in axes:
        grid = at
        if a is not axes[-1]:
            # A panel above the last shows no x tick labels: its own Ticker without
            # Tick objects (the limits stay shared); its decades' grid lines join the
            # grid's path and their tick marks are one line of tick markers.
            a.xaxis.major = Ticker()
            a.xaxis.set_major_locator(NullLocator())
            a.xaxis.set_major_formatter(NullFormatter())
            grid = at + decades
            direction = rcParams["xtick.direction"]
            a.add_artist(Line2D(
                decades, [0] * len(decades), ls="none", transform=a.get_xaxis_transform(),
                # matplotlib's TICKUP (2), "|" or TICKDOWN (3), as its ticks use them
                marker=2 if direction == "in" else "|" if direction == "inout" else 3,
                markersize=rcParams["xtick.major.size"], color=rcParams["xtick.color"],
                markeredgewidth=rcParams["xtick.major.width"], clip_on=False, zorder=2.01))
        a.add_collection(LineCollection(
            [[(v, y) for x in grid for v, y in ((x, 0.0), (x, 1.0), (math.nan, math.nan))]],
            transform=a.get_xaxis_transform(), colors=rcParams["grid.color"],
            linewidths=rcParams["grid.linewidth"], linestyles=rcParams["grid.linestyle"],
            alpha=0.3, zorder=1.5), autolim=False)


def _draw_K(ax, result, curves, resonances, unit: str, mark: bool = False):
    """|K| on ``ax`` with its flagged points and the roots' labels (and lines if ``mark``)."""
    omega, absK, _, _, flags = curves
    positive = omega > 0
    ax.loglog(omega[positive], absK[positive], color="C0")
    ax.set_ylabel(f"|K| [{units_of(getattr(result, 'drive', None))['K']}]")
    flagged = positive & (flags != 0) & np.isfinite(absK) & (absK > 0)
    if flagged.any():
        ax.loglog(omega[flagged], absK[flagged], "x", color="C3", label="flagged point")
        ax.legend(loc="best", fontsize="small")
    per_unit = FREQUENCY_UNITS[unit][1]
    if mark:
        _mark_resonances((ax,), resonances, ax, per_unit)
        ax.set_xlabel(_FREQUENCY_LABEL[unit])
        ax.grid(True, which="both", alpha=0.3)
    _label_resonances(ax, resonances, per_unit)


#: Most clearance (backlash) panels of a transient plot, and most nodes drawn by default.
MAX_CLEARANCE_PANELS, MAX_NODES = 4, 8


def _known(kind: str, names, known) -> list:
    """``names`` (checked against ``known``, a clear error naming them otherwise)."""
    names = list(names)
    bad = [n for n in names if n not in known]
    if bad:
        raise MechcircError(f"unknown {kind} {bad[0]!r}{did_you_mean(bad[0], known)} (the "
                            f"transient has {', '.join(known) or 'none'})")
    return names


def plot_transient(result, nodes=None, what: str = "x", elements=None, title: str | None = None,
                   *, ax=None, fig=None):
    """A transient (:class:`mechcirc.transient.TransientResult`) against time.

    Panels: the displacement x (or, ``what="v"``, velocity) of ``nodes`` (default the
    first :data:`MAX_NODES`) in the drive's units (m or rad, m/s or rad/s); the forces
    of ``elements`` (names; N or N·m) when given; and for each spring with a clearance
    (at most :data:`MAX_CLEARANCE_PANELS`) its deformation x(n1) − x(n2) with the band
    ±B/2 inside which it transmits nothing and the contact phases (the spring's force
    is not 0) shaded.  The title names the netlist and the drive.

    Parameters
    ----------
    result : TransientResult
    nodes : sequence of str, optional
    what : {"x", "v"}
    elements : sequence of str, optional
    title : str, optional
    ax : matplotlib Axes, optional
        Draw only the nodes' panel there and return it.
    fig : matplotlib Figure or SubFigure, optional
        An empty one to fill (see :func:`new_panels`); a new one by default.

    Returns
    -------
    The Axes ``ax`` when given, else ``fig`` (empty) or the new Figure (what it drew on).
    """

    if what not in ("x", "v") or (what == "v" and result.v is None):
        raise MechcircError(f"what={what!r}: expected 'x' or 'v' (v only when the transient "
                            "kept velocities)")
    names = _known("node", nodes, result.nodes) if nodes is not None \
        else list(result.nodes)[:MAX_NODES]
    forces = _known("element", elements or (), result.elements)
    wave = getattr(result, "waveform", None)        # the title: the netlist and the drive
    title = title or f"{result.name}: transient, " + (
        f"{result.drive_kind} drive {result.drive_name}" + (f", {wave}" if wave else "")
        if result.drive_name else "no drive")
    if ax is not None:
        _nodes_panel(ax, result, names, what)
        ax.set(xlabel="t [s]", title=ax.get_title() or title)
        ax.grid(True, alpha=0.3)
        return ax
    gaps = list(result.clearances.items())[:MAX_CLEARANCE_PANELS]
    n = 1 + bool(forces) + len(gaps)
    made = fig is None
    fig, axes = new_panels(fig, n, caller="plot_transient", figsize=(8, 3 + 2.2 * n), sharex=True)
    axes = axes[:, 0]
    _nodes_panel(axes[0], result, names, what)
    if forces:
        _forces_panel(axes[1], result, forces)
    for a, gap in zip(axes[1 + bool(forces):], gaps):
        _clearance_panel(a, result, *gap)
    axes[-1].set_xlabel("t [s]")
    for a in axes:
        a.grid(True, alpha=0.3)
    fig.suptitle(title)
    return laid_out(made, fig)


def _nodes_panel(a, result, names, what: str) -> None:
    """The displacement (``what="x"``) or velocity of the nodes ``names`` against time."""
    data = result.x if what == "x" else result.v
    for n in names:
        a.plot(result.time, data[:, result.nodes.index(n)], label=f"{what}({n})")
    a.set_ylabel(f"displacement x [{result.units['x']}]" if what == "x"
                 else f"velocity v [{result.units['v']}]")
    if names:
        a.legend(loc="best", fontsize="small")


def _forces_panel(a, result, forces) -> None:
    """The forces (moments) of the elements ``forces`` against time."""
    for e in forces:
        a.plot(result.time, result.force[:, result.elements.index(e)], label=f"F({e})")
    word = "moment" if result.units["Q"] == "N·m" else "force"
    a.set_ylabel(f"element {word} [{result.units['Q']}]")
    a.legend(loc="best", fontsize="small")


def _clearance_panel(a, result, name: str, gap: tuple) -> None:
    """A spring's deformation with its clearance band ±B/2 and its contact phases shaded."""
    n1, n2, B = gap
    t, u = result.time, result.units
    index = {m: i for i, m in enumerate(result.nodes)}
    e = sum(sign * result.x[:, index[m]] for sign, m in ((1, n1), (-1, n2)) if m in index)
    e = np.broadcast_to(e, t.shape)
    a.plot(t, e, color="C0", label=f"x({n1}) − x({n2})")
    for y in (B / 2, -B / 2):
        a.axhline(y, color="C3", lw=0.8, ls="--",
                  label=f"clearance ±B/2 = ±{B / 2:.4g} {u['x']}" if y > 0 else None)
    if name in result.elements:
        contact = result.force[:, result.elements.index(name)] != 0
        a.fill_between(t, 0, 1, where=contact, step="mid", color="C1", alpha=0.15,
                       transform=a.get_xaxis_transform(), label="contact")
    a.set_ylabel(f"deformation {name} [{u['x']}]")
    a.legend(loc="best", fontsize="small")


#: Colour of each element kind in force plots (bars and legend swatches alike).
KIND_COLOURS = {"mass": "C0", "spring": "C1", "damper": "C2"}


def plot_forces(rows, omega: float, name: str = "circuit", title: str | None = None, *,
                ax=None, units: dict | None = None):
    """Bars of |Q| per element (from :func:`mechcirc.forces.element_forces`) at ``omega``.

    Bars are coloured by element kind, and so are the legend's swatches; the
    y axis is logarithmic when the forces span more than two decades.
    ``units``: :func:`mechcirc.circuit.units_of` of the circuit's drive (default
    translational: N; a rotary drive's moments are in N·m).
    Returns ``ax`` when given, else the new Figure.

    Parameters
    ----------
    rows : list of ElementForce
    omega : float
        [rad/s].
    name : str
    title : str, optional
    ax : matplotlib.axes.Axes, optional
    units : dict, optional

    Returns
    -------
    matplotlib.axes.Axes or matplotlib.figure.Figure
    """
    from matplotlib.patches import Patch

    u = units or units_of(None)

    fig, ax, made = one_panel(ax, (max(5.0, 0.45 * len(rows) + 2), 4))
    values = np.array([r.Q_abs for r in rows], dtype=float)
    ax.bar(range(len(rows)), values, color=[KIND_COLOURS.get(r.kind, "C7") for r in rows])
    ax.set_xticks(range(len(rows)), [r.name for r in rows], rotation=45, ha="right")
    finite = values[np.isfinite(values) & (values > 0)]
    if finite.size and finite.max() > 100 * finite.min():
        ax.set_yscale("log")
    ax.set(ylabel=f"|Q| [{u['Q']}]", xlabel="element")
    handles = [Patch(facecolor=colour, label=kind) for kind, colour in KIND_COLOURS.items()
               if any(r.kind == kind for r in rows)]
    ax.legend(handles=ax.get_legend_handles_labels()[0] + handles, loc="best", fontsize="small")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.get_title() or ax.set_title(title or f"{name}: element forces at ω = {omega:.6g} rad/s "
                                   f"({omega / (2 * np.pi):.4g} Hz)")
    return laid_out(made, fig, ax)


def plot_comparison(comparison, name: str = "circuit", measured: str = "measured",
                    title: str | None = None, *, ax=None, fig=None, units: dict | None = None):
    """A measured mobility over the model's: |K| and arg K [deg] against ω [rad/s].

    Two panels, on ``fig`` when given (else a new Figure); returns the Figure.
    ``units``: :func:`mechcirc.circuit.units_of` of the model's drive (default
    translational: |K| in m/(N·s); rotary: rad/(N·m·s)).

    Parameters
    ----------
    comparison : Comparison
        From :func:`mechcirc.interop.skrf.compare`.
    name, measured : str
        Legend labels.
    title : str, optional
    ax : matplotlib.axes.Axes, optional
        Draw only the |K| panel there (nothing else of its figure is touched); ``fig``
        is then not used.
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one to fill (see :func:`new_panels`); a new one by default.
    units : dict, optional

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on: ``ax`` when given, else ``fig`` (it must be empty) or the new Figure.
    """
    u = units or units_of(None)
    made = fig is None and ax is None
    fig, ((ax_k,), (ax_p,)) = new_panels(fig, 2, caller="plot_comparison", figsize=(7, 6), sharex=True,
                                         ax=ax, gridspec_kw={"height_ratios": [3, 2]})
    w = comparison.omega
    with np.errstate(all="ignore"):
        for K, label, style in ((comparison.K_model, "model", "-"),
                                (comparison.K_measured, measured, "."),):
            ax_k.loglog(w, np.abs(K), style, label=label, ms=3)
            ax_p.semilogx(w, np.degrees(np.angle(K)), style, ms=3)
    ax_k.set_ylabel(f"|K| [{u['K']}]")
    ax_p.set(**_PHASE_AXIS, xlabel="ω [rad/s]")
    ax_k.legend(loc="best", fontsize="small")
    for panel in (ax_k, ax_p):
        panel.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"{name}: model against {measured}")
    return laid_out(made, fig, ax, np.array([[ax_k], [ax_p]]))


def plot_study(result, params, column: str, name: str = "study", title: str | None = None, *,
               ax=None, units=None):
    """A study's ``column`` against its parameters; returns ``ax`` when given, else the Figure.

    One parameter: the column against it (points joined in order of the
    parameter).  Two or more: a scatter of the first two parameters coloured
    by the column (log colours when it spans more than two decades).  Failed
    points are drawn as grey crosses.  ``units`` maps column and parameter
    names to their units, as the study gives them
    (:func:`mechcirc.study.column_units` of its spec); labels go without a
    unit where it has none (a count, or no ``units``).

    Parameters
    ----------
    result : StudyResult
    params : sequence of str
        The parameter columns.
    column : str
    name : str
    title : str, optional
    ax : matplotlib.axes.Axes, optional
    units : dict[str, str], optional

    Returns
    -------
    matplotlib.axes.Axes or matplotlib.figure.Figure
    """
    ok = [r for r in result.rows if r["status"] == "ok" and r.get(column, "") != ""]
    bad = [r for r in result.rows if r["status"] != "ok"]
    fig, ax, made = one_panel(ax, (6.5, 4.5))
    if len(params) == 1:
        _study_line(ax, ok, bad, params[0], column, units)
    else:
        _study_scatter(fig, ax, ok, bad, params[:2], column, units)
    ax.grid(True, which="both", alpha=0.3)
    ax.get_title() or ax.set_title(title or f"{name}: {column} over {len(result.rows)} points")
    return laid_out(made, fig, ax)


def _unit_label(key: str, units) -> str:
    """``key [unit]`` from ``units``, or ``key`` alone where it has none (or unit "1")."""
    u = (units or {}).get(key)
    return f"{key} [{u}]" if u and u != "1" else key


def _study_line(ax, ok, bad, p, column, units) -> None:
    """:func:`plot_study` of one parameter ``p``: the column against it, in its order."""
    pts = sorted((r[p], r[column]) for r in ok)
    if pts:
        x, y = np.array(pts, dtype=float).T
        ax.plot(x, y, "o-", ms=3)
        if np.all(y > 0) and y.max() > 100 * y.min():
            ax.set_yscale("log")
    for r in bad:
        ax.axvline(r[p], color="0.6", lw=0.8, ls=":")
    ax.set(xlabel=_unit_label(p, units), ylabel=_unit_label(column, units))


def _study_scatter(fig, ax, ok, bad, params, column, units) -> None:
    """:func:`plot_study` of two parameters: a scatter coloured by the column (log colours
    when it spans more than two decades), the failed points as grey crosses."""
    from matplotlib.colors import LogNorm

    px, py = params
    x, y, c = (np.array([r[key] for r in ok], dtype=float) for key in (px, py, column))
    finite = np.isfinite(c)
    norm = LogNorm() if finite.any() and np.all(c[finite] > 0) and \
        c[finite].max() > 100 * c[finite].min() else None
    sc = ax.scatter(x[finite], y[finite], c=c[finite], norm=norm, s=18, cmap="viridis")
    fig.colorbar(sc, ax=ax, label=_unit_label(column, units))
    if bad:
        ax.plot([r[px] for r in bad], [r[py] for r in bad], "x", color="0.5",
                label="failed point")
        ax.legend(loc="best", fontsize="small")
    ax.set(xlabel=_unit_label(px, units), ylabel=_unit_label(py, units))


def plot_periodic(result, title: str | None = None, *, ax=None, fig=None):
    """Q(θ) [N] over the crank angle beside its spectrum |Q_k| [N] at ω = kΩ, with
    |K(kΩ)| [m/(N·s)] and the resonances (a :class:`mechcirc.periodic.PeriodicResult`;
    labelled in ``result.units``: N·m and rad/(N·m·s) for a rotary drive).

    Two panels; harmonics near a resonance are drawn in red.

    Parameters
    ----------
    result : PeriodicResult
    title : str, optional
    ax : matplotlib Axes, optional
        Draw only the main panel, Q(θ) and the element forces, there (nothing else
        of its figure is touched).
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one to fill (see :func:`new_panels`); a new one by default.

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on: ``ax``, else ``fig`` (it must be empty) or the new Figure.
    """
    u = result.units
    word = "moment" if u["Q"] == "N·m" else "force"
    made = fig is None and ax is None
    fig, axes = new_panels(fig, 1, 2, caller="plot_periodic", figsize=(11, 4.2), ax=ax,
                           gridspec_kw={"width_ratios": [3, 2]})
    (ax_q, ax_s), = axes
    ax_q.plot(result.angle_deg, result.Q, color="C0", label="Q(θ), drive")
    for name, f in result.forces.items():
        ax_q.plot(result.angle_deg, f, lw=0.9, label=f"{name}")
    if result.unbounded:
        ax_q.text(0.5, 0.5, "unbounded: harmonic on an undamped resonance",
                  transform=ax_q.transAxes, ha="center", color="C3")
    ax_q.set(xlabel="crank angle θ [deg]", ylabel=f"{word} [{u['Q']}]", xlim=(0, 360))
    ax_q.grid(True, alpha=0.3)
    ax_q.legend(loc="best", fontsize="small")
    with np.errstate(all="ignore"):
        amp, absK = np.abs(result.amplitude), np.abs(result.K)
    top = float(np.max(amp[np.isfinite(amp)], initial=0.0))
    floor = top * 1e-6 if top > 0 else 1.0
    ok = np.isfinite(amp) & (amp >= floor)           # the spectrum down to 1e-6 of its top
    colours = np.where(result.near, "C3", "C0")
    ax_s.vlines(result.omega[ok], floor, amp[ok], colors=colours[ok], lw=1.2)
    ax_s.set(yscale="log", ylim=(floor, 2 * top if top > 0 else 10.0), xscale="log",
             xlabel="ω = kΩ [rad/s]", ylabel=f"|Q_k| [{u['Q']}]")
    ax_k = ax_s.twinx()
    good = np.isfinite(absK) & (absK > 0)
    ax_k.loglog(result.omega[good], absK[good], color="0.4", lw=0.9, label="|K(kΩ)|")
    ax_k.set_ylabel(f"|K| [{u['K']}]")
    for i, (wn, _) in enumerate(result.resonances):
        ax_s.axvline(wn, color="C3", lw=0.8, ls="--",
                     label="resonance (K = 0)" if i == 0 else None)
    if result.resonances:
        ax_s.legend(loc="lower left", fontsize="small")
    ax_s.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"{result.name}: drive {word} over one revolution at "
                          f"{result.rpm:g} rpm ({result.harmonics} harmonics, error "
                          f"{result.error:.1g})")
    return laid_out(made, fig, ax, axes)


def plot_speed_map(result, title: str | None = None, *, ax=None, min_weight: float = 1e-3):
    """The peak drive force over the cycle [N] against machine speed [rpm] (a
    :class:`mechcirc.periodic.SpeedMap`), with a line at each speed where a harmonic
    meets a resonance (k·Ω = ωₙ) whose share of the drive velocity is at least
    ``min_weight``, labelled by k (in ``result.units``: N·m for a rotary drive).
    Returns ``ax`` when given, else the Figure.

    Parameters
    ----------
    result : SpeedMap
    title : str, optional
    ax : matplotlib.axes.Axes, optional
    min_weight : float

    Returns
    -------
    matplotlib.axes.Axes or matplotlib.figure.Figure
    """
    u = result.units
    word = "moment" if u["Q"] == "N·m" else "force"
    fig, ax, made = one_panel(ax, (8, 4.5))
    peak = np.where(np.isfinite(result.peak), result.peak, np.nan)
    ax.plot(result.rpm, peak, color="C0", label="max |Q(θ)|, drive")
    for name, p in result.element_peaks.items():
        ax.plot(result.rpm, np.where(np.isfinite(p), p, np.nan), lw=0.9, ls="--",
                label=f"max |force| {name}")
    inf = ~np.isfinite(result.peak)
    if inf.any():
        ax.plot(result.rpm[inf], np.ones(int(inf.sum())), "^", color="C3",
                transform=ax.get_xaxis_transform(), clip_on=False, label="unbounded")
    for rpm, k, _, _, weight in result.crossings:
        if weight >= min_weight:
            ax.axvline(rpm, color="C3", lw=0.7, alpha=0.6)
            ax.text(rpm, 1.0, f"{k}", transform=ax.get_xaxis_transform(), ha="center",
                    va="bottom", fontsize="x-small", color="C3")
    if np.nanmax(peak, initial=0) > 100 * np.nanmin(peak, initial=np.inf):
        ax.set_yscale("log")
    ax.set(xlabel="machine speed [rpm]", ylabel=f"peak {word} over the cycle [{u['Q']}]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    ax.get_title() or ax.set_title(
        title or f"{result.name}: peak drive {word} vs speed (red: k·Ω = ωₙ)", pad=14)
    return laid_out(made, fig, ax)


def plot_mode(mode, name: str = "circuit", title: str | None = None, *, ax=None,
              unit: str = "rad/s"):
    """A mode shape (a :class:`mechcirc.modes.Mode`): each node's velocity along the circuit.

    The nodes in the netlist's order on x; the real part of the normalised
    velocity (the largest is 1) joined by a line, and for a damped mode its
    modulus as a dashed envelope.  Returns ``ax`` when given, else the new Figure.

    Parameters
    ----------
    mode : Mode
    name : str
    title : str, optional
    ax : matplotlib.axes.Axes, optional
    unit : {"rad/s", "Hz", "rpm"}
        The frequency in the title: ω [rad/s] with f [Hz] (default), f [Hz] or n [rpm].

    Returns
    -------
    matplotlib.axes.Axes or matplotlib.figure.Figure
    """
    fig, ax, made = one_panel(ax, (max(5.0, 0.45 * len(mode.shape) + 2), 3.5))
    r = mode.resonance
    at = (f"ω = {r.omega:.6g} rad/s ({r.f_hz:.4g} Hz)" if unit == "rad/s" else
          f"{'f' if unit == 'Hz' else 'n'} = {in_unit(r.omega, unit):.6g} {unit}")
    label = f"{r.kind} {at}" + (f", ζ = {r.zeta:.3g}" if r.zeta else "")
    ax.get_title() or ax.set_title(title or f"{name}: {label}")
    if not mode.shape:           # an overdamped root: its note, on an empty panel
        import textwrap

        ax.text(0.5, 0.5, textwrap.fill(mode.note, 60), ha="center", va="center",
                transform=ax.transAxes)
        ax.set(xticks=[], yticks=[])
        return fig if made else ax
    v = np.array(list(mode.shape.values()), dtype=complex)
    x = np.arange(v.size)
    ax.axhline(0, color="0.5", lw=0.8)
    ax.plot(x, v.real, "o-", color="C0", ms=4, label="Re v")
    if np.any(np.abs(v.imag) > 1e-9):
        ax.plot(x, np.abs(v), "--", color="C1", lw=1, label="|v|")
        ax.legend(loc="best", fontsize="small")
    ax.set_xticks(x, list(mode.shape), rotation=45 if v.size > 8 else 0, ha="right"
                  if v.size > 8 else "center")
    ax.set(ylim=(-1.1, 1.1), xlabel="node", ylabel="velocity / largest [1]")
    ax.grid(True, alpha=0.3)
    return laid_out(made, fig, ax)


def plot_modes(found, name: str = "circuit", *, ax=None, fig=None, unit: str = "rad/s"):
    """One panel per mode of ``found`` (from :func:`mechcirc.modes.modes`) by
    :func:`plot_mode`, stacked, on ``fig`` when given (else a new Figure); returns the Figure.

    Parameters
    ----------
    found : list of Mode
    name : str
    ax : matplotlib.axes.Axes, optional
        Draw only the first mode that has a shape there (the lowest that vibrates: an
        overdamped root has none; nothing else of its figure is touched); ``fig`` is then
        not used.
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty one to fill (see :func:`new_panels`); a new one by default.
    unit : {"rad/s", "Hz", "rpm"}
        The frequency unit of the panels' titles (:func:`plot_mode`).

    Returns
    -------
    matplotlib Axes, matplotlib.figure.Figure or matplotlib.figure.SubFigure
        What it drew on: ``ax`` when given, else ``fig`` (it must be empty) or the new Figure.
    """
    made = fig is None and ax is None
    found = found if ax is None else [m for m in found if m.shape][:1] or found[:1]
    fig, axes = new_panels(fig, max(len(found), 1), caller="plot_modes", ax=ax, figsize=(
        max(6.0, 0.45 * max((len(m.shape) for m in found), default=0) + 2), 2.6 * max(len(found), 1)))
    for mode, panel in zip(found, axes[:, 0]):
        plot_mode(mode, name, ax=panel, unit=unit)
    return laid_out(made, fig, ax, axes)
