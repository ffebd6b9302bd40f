"""The result of a transient: its arrays, their units, and how to read them.

:class:`TransientResult` holds plain arrays on the time grid (picklable) and
writes them as CSV, JSON or a ``pandas.DataFrame``; :meth:`TransientResult.plot`
delegates to :func:`mechcirc.plotting.plot_transient`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..circuit import units_of
from ..sources import name_index, quantity_frame

__all__ = ["TransientResult"]


@dataclass
class TransientResult:
    """The transient on the time grid ``time`` [s] (plain arrays; picklable).

    ``x``, ``v``: node displacements [m or rad] and velocities, shape (nt, n_nodes),
    columns in ``nodes`` order (``v`` is None when not asked for); ``force``, ``dv``: every element's force [N] and
    velocity difference v(n1) − v(n2), shape (nt, n_elements), columns in
    ``elements`` order; ``drive_force`` (velocity drive) or ``drive_velocity``
    (force drive) [nt] or None; ``drive`` the drive's value u(t) [nt] (None
    without a drive); ``error`` an estimate of the largest error of ``x``
    [same unit] (a linear run's includes the drive's interpolation error carried
    to x through the worst-case gain; a run with clearances only notes it) and
    ``notes`` what the run had to say.  ``drive_name``, ``units``
    (:func:`mechcirc.circuit.units_of` of the drive: m or rad, N or N·m, ...)
    and ``clearances`` (spring name -> (n1, n2, total clearance B)) and ``waveform``
    (the drive's :attr:`Waveform.label`) serve the labels and :meth:`plot`.  ``separations``
    lists every opening of a clearance's contact
    (:class:`~mechcirc.transient.contact.Separation`: when, at which shaft angle with a
    motion drive, for how long, the impact velocity).
    """

    time: np.ndarray
    nodes: tuple
    x: np.ndarray
    v: np.ndarray | None
    elements: tuple
    force: np.ndarray
    dv: np.ndarray
    drive_kind: str | None
    drive: np.ndarray | None
    drive_force: np.ndarray | None
    drive_velocity: np.ndarray | None
    error: float
    method: str
    notes: list
    name: str = "circuit"
    drive_name: str | None = None
    units: dict = field(default_factory=lambda: units_of(None))
    clearances: dict = field(default_factory=dict)
    separations: list = field(default_factory=list)
    waveform: str | None = None
    #: An estimate of the largest error of ``drive_force`` or ``drive_velocity`` from the
    #: steps (a linear run with a drive known exactly at every step: harmonic, step,
    #: impulse, a table on the grid), else None.
    drive_error: float | None = None
    #: The CSV's number format (:meth:`write_csv`, ``mechcirc transient -o``): 17 digits,
    #: every float64 read back as written (as the sweep's CSV; 12 lost exact runs' digits).
    CSV_FORMAT = "%.17g"

    def node(self, name: str) -> tuple[np.ndarray, np.ndarray | None]:
        """(x, v) of node ``name``."""
        i = name_index(name, self.nodes, "node")
        return self.x[:, i], (self.v[:, i] if self.v is not None else None)

    def element_force(self, name: str) -> np.ndarray:
        """Force [N] through element ``name`` (n1 → n2)."""
        return self.force[:, name_index(name, self.elements, where="" if self.elements else
                                        " in this run, which kept none (elements=True keeps them)")]

    def __repr__(self) -> str:
        """A short summary (the arrays are in the attributes, not in the repr)."""
        t = self.time
        span = f"t {t[0]:.4g}..{t[-1]:.4g} s" if len(t) else "no steps"
        with np.errstate(all="ignore"):
            xmax = float(np.nanmax(np.abs(self.x))) if self.x.size else 0.0
            qmax = float(np.nanmax(np.abs(self.force))) if self.force.size else 0.0
        return (f"<TransientResult {self.name!r}: {len(t)} samples, {span}, method "
                f"{self.method}, {len(self.nodes)} nodes (max |x| {xmax:.4g} "
                f"{self.units['x']}), {len(self.elements)} elements (max |force| "
                f"{qmax:.4g} {self.units['Q']}), "
                f"error {self.error:.2g}" + (f", {len(self.notes)} note(s)>" if self.notes
                                              else ">"))

    def to_json(self) -> dict:
        """The ``--json`` document."""
        doc = {"time": self.time,
               "nodes": {n: ({"x": self.x[:, i], "v": self.v[:, i]} if self.v is not None
                             else {"x": self.x[:, i]})
                         for i, n in enumerate(self.nodes)},
               "elements": {e: {"force": self.force[:, j], "dv": self.dv[:, j]}
                            for j, e in enumerate(self.elements)},
               "drive": ({"force": self.drive_force} if self.drive_force is not None else
                         {"velocity": self.drive_velocity} if self.drive_velocity is not None
                         else {}),
               "error": self.error, "drive_error": self.drive_error, "method": self.method,
               "notes": list(self.notes),
               "units": {"t": "s", **self.units}}
        if self.clearances:
            doc["separations"] = [dataclasses.asdict(s) for s in self.separations]
        return doc

    def columns(self) -> dict:
        """The run's columns by name, in order: ``t``, ``x(NODE)``, ``v(NODE)`` when the run
        kept velocities, ``F(ELEMENT)``, then ``F(drive)`` (a velocity drive) or ``v(drive)``
        (a force drive): what :meth:`write_csv` and ``mechcirc transient -o`` write and
        :meth:`to_dataframe` holds."""
        cols = {"t": self.time}
        for kind, names, values in (("x", self.nodes, self.x), ("v", self.nodes, self.v),
                                    ("F", self.elements, self.force)):
            if values is not None:
                cols.update({f"{kind}({n})": values[:, i] for i, n in enumerate(names)})
        if self.drive_force is not None:
            cols["F(drive)"] = self.drive_force
        elif self.drive_velocity is not None:
            cols["v(drive)"] = self.drive_velocity
        return cols

    def write_csv(self, fh) -> None:
        """Columns: t, x(node), v(node) for each node, F(element) for each element, drive."""
        cols = self.columns()
        np.savetxt(fh, np.column_stack(list(cols.values())), delimiter=",", fmt=self.CSV_FORMAT,
                   header=",".join(cols), comments="")

    def to_dataframe(self):
        """The run as a ``pandas.DataFrame``, one row per time step, in the columns of
        :meth:`write_csv`: ``t`` [s], ``x(NODE)`` [m or rad], ``v(NODE)`` [m/s or rad/s]
        when the run kept velocities, ``F(ELEMENT)`` [N or N·m], and ``F(drive)`` (a
        velocity drive) or ``v(drive)`` (a force drive); ``attrs["units"]`` maps each column
        to its unit (as :meth:`mechcirc.Sweep.to_dataframe`).  pandas is imported here only
        (an ImportError says so without it)."""
        cols = self.columns()
        unit = {"t": "s", "x": self.units["x"], "v": self.units["v"], "F": self.units["Q"]}
        return quantity_frame(cols, unit)

    def plot(self, ax=None, nodes=None, what: str = "x", *, elements=None, fig=None,
             title: str | None = None):
        """Plot this transient: :func:`mechcirc.plotting.plot_transient` (``ax=`` the
        nodes' panel only, else the panels on ``fig`` or a new Figure); returns what
        it drew on.  ``fig`` must be an *empty* Figure or SubFigure (one already
        holding Axes is refused with an InputError)."""
        from ..plotting import plot_transient

        return plot_transient(self, nodes, what, elements, title, ax=ax, fig=fig)
