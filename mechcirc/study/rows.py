"""A batch of a study's points into rows: a netlist's as one batch of designs, a
sley preset's one simulation each; a point that fails is a row with its error."""

import math
import warnings

import numpy as np

from .spec import SLEY_QUANTITIES, SWEEP_COLUMNS, StudySpec, omega_grid, setting

__all__ = ["run_batch"]


def run_batch(spec: StudySpec, batch: list[tuple[int, dict[str, float]]],
              curves: bool = False):
    """Rows of a batch of points (what each worker runs; errors recorded, never raised).

    With ``curves`` (a sweep), ``(rows, K)``: also K [m/(N·s)] of every point on
    the study's ω grid, shape (points, W), NaN in the rows of failed points.

    A netlist's points are one :func:`mechcirc.batch.designs` batch: the
    netlist parsed once, K on the D × W grid in one pass, the resonances from
    stacked eigenproblems; a point the batch cannot take is computed on its
    own, and a point that fails is a row with its error.  Each row is the
    same whatever the batch it is in.

    Parameters
    ----------
    spec : StudySpec
    batch : list of (int, dict[str, float])
        ``(index, values)`` of each point.
    curves : bool

    Returns
    -------
    list of dict or tuple of (list of dict, ndarray)
    """
    rows = [{"index": i, **v, "status": "ok", "error": ""} for i, v in batch]
    if spec.analysis == "simulate":
        return [_simulate_row(spec, row, v) for row, (_, v) in zip(rows, batch)]
    try:
        ds, K, failed = _design_rows(spec, rows, batch)
    except Exception as exc:  # noqa: BLE001 - a study records every failure
        if len(batch) > 1:          # find the point at fault: each on its own
            alone = [run_batch(spec, [point], curves) for point in batch]
            if not curves:
                return [r[0] for r in alone]
            return [r[0][0] for r in alone], np.concatenate([r[1] for r in alone])
        message = f"{type(exc).__name__}: {exc}".replace("\n", " ")
        rows, K, failed = [{**row, "status": "error", "error": message} for row in rows], None, {}
    for d, message in failed.items():
        rows[d] = {"index": rows[d]["index"], **batch[d][1], "status": "error",
                   "error": _failure(ds, d, message)}
    if not curves:
        return rows
    K = np.full((len(rows), omega_grid(spec).size), np.nan + 0j) if K is None else np.array(K)
    K[[r["status"] != "ok" for r in rows]] = np.nan
    return rows, K


def _design_rows(spec: StudySpec, rows: list[dict], batch: list[tuple[int, dict[str, float]]]):
    """Fill ``rows`` (a sweep's extremes, or the resonances) from one
    :func:`mechcirc.batch.designs` batch of the points; the designs, K on the ω
    grid (a sweep, else None) and the points the batch could not take
    (``{row: message}``)."""
    from ..batch import designs

    with warnings.catch_warnings(action="ignore"):
        ds = designs(spec.netlist_text, {n: [v[n] for _, v in batch] for n in spec.params},
                     source=spec.netlist_source)
        if spec.analysis != "sweep":
            res = ds.resonances(omega_max=spec.omega_max)
            for d, row in enumerate(rows):
                for kind in ("resonance", "antiresonance"):
                    ws = res.omega[d, :res.count[d]][res.kind[d, :res.count[d]] == kind]
                    for i in range(spec.n_resonances):
                        row[f"{kind}_{i + 1}"] = float(ws[i]) if i < ws.size else math.nan
            return ds, None, res.failed
        omega = omega_grid(spec)
        s = ds.sweep(omega)
        flagged = np.count_nonzero(s.flags, axis=1)
        ex = ds.extremes(omega, ds.resonances(omega_max=setting(spec, "omega")[1] * (1 + 1e-9)), s)
    # Exact extremes over the band: 0 and inf at a zero or pole of K in it, named by
    # its ω, not the grid's values; in the order of SWEEP_COLUMNS.
    found = (ex.K_min, ex.omega_at_K_min, ex.K_max, ex.omega_at_K_max, ex.Q0_max,
             ex.omega_at_Q0_max)
    for d, row in enumerate(rows):
        row.update(zip(SWEEP_COLUMNS, [*(float(x[d]) for x in found), int(flagged[d])]))
    return ds, s.K, {**ex.failed, **s.failed}


def _failure(ds, d: int, message: str) -> str:
    """The row's error: the single path's exception, named as the single path names it."""
    try:
        ds.design(d)
    except Exception as exc:  # noqa: BLE001
        return f"{type(exc).__name__}: {exc}".replace("\n", " ")
    return message.replace("\n", " ")


def _simulate_row(spec: StudySpec, row: dict, values: dict) -> dict:
    """One row of a sley study (errors caught and recorded, never raised)."""
    try:
        from ..sley import simulate

        with warnings.catch_warnings(action="ignore"):
            drive, variant, revolutions, ppr = setting(spec, "sley")
            result = simulate(drive, variant, revolutions=revolutions,
                              points_per_revolution=ppr, **values)
            for q in SLEY_QUANTITIES[drive]:
                lo, hi = result.extrema[q]
                row[f"{q}_min"], row[f"{q}_max"] = float(lo), float(hi)
    except Exception as exc:  # noqa: BLE001 - a study records every failure
        row.update(status="error", error=f"{type(exc).__name__}: {exc}".replace("\n", " "))
    return row
