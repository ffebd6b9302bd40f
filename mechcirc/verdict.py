"""Verdicts of the cross-checks (netlist, scene, sley): one logic for all three.

Each comparison of the two domains is a row (a dict) that :func:`judge` gives
a ``verdict`` — ``agrees`` (difference within the stated tolerance),
``disagrees`` (beyond it) or ``cannot be measured`` (and ``why``) — and
:func:`summarise` sums up (exit status 3 when one disagrees).
"""

from __future__ import annotations

import math

from .sources import summary_repr

__all__ = ["AGREES", "DISAGREES", "UNMEASURED", "judge", "summarise", "summary_line",
           "verdict_text", "checked_repr"]

AGREES, DISAGREES, UNMEASURED = "agrees", "disagrees", "cannot be measured"


def judge(row: dict, error: float | None, tol: float, why: str | None = None) -> dict:
    """Add ``verdict``, ``tol`` and ``why`` to one comparison ``row`` (returned).

    ``error`` is the relative difference of the two domains (∞ disagrees);
    ``why`` (or a missing / NaN ``error``) makes the line ``cannot be measured``.

    Parameters
    ----------
    row : dict
        One comparison (a dict of the row's columns); it gains the three keys.
    error : float or None
        Relative difference of the two domains; None or NaN: not measured.
    tol : float
        Largest relative difference that agrees.
    why : str, optional
        Why the difference cannot be measured; None when it can.

    Returns
    -------
    dict
    """
    if why is None and (error is None or math.isnan(error)):
        why = "no difference could be formed"
    if why is not None or error is None:      # (error None always has a why here)
        row.update(verdict=UNMEASURED, tol=tol, why=why)
    else:
        row.update(verdict=AGREES if error <= tol else DISAGREES, tol=tol, why="")
    return row


def summarise(rows) -> dict:
    """Overall verdict of judged rows: ``{"verdict", "agree", "disagree", "unmeasured", "exit"}``.

    ``disagrees`` (exit status 3) if any line disagrees; otherwise ``agrees``
    (exit 0) — with the number of lines that could not be measured said, and
    ``cannot be measured`` when none could.

    Parameters
    ----------
    rows : iterable of dict
        Rows with a ``verdict`` key (as :func:`judge` leaves them).

    Returns
    -------
    dict
    """
    rows = list(rows)
    n = {v: sum(r["verdict"] == v for r in rows) for v in (AGREES, DISAGREES, UNMEASURED)}
    verdict = DISAGREES if n[DISAGREES] else AGREES if n[AGREES] else UNMEASURED
    return {"verdict": verdict, "agree": n[AGREES], "disagree": n[DISAGREES],
            "unmeasured": n[UNMEASURED], "exit": 3 if n[DISAGREES] else 0}


def verdict_text(row: dict) -> str:
    """``agrees (≤ tol)`` / ``DISAGREES (> tol)`` / ``cannot be measured: why`` for one row.

    Parameters
    ----------
    row : dict
        One row with ``verdict``, ``tol`` and ``why`` (as :func:`judge` leaves it).

    Returns
    -------
    str
    """
    if row["verdict"] == UNMEASURED:
        return f"cannot be measured: {row['why']}"
    word, sign = ("agrees", "≤") if row["verdict"] == AGREES else ("DISAGREES", ">")
    return f"{word} ({sign} tol {row['tol']:.0e})" + (f": {row['why']}" if row["why"] else "")


def summary_line(s: dict) -> str:
    """The last line of every cross-check's printout.

    Parameters
    ----------
    s : dict
        From :func:`summarise`.

    Returns
    -------
    str
    """
    total = s["agree"] + s["disagree"] + s["unmeasured"]
    word = {AGREES: "agrees", DISAGREES: "DISAGREES", UNMEASURED: "cannot be measured"}
    return (f"verdict: {word[s['verdict']]} — {s['agree']} of {total} checks agree, "
            f"{s['disagree']} disagree beyond their tolerance, {s['unmeasured']} cannot be "
            "measured")


def checked_repr(result) -> str:
    """The repr of a cross-check's result: its :func:`summary_line` (the verdict and the
    counts), then its fields as :func:`mechcirc.sources.summary_repr`.

    Parameters
    ----------
    result : dataclass instance
        A cross-check's result with a ``verdict`` (:func:`summarise`).

    Returns
    -------
    str
    """
    return f"{summary_line(result.verdict)}\n{summary_repr(result)}"
