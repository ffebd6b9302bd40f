"""Sweeps as CSV text: one row per frequency, full precision, flags last."""

from __future__ import annotations

import numpy as np

from .progress import Progress
from .units import FREQUENCY_UNITS, in_unit

__all__ = ["write_sweep_csv"]


def write_sweep_csv(result, path, *, unit: str = "rad/s", extra: dict | None = None) -> None:
    """Write ``omega,K_re,K_im,Q0_re,Q0_im[,v0_re,v0_im][,extra...],flag`` rows to ``path``.

    The ``v0`` columns appear for a force drive.  ``unit`` (``"rad/s"``,
    ``"Hz"`` or ``"rpm"``) gives the first column as ``omega`` [rad/s],
    ``f_Hz`` = ω/2π or ``n_rpm`` = 60·ω/2π.  ``extra`` maps further column
    names to real arrays (e.g. a node's velocity amplitude), written before
    ``flag``.  ``flag`` is 0 for a regular point, 1 on a pole or zero of K, 2
    within rounding of one.  ``path`` is written in place: for a file that
    appears whole or not at all, pass a temporary path from
    :func:`mechcirc.outputs.atomic_path` or :class:`mechcirc.outputs.OutputSet`
    (as ``mechcirc sweep -o`` does).

    Parameters
    ----------
    result : Sweep
    path : str or PathLike
    unit : {"rad/s", "Hz", "rpm"}
    extra : dict[str, ndarray], optional
    """
    name = FREQUENCY_UNITS[unit][0]
    columns = [result.omega, result.K.real, result.K.imag, result.Q0.real,
               result.Q0.imag]
    header = ("omega" if unit == "rad/s" else f"{name}_{unit.replace('/', '_')}") \
        + ",K_re,K_im,Q0_re,Q0_im"
    if result.drive.kind == "force":
        columns += [result.v0.real, result.v0.imag]
        header += ",v0_re,v0_im"
    for key, values in (extra or {}).items():
        columns.append(np.asarray(values, dtype=float))
        header += f",{key}"
    columns.append(result.flags)
    n = len(result.omega)
    # Formatting 17 digits is the slow part: in blocks, so that a terminal shows
    # progress on long sweeps, and stacking the columns one block at a time keeps
    # memory bounded (10^7 points would otherwise need a 640 MB table).  Each
    # block is one string: the rows as np.savetxt writes them (the same format,
    # on the same float64 values) at about half its cost.
    block = 100_000
    row = ",".join(["%.17g"] * (len(columns) - 1) + ["%d"]) + "\n"
    with open(path, "w", newline="") as fh, Progress(n, "CSV") as bar:
        fh.write(header + ",flag\n")
        for start in range(0, n, block):
            table = np.column_stack([c[start:start + block] for c in columns])
            if unit != "rad/s":         # per block: no second array of n frequencies
                table[:, 0] = in_unit(table[:, 0], unit)
            fh.write(format_rows(table, row))
            bar.update(len(table))


def format_rows(table, row: str) -> str:
    """The rows of ``table`` (2-D) as one string, each ``row % values`` (np.savetxt's output
    for that format, at about half its cost).

    Parameters
    ----------
    table : ndarray
        The block of rows.
    row : str
        A printf-style format of one row, newline included.

    Returns
    -------
    str
    """
    return "".join([row % tuple(r) for r in table.tolist()])
