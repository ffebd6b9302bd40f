"""What a sampled time record says about the circuit: its modes, its forced amplitude,
and their match to the frequency domain's resonances.

One logic for the three cross-checks (netlist, scene, sley), which each produce
records their own way:

* :func:`poles` -- the damped exponentials y_k ≈ Σ c_i exp(s_i k Δt) of a record of
  one or several channels, by the matrix pencil (Hua & Sarkar 1990) of its block
  Hankel matrix: the record's delays span the modes' subspace, whose shift gives
  exp(s_i Δt).  One signal (a netlist's drive output): n/3 delays, the order set
  by the singular values; a whole state (a scene's kick): a few delays and the
  order known.  :func:`pole_weights`: how much of each pole the record holds.
* :func:`fit_sinusoid` -- the least-squares fit of a record to a sinusoid at ω
  (plus a constant and, optionally, the free modes, so the start transient need not
  have died out), its amplitude and the record's largest departure from the fit.
* :func:`nearest_pole` and :func:`judge_pole` -- a predicted pole against the
  identified ones (nearest in the sampled domain, aliases apart), the row's
  measured frequency, decay and relative error, judged by
  :func:`mechcirc.verdict.judge`.
"""

from __future__ import annotations

import math

import numpy as np

from .verdict import judge

__all__ = ["poles", "pole_weights", "fit_sinusoid", "pole_of", "nearest_pole", "judge_pole"]


def poles(record, dt: float, *, delays: int | None = None, order: int | None = None,
          rel: float = 1e-9, max_order: int = 60) -> np.ndarray:
    """Poles s [1/s] of a sampled record (:func:`pole_weights`: how much of each it holds).

    Parameters
    ----------
    record : array_like
        Samples, one per row; columns are channels (a 1-D record is one channel).
        Each channel is scaled to unit standard deviation first.
    dt : float
        Sample interval [s].
    delays : int, optional
        Block columns of the Hankel matrix less one (default n/3 of the n samples:
        right for one channel; a record of the whole state needs few).
    order : int, optional
        The number of poles when it is known (a record of the whole state: its
        dimension, and any slow drift); by default set by ``rel``.
    rel : float
        Singular values below ``rel`` × the largest are noise (they set the order).
    max_order : int
        Largest number of poles (of an order set by ``rel``).

    Returns
    -------
    ndarray of complex
        The poles, all of them (both signs of Im s; sampled, so |Im s| < π/Δt).
    """
    Y = np.asarray(record, float)
    Y = Y[:, None] if Y.ndim == 1 else Y
    n, p = Y.shape
    Y, L = Y / np.maximum(np.std(Y, axis=0), 1e-300), n // 3 if delays is None else delays
    H = np.lib.stride_tricks.sliding_window_view(Y, L + 1, axis=0)  # (n − L, p, L + 1)
    H = H.transpose(0, 2, 1).reshape(n - L, (L + 1) * p)           # row k: y_k … y_k+L
    R = np.linalg.qr(H, mode="r")          # same right singular vectors, cheaper SVD
    _, sv, Vh = np.linalg.svd(R, full_matrices=False)
    if sv[0] == 0:
        return np.zeros(0, complex)
    if order is None:
        order = int(min(max_order, np.sum(sv > rel * sv[0])))
    V = Vh[:order].T                                          # ((L + 1) p, order)
    z = np.linalg.eigvals(np.linalg.pinv(V[:-p]) @ V[p:])
    z = z[np.abs(z) > 1e-12]
    return np.log(z.astype(complex)) / dt


def pole_weights(record, dt: float, s) -> np.ndarray:
    """How much of each pole of ``s`` the record holds: the norm over the channels of its
    least-squares amplitude in y_k = Σ c_i exp(s_i k Δt) (a noise pole has ~0).

    Parameters
    ----------
    record : array_like
        Samples, one per row (as :func:`poles`).
    dt : float
        Sample interval [s].
    s : array_like of complex
        Poles [1/s], e.g. from :func:`poles`.

    Returns
    -------
    ndarray of float
    """
    Y = np.asarray(record, float)
    Y = Y[:, None] if Y.ndim == 1 else Y
    k = np.arange(Y.shape[0])
    amps = np.linalg.lstsq(np.exp(np.outer(k * dt, s)), Y.astype(complex), rcond=None)[0]
    return np.linalg.norm(amps, axis=1)


def fit_sinusoid(t, y, omega: float, free=()) -> tuple[float, float]:
    """Amplitude of the sinusoid at ``omega`` in the record ``y(t)``, by least squares.

    The record is fitted by a constant, cos ωt, sin ωt and, for each free pole s of
    ``free``, e^{Re s t} (cos, sin)(Im s t); over whole periods of a record sampled
    evenly and without free modes it is the record's Fourier coefficient at ω.

    Parameters
    ----------
    t, y : array_like
        Times [s] and values of the record.
    omega : float
        Angular frequency of the forcing [rad/s].
    free : iterable of complex
        Free poles [1/s] also in the record (Im s > 0), fitted and left out.

    Returns
    -------
    amplitude : float
        |the sinusoid at ω| (units of y).
    departure : float
        Largest |y − fit| (units of y).
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    cols = [np.ones_like(t), np.cos(omega * t), np.sin(omega * t)]
    for s in free:
        env = np.exp(s.real * t)
        cols += [env * np.cos(s.imag * t), env * np.sin(s.imag * t)]
    B = np.column_stack(cols)
    c = np.linalg.lstsq(B, y, rcond=None)[0]
    return math.hypot(c[1], c[2]), float(np.abs(y - B @ c).max())


def pole_of(mode) -> complex:
    """The pole s = −ζω_n + iω_d [1/s] of a resonance (or anti-resonance).

    Parameters
    ----------
    mode : mechcirc.resonances.Resonance
        Anything with ``omega`` (ω_n), ``zeta`` and ``omega_d``.

    Returns
    -------
    complex
    """
    return complex(-mode.zeta * mode.omega, mode.omega_d)


def nearest_pole(found, expected: complex, dt: float) -> complex:
    """The pole of ``found`` nearest ``expected`` in the sampled (z) domain, where poles
    2π/Δt apart in frequency (aliases) are one.

    Parameters
    ----------
    found : array_like of complex
        Identified poles [1/s] (at least one).
    expected : complex
        The predicted pole [1/s].
    dt : float
        Sample interval of the record [s].

    Returns
    -------
    complex
    """
    found = np.asarray(found, complex)
    return complex(found[np.argmin(np.abs(np.exp(found * dt) - np.exp(expected * dt)))])


def judge_pole(row: dict, expected: complex, found, dt: float, tol: float, *,
               measure: str = "pole", spread: float = 0.0, why: str | None = None) -> dict:
    """Judge the predicted pole ``expected`` against the nearest identified one.

    ``measure="pole"`` (a netlist's rows): the row gains ``ringing_omega_d`` (ω_d =
    Im s of the match [rad/s]), ``decay`` (−Re s [1/s]) and ``rel_error`` =
    |s − s_expected| / |s_expected|.  ``measure="omega_n"`` (a scene's rows):
    ``ringing_omega`` (ω_n = |s|), ``ringing_zeta`` (−Re s / |s|) and ``rel_error``
    = |ω_n − ω_n,expected| / ω_n,expected.  Then :func:`mechcirc.verdict.judge`
    with ``tol`` (at least 100 × ``spread``).

    Parameters
    ----------
    row : dict
        The row (it gains the keys above, ``verdict``, ``tol`` and ``why``).
    expected : complex
        The circuit's pole s = −ζω_n + iω_d [1/s].
    found : array_like of complex
        Identified poles [1/s]; those with Im s > 0 are matched.
    dt : float
        Sample interval of the record [s].
    tol : float
        Tolerance of ``rel_error``.
    measure : {"pole", "omega_n"}
        What is compared (above).
    spread : float
        Uncertainty of the match (relative).
    why : str, optional
        Given: the line cannot be measured, for this reason (the match is still shown).

    Returns
    -------
    dict
    """
    found = np.asarray(found, complex)
    found = found[found.imag > 0]
    if found.size == 0:
        return judge(row, None, tol, why or "no underdamped mode in the recorded motion")
    best = nearest_pole(found, expected, dt)
    if measure == "pole":
        row.update(ringing_omega_d=best.imag, decay=-best.real,
                   rel_error=abs(best - expected) / abs(expected))
    else:
        row.update(ringing_omega=abs(best), ringing_zeta=-best.real / abs(best),
                   rel_error=abs(abs(best) - abs(expected)) / abs(expected))
    return judge(row, row["rel_error"], max(tol, 100 * spread), why)
