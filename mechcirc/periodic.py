"""The drive's periodic motion at machine speed: force over the cycle, speed map.

A drive that moves x(θ) over one revolution of the main shaft
(:class:`mechcirc.motion_laws.Motion`, netlist ``drive ... motion=``), the
shaft turning at Ω [rad/s] (θ = Ωt), has the velocity

    v(θ) = Ω dx/dθ = Σ_{k≥1} Re(V_k e^{jkθ}),   V_k = 2Ω c_k,

c_k the Fourier coefficients of dx/dθ (exact, :meth:`Motion.fourier`).  The
linear circuit answers each harmonic by the law Q0 = V0/K at ω = kΩ, so the
steady-state periodic force the drive must supply is

    Q(θ) = Σ_{k=1}^{N} Re(Q_k e^{jkθ}),   Q_k = V_k / K(kΩ),

and every element's force and velocity are the same sums of its per-harmonic
responses (:meth:`mechcirc.Sweep.force`).  The mean force (k = 0) is 0:
the mean velocity of a periodic motion is 0, and a static preload depends on
the springs' free lengths, which a circuit does not hold.

Number of harmonics.  N is the smallest for which the omitted tail,
Σ_{k>N} |Q_k| (a bound of the truncation error at every θ), is at most
``tol`` × max|Q(θ)|.  The terms are computed out to k_max, raised ×4 from 64
until the tail beyond k_max, extrapolated from the last two octaves of |Q_k|,
is small, and until those octaves lie above every resonance and anti-resonance
of K within 4096 harmonics (unless the root's gain could not make their sum
matter).  Where |Q_k| falls as 1/k the force jumps: the tail beyond k_max is
then what it adds next to a jump, half of it, which no N reduces.  The
reported ``error`` is that tail plus
the rounding of K (:attr:`Sweep.error`) over the harmonics used and, for a
table, the interpolation estimate (the same force from the spline through
every other row), all relative to max|Q|.

Undamped circuits: a harmonic exactly on a resonance (K(kΩ) = 0) makes the
steady state unbounded; the result says so (``unbounded``, ``Q`` all NaN,
``peak = inf``) instead of a number.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from .circuit import Circuit, units_of
from .errors import MechcircError, NetlistError
from .sources import brief, positive_number, quantity_frame, real_number, summary_repr
from .units import convert_frequency

__all__ = ["PeriodicResult", "SpeedMap", "periodic", "rpm_to_omega", "speed_map"]

#: Relative distance |kΩ − ωₙ|/ωₙ within which a harmonic is named "near" a resonance.
NEAR = 0.03
#: Speeds of a map solved together (their phasors: SPEED_CHUNK × k_max complex numbers).
SPEED_CHUNK = 256
#: The default error asked for, relative to the peak force.
TOL = 1e-4
#: A motion's Fourier coefficient at most this fraction of the largest is rounding
#: (64ε; the closed form's rounding on a pure cosine law: about ε).
_ENDED = 64 * float(np.finfo(float).eps)
#: The most harmonics computed (the tail beyond is extrapolated).
MAX_HARMONICS = 4096
#: Damping ratio below which a resonance counts as undamped (as mechcirc.sweep).
UNDAMPED_ZETA = 1e-12


def rpm_to_omega(rpm: float) -> float:
    """Shaft speed [rev/min] to angular frequency Ω [rad/s]: ``Ω = 2π·rpm/60``.

    The shorthand the speed-domain functions use for
    ``units.convert_frequency(rpm, "rpm", "rad/s")`` (the one conversion).

    Parameters
    ----------
    rpm : float

    Returns
    -------
    float
    """
    return convert_frequency(rpm, "rpm", "rad/s")


@dataclass
class PeriodicResult:
    """The steady periodic state over one revolution at one machine speed (plain data; pickles).

    Attributes
    ----------
    name : str
        The circuit's name.
    rpm, omega_shaft : float
        Machine speed [rev/min] and Ω [rad/s].
    angle_deg : ndarray
        Crank angles θ [deg] of the outputs, 0 ≤ θ < 360.
    Q : ndarray
        Force the drive supplies [N] at each angle (NaN when unbounded).
    x, v : ndarray
        The drive's displacement [m] and velocity Ω dx/dθ [m/s] (exact).
    k : ndarray of int
        The harmonics used, 1 … N.
    omega : ndarray
        kΩ [rad/s].
    V, amplitude : ndarray of complex
        Velocity and force phasors V_k [m/s], Q_k [N]: v = Σ Re(V_k e^{jkθ}).
    K : ndarray of complex
        K(kΩ) [m/(N·s)].
    nearest, distance : ndarray
        The nearest resonance ωₙ [rad/s] (NaN when none is known) and
        (kΩ − ωₙ)/ωₙ.
    near : ndarray of bool
        |distance| ≤ ``near_fraction``.
    resonances : tuple of (float, float)
        (ωₙ, ζ) of the resonances (K = 0) up to beyond N·Ω.
    peak, peak_angle_deg : float
        max |Q(θ)| of the truncated series, located exactly (Newton on
        dQ/dθ = 0 from the best of a fine grid), and where.
    error : float
        Estimated error of Q relative to ``peak`` (see the module text); inf
        when unbounded or when the series does not converge fast enough.
    tol : float
        The error asked for.
    unbounded : tuple of int
        Harmonics exactly on an undamped resonance (the force is infinite).
    forces, velocities : dict of str to ndarray
        Each asked-for element's force [N] and velocity difference [m/s] over θ.
    element_peaks : dict of str to (float, float)
        Each asked-for element's max |force| over the cycle [N], located exactly as
        ``peak`` is (not the largest sample of ``forces``), and its θ [deg].
    notes : tuple of str
    units : dict of str to str
        The unit labels of the drive (:func:`mechcirc.circuit.units_of`): N, m,
        m/s for a translational drive; N·m, rad, rad/s for a rotary one (the
        units written above in brackets are the translational ones).
    """

    __repr__ = summary_repr

    name: str
    rpm: float
    omega_shaft: float
    angle_deg: np.ndarray
    Q: np.ndarray
    x: np.ndarray
    v: np.ndarray
    k: np.ndarray
    omega: np.ndarray
    V: np.ndarray
    amplitude: np.ndarray
    K: np.ndarray
    nearest: np.ndarray
    distance: np.ndarray
    near: np.ndarray
    resonances: tuple
    peak: float
    peak_angle_deg: float
    error: float
    tol: float
    unbounded: tuple = ()
    near_fraction: float = NEAR
    forces: dict = field(default_factory=dict)
    velocities: dict = field(default_factory=dict)
    notes: tuple = ()
    units: dict = field(default_factory=lambda: units_of(None))
    element_peaks: dict = field(default_factory=dict)

    @property
    def harmonics(self) -> int:
        """N, the number of harmonics summed."""
        return int(self.k.size)

    def to_dataframe(self):
        """One row per angle: ``angle_deg`` [deg], the drive's ``Q`` [N], ``x`` [m], ``v`` [m/s]
        (N·m, rad, rad/s for a rotary drive), then ``F(NAME)`` and ``dv(NAME)`` of each element
        asked for; ``attrs["units"]`` the unit of each column (as :meth:`mechcirc.Sweep.to_dataframe`)."""
        u = self.units
        cols = {"angle_deg": self.angle_deg, "Q": self.Q, "x": self.x, "v": self.v,
                **{f"F({n})": f for n, f in self.forces.items()},
                **{f"dv({n})": dv for n, dv in self.velocities.items()}}
        unit = {"angle_deg": "deg", "Q": u["Q"], "x": u["x"], "v": u["v"], "F": u["Q"], "dv": u["v"]}
        return quantity_frame(cols, unit)

    def plot(self, ax=None, fig=None):
        """Q(θ) beside its spectrum with |K| and the resonances: :func:`mechcirc.plotting.plot_periodic`.

        Returns what it drew on: ``ax`` (Q(θ) only, on the caller's Axes), ``fig`` (which
        must be an *empty* Figure or SubFigure; one already holding Axes is refused with an
        InputError) or a new Figure.
        """
        from .plotting import plot_periodic

        return plot_periodic(self, ax=ax, fig=fig)


@dataclass
class SpeedMap:
    """Peak drive force over the cycle versus machine speed (plain data; pickles).

    Attributes
    ----------
    name : str
    rpm : ndarray
        Machine speeds [rev/min].
    peak : ndarray
        max |Q(θ)| [N] at each speed (inf where a harmonic sits on an undamped resonance).
    harmonics : ndarray of int
        N used at each speed.
    error : ndarray
        Estimated relative error at each speed.
    crossings : tuple of (rpm, k, omega_n, zeta, weight)
        Speeds in the range where a harmonic meets a resonance, k·Ω = ωₙ
        (k up to the largest N used); ``weight`` is that harmonic's share of the
        drive velocity, |c_k| / max |c|, so that the ones that matter stand out.
    element_peaks : dict of str to ndarray
        max |force| [N] over the cycle of each element asked for, at each speed.
    notes : tuple of str
    units : dict of str to str
        The drive's unit labels (:func:`mechcirc.circuit.units_of`; N·m for a rotary drive).
    """

    __repr__ = summary_repr

    name: str
    rpm: np.ndarray
    peak: np.ndarray
    harmonics: np.ndarray
    error: np.ndarray
    crossings: tuple
    element_peaks: dict = field(default_factory=dict)
    notes: tuple = ()
    units: dict = field(default_factory=lambda: units_of(None))

    def to_dataframe(self):
        """One row per speed: ``rpm`` [rev/min], ``peak`` drive force [N, N·m for a rotary
        drive], ``harmonics`` N used, ``error`` [1], then ``peak(NAME)`` [N] of each element
        asked for; ``attrs["units"]`` the unit of each column."""
        cols = {"rpm": self.rpm, "peak": self.peak, "harmonics": self.harmonics,
                "error": self.error, **{f"peak({n})": p for n, p in self.element_peaks.items()}}
        return quantity_frame(cols, {"rpm": "rpm", "peak": self.units["Q"], "harmonics": "",
                                     "error": "1"})

    def plot(self, ax=None):
        """The map: :func:`mechcirc.plotting.plot_speed_map`; returns ``ax`` when given,
        else the new Figure."""
        from .plotting import plot_speed_map

        return plot_speed_map(self, ax=ax)


# ------------------------------------------------------------------ the pieces
def _prepared(circuit: Circuit, motion):
    """``(circuit, motion, amplitude)``: the motion (given or the drive's) and the drive's
    amplitude, by which per-element responses are divided (a motion drive has 1)."""
    drive = circuit.drive
    if drive is None:
        raise MechcircError("the circuit has no drive; a periodic drive needs "
                            "'drive NAME N1 N2 motion=...'")
    if motion is None:
        motion = drive.motion
        if motion is None:
            raise NetlistError(
                f"drive {drive.name!r} has no motion over the revolution",
                circuit.source or "<string>", drive.line, drive.col,
                "a motion: 'drive NAME N1 N2 motion=lift.csv' or 'motion=cycloidal rise=120 "
                "dwell=60 return=120 stroke=0.05' (docs/netlist.md)")
    if not hasattr(motion, "fourier"):
        raise MechcircError(f"motion must be a Motion (mechcirc.motion_laws.cam_cycle or "
                            f"read_motion_table), got {brief(motion)}")
    if drive.kind != "velocity":
        raise MechcircError(f"drive {drive.name!r} is a force drive; a motion is imposed "
                            "by a velocity drive")
    if drive.amplitude == 0 or not math.isfinite(drive.amplitude):
        drive = dataclasses.replace(drive, amplitude=1.0)
        circuit = dataclasses.replace(circuit, drive=drive)
    return circuit, motion, drive.amplitude


def _on_grid(Qk: np.ndarray, n: int) -> np.ndarray:
    """Σ_{k=1}^{N} Re(Q_k e^{jkθ}) at θ = 2πi/n, i < n, by one inverse FFT on a grid
    fine enough for N (every m-th point of n·m > 2N points: no aliasing); Q_k on the
    last axis (each row of a 2-D ``Qk`` on its own)."""
    N = Qk.shape[-1]
    m = -(-(2 * N + 1) // n)
    X = np.zeros(Qk.shape[:-1] + (n * m // 2 + 1,), dtype=complex)
    X[..., 1:N + 1] = Qk * (n * m / 2)
    return np.fft.irfft(X, n * m)[..., ::m]


def _peaks(Qk: np.ndarray, fine: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """max |Σ Re(Q_k e^{jkθ})| and its θ [rad] for each row of ``Qk``: a fine grid
    (inverse FFT), then Newton on the derivative from the grid's best point
    (``fine=False``: the grid of 4 points per period of the highest harmonic only,
    a scale good to a few per cent)."""
    Qk = np.atleast_2d(Qk)
    rows, n_k = Qk.shape
    if n_k == 0:
        return np.zeros(rows), np.zeros(rows)
    per = 4                                 # grid points per period of the highest harmonic
    n = 1 << max(10 if fine else 6, math.ceil(math.log2(per * n_k + 1)))
    y = _on_grid(Qk, n)         # (n > 4 n_k: no finer grid needed)
    i = np.argmax(np.abs(y), axis=1)
    best, theta = np.abs(y[np.arange(rows), i]), 2 * np.pi * i / n
    k = np.arange(1, n_k + 1)
    for r in range(rows if fine else 0):
        q, t = Qk[r], theta[r]
        sign = 1.0 if y[r, i[r]] >= 0 else -1.0
        for _ in range(8):
            e = q * np.exp(1j * k * t)
            d1 = -float(np.sum(k * e.imag))           # d/dθ Re(Q e^{jkθ}) = −k Im(...)
            d2 = -float(np.sum(k * k * e.real))
            if sign * d2 >= 0:
                break
            step = -d1 / d2
            t += step
            if abs(step) < 1e-15:
                break
        value = abs(float(np.sum((q * np.exp(1j * k * t)).real)))
        if value >= best[r] and abs(t - theta[r]) < 2 * math.pi / n:
            best[r], theta[r] = value, t
    return best, np.mod(theta, 2 * np.pi)


def _tail_beyond(mag: np.ndarray) -> float:
    """Σ_{k>k_max} |Q_k| extrapolated from the last two octaves of ``mag`` (|Q_1| … |Q_kmax|);
    where |Q_k| falls as 1/k, what those harmonics can add at any θ instead (below)."""
    n = mag.size
    if n < 8:
        return math.inf
    s1, s2 = float(np.sum(mag[n // 4:n // 2])), float(np.sum(mag[n // 2:]))
    if s2 == 0:
        return 0.0
    r = s2 / s1 if s1 > 0 else math.inf
    # Octave sums fall geometrically for |Q_k| ~ k^(−p): r = 2^(1−p).  p within 0.15 of 1
    # is a force with jumps J, |Q_k| ≈ |Σ J e^{−jkθ_J}|/(πk): their harmonics beyond any
    # k_max add up to J/2 next to each jump (no N does better), at most π/2 · max k|Q_k|.
    # Slower (p < 0.85: impulses) has no bound.
    if r < 0.9:
        return s2 * r / (1 - r)
    return math.pi / 2 * float(np.max(mag[n // 2:] * np.arange(n // 2 + 1, n + 1))) \
        if r <= 1.1 else math.inf


def _unit_force(K: np.ndarray) -> np.ndarray:
    """1/K with the exact limits: K = ∞ → 0, K = 0 → ∞ (flagged by the caller)."""
    with np.errstate(all="ignore"):
        Qu = 1.0 / K
    Qu[np.isinf(K)] = 0.0
    Qu[K == 0] = complex(math.inf, 0.0)
    return Qu


def _solve(circuit, motion, amp, Omega, tol, harmonics, method,
           max_harmonics=MAX_HARMONICS):
    """Harmonic amplitudes at the shaft speeds ``Omega`` (shape (S,)).

    Returns ``(N, V, Qk, K, error, notes, responses)``: N and error of shape (S,);
    V, Qk and K(kΩ) of shape (S, max N), V and Qk zero beyond each row's N; ``responses(name)``
    gives an element's (force, velocity) phasors in the same shape.  k_max starts
    at 64 (4N when ``harmonics`` is fixed) and is raised ×4 for the speeds whose
    extrapolated tail is not yet small.
    """
    Omega = np.atleast_1d(np.asarray(Omega, dtype=float))
    S = Omega.size
    N, error, table_error = np.zeros(S, dtype=int), np.zeros(S), np.zeros(S)
    rows: list = [None] * S                    # (V, Qk, sweep, index in the sweep)
    pending = np.arange(S)
    kmax = max(64, 4 * harmonics) if harmonics else 64
    # (ωₙ, ζ) of every root of K the harmonics can reach (none needed for a fixed N)
    roots = np.array([r[:2] for r in _resonances(circuit, max_harmonics * Omega.max(), [],
                                                 None)] if not harmonics else []).reshape(-1, 2)
    while pending.size:
        n, e, from_table, V, Qk, sw, done = _harmonics_round(
            circuit, motion, Omega[pending], kmax, tol, harmonics, method,
            done_anyway=bool(harmonics) or kmax >= max_harmonics, roots=(roots, max_harmonics))
        for j in np.flatnonzero(done):
            i = pending[j]
            N[i], error[i], table_error[i] = n[j], e[j], from_table[j]
            rows[i] = (V[j, :n[j]], Qk[j, :n[j]], sw, j * kmax)
        pending, kmax = pending[~done], min(4 * kmax, max_harmonics)
    width = int(N.max())
    Vs, Qs = np.zeros((S, width), dtype=complex), np.zeros((S, width), dtype=complex)
    Ks = np.full((S, width), complex(math.inf, 0.0))
    for i, (v, q, sw, at) in enumerate(rows):
        Vs[i, :v.size], Qs[i, :q.size], Ks[i, :v.size] = v, q, sw.K[at:at + v.size]

    def responses(name):
        F, U = np.zeros((S, width), dtype=complex), np.zeros((S, width), dtype=complex)
        for i, (v, _, sw, at) in enumerate(rows):
            F[i, :v.size] = sw.force(name)[at:at + v.size] * (v / amp)
            U[i, :v.size] = sw.velocity(name)[at:at + v.size] * (v / amp)
        return F, U

    return N, Vs, Qs, Ks, error, _not_met(N, error, table_error, tol), responses


def _harmonics_round(circuit, motion, Omega, kmax, tol, harmonics, method, done_anyway,
                     roots):
    """One round of :func:`_solve` at the speeds ``Omega`` with ``kmax`` harmonics:
    per speed the harmonics needed ``n``, the relative error ``e`` (of it, the
    table's interpolation ``from_table``), the amplitudes V and Qk (shape
    (speeds, kmax)), the sweep, and which speeds are ``done``.

    The tail beyond k_max is extrapolated from the last two octaves, which a root of K
    (``roots``: its (ωₙ, ζ) rows, and the most harmonics) in or above them bends: an
    anti-resonance in them hid a tail 18 times the estimate beyond it.  Such a root
    leaves a speed not done unless those octaves' sum, raised by its gain (the rise of
    |1/K| up to it, at most ∝ ω, times 1/(2|ζ|) at a resonance), is still small."""
    P, c, k = Omega.size, motion.fourier(kmax), np.arange(1, kmax + 1)
    # A series that has ended (a crank's or an eccentric's cosine): every coefficient
    # of the last four octaves at rounding level, which a law decaying as a power of k
    # cannot be; they are dropped, and their share of the force counted as error below.
    noise = np.where(np.abs(c) <= _ENDED * np.abs(c).max(initial=0.0), np.abs(c), 0.0)
    ended = kmax >= 64 and not np.any(np.abs(c[kmax // 16:]) > noise[kmax // 16:])
    c = np.where(noise > 0, 0.0, c) if ended else c
    sw = circuit.sweep(np.outer(Omega, k).ravel(), method=method)
    Qu = _unit_force(sw.K).reshape(P, kmax)
    V = 2 * Omega[:, None] * c[None, :]
    Qk = V * Qu
    with np.errstate(invalid="ignore"):
        mag = np.abs(Qk)
    mag[~np.isfinite(mag)] = 0.0          # unbounded terms are reported apart
    beyond = np.array([_tail_beyond(m) for m in mag])
    # The scale max|Q(θ)| from the first 512 harmonics: the rest moves it by at most
    # their Σ|Q_k|, a small fraction wherever a tolerance can be met at all.
    head = Qk[:, :512]
    scale = _peaks(np.where(np.isfinite(head), head, 0.0), fine=False)[0]
    (roots, most), lo = roots, kmax * Omega[:, None] / 8
    above = (roots[:, 0] > lo) & (roots[:, 0] <= most * Omega[:, None])
    with np.errstate(divide="ignore", invalid="ignore"):   # (ζ may be −0.0: gain ∞; ∞·0 NaN)
        gain = np.where(above, roots[:, 0] / lo / abs(2 * roots[:, 1]), 0).max(axis=1, initial=0)
        window = gain * mag[:, kmax // 4:].sum(axis=1)
    done = (np.fmax(beyond, window) <= 0.25 * tol * scale) | done_anyway
    tail = np.cumsum(mag[:, ::-1], axis=1)[:, ::-1]         # Σ_{k' ≥ k}
    tail = np.concatenate([tail[:, 1:], np.zeros((P, 1))], axis=1) + beyond[:, None]
    if harmonics:
        n = np.full(P, min(harmonics, kmax))
    else:
        ok = tail <= tol * scale[:, None]
        n = np.where(ok.any(axis=1), np.argmax(ok, axis=1) + 1, kmax)
    used, err = k[None, :] <= n[:, None], tail[np.arange(P), n - 1]
    errK = sw.error.reshape(Qk.shape)
    err = err + np.sum(np.where(used & np.isfinite(errK), errK, 0.0) * mag, axis=1)
    if ended:
        err = err + np.sum(2 * Omega[:, None] * noise * np.abs(np.where(np.isfinite(Qu), Qu, 0)),
                           axis=1)
    interp, coarse = np.zeros(P), getattr(motion, "coarse", None)
    if coarse is not None:
        dQ = np.abs(2 * Omega[:, None] * (c - coarse.fourier(kmax)) * Qu)
        interp = np.sum(np.where(used & np.isfinite(dQ), dQ, 0.0), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.where(scale > 0, (err + interp) / scale,
                     np.where(err + interp == 0, 0.0, np.inf))
        from_table = np.where(scale > 0, interp / scale, 0.0)
    return n, e, from_table, V, Qk, sw, done


def _not_met(N, error, table_error, tol) -> list[str]:
    """The note (at most one) when a speed's estimated error is over ``tol``, with why."""
    if not np.any(error > tol):
        return []
    i = int(np.argmax(error > tol))
    if table_error[i] >= 0.5 * error[i]:
        why = (f"{table_error[i]:.2g} of it is the table's interpolation, estimated from "
               "the spline through every other row: give a finer table")
    elif math.isinf(error[i]):
        why = ("|Q_k| does not fall in the last octaves, so the tail cannot be bounded: a "
               "resonance or anti-resonance of K lies there, or the force has impulses (a "
               "mass at the drive following a motion whose velocity jumps)")
    else:
        why = ("the force's harmonics fall off slowly: a mass or a stiff path at the "
               "drive sees the jumps of the motion's acceleration or jerk (where the force "
               "itself jumps, as |Q_k| ~ 1/k says, no number of harmonics does better than "
               "half the jump: the sum shows Gibbs overshoot there); ask a larger "
               "tolerance or smooth the motion")
    return [f"the error asked for ({tol:g}) is not met with {int(N[i])} harmonics: "
            f"estimated {error[i]:.3g} ({why})"]


def _resonances(circuit, omega_max, notes, kind="resonance"):
    """(ωₙ, ζ, error) of the resonances (K = 0; ``kind=None``: and anti-resonances) up to
    ``omega_max``; a note if they cannot be had.

    Kept on the circuit (they do not depend on the speed), as its reduction is; a refusal
    too, for bands as wide or wider (a speed map's chunks ask for the same band)."""
    def make():
        try:
            return omega_max, [(r.omega, r.zeta, r.error, r.kind) for r in
                               circuit.resonances(omega_max=omega_max)]
        except MechcircError as exc:
            return omega_max, exc
    _, found = circuit.memo("_periodic_resonances", make, lambda c: c[0] >= omega_max
                              if isinstance(c[1], list) else c[0] <= omega_max)
    if isinstance(found, MechcircError):
        notes.append(f"resonances not computed ({found}); harmonics are not named")
        return []
    return [r[:3] for r in found if r[0] <= omega_max and kind in (None, r[3])]


def _validate(rpm, tol, harmonics):
    if not (positive_number(rpm)):
        raise MechcircError(f"the machine speed must be a finite number > 0 rev/min, got {rpm!r}")
    if not (real_number(tol) and 0 < tol < 1):
        raise MechcircError(f"tol must be between 0 and 1, got {tol!r}")
    if harmonics is not None and not (isinstance(harmonics, numbers.Integral)
                                      and 1 <= harmonics <= MAX_HARMONICS):
        raise MechcircError(f"harmonics must be between 1 and {MAX_HARMONICS}, got {harmonics}")


# ------------------------------------------------------------------ periodic
def periodic(circuit: Circuit, rpm: float, *, motion=None, tol: float = TOL,
             harmonics: int | None = None, points: int = 360, elements=(),
             near: float = NEAR, method: str = "auto") -> PeriodicResult:
    """The steady-state periodic force of the drive over one revolution at ``rpm``.

    Parameters
    ----------
    circuit : Circuit
        A linear circuit whose velocity drive has a ``motion`` (netlist
        ``drive ... motion=``), or any velocity drive with ``motion`` given.
    rpm : float
        Machine (main shaft) speed [rev/min].
    motion : Motion, optional
        The drive's motion over one revolution (default: the drive's).
    tol : float
        Error asked for, relative to max |Q(θ)|: fixes the number of harmonics.
    harmonics : int, optional
        Use exactly this many harmonics instead (the error is still estimated).
    points : int
        Output angles, θ = 360°·i/points.
    elements : str, sequence of str or True
        Element (or elements) whose force and velocity to return (True: all loaded elements).
    near : float
        A harmonic within this relative distance of a resonance is named near it.
    method : {"auto", "sp", "nodal"}
        How K is evaluated (:func:`mechcirc.sweep`).

    Returns
    -------
    PeriodicResult

    Examples
    --------
    >>> from mechcirc import parse
    >>> from mechcirc.periodic import periodic
    >>> c = parse("drive V T 0 motion=cycloidal rise=120 dwell=60 return=120 stroke=0.05\\n"
    ...           "spring k T a 2e5\\nmass m a 0 1.5\\ndamper c a 0 20")
    >>> r = periodic(c, 600)
    >>> r.harmonics < 200 and r.error <= 1e-4
    True
    """
    _validate(rpm, tol, harmonics)
    if not (isinstance(points, numbers.Integral) and 4 <= points <= 1_000_000):
        raise MechcircError(f"points must be an integer from 4 to 1000000, got {points!r}")
    circuit, motion, amp = _prepared(circuit, motion)
    solved = _solve(circuit, motion, amp, rpm_to_omega(rpm), tol, harmonics, method)
    elements = (elements,) if isinstance(elements, str) else elements      # one name
    return _at_angles(circuit, motion, rpm, solved, points, elements, near, tol)


def _at_angles(circuit, motion, rpm, solved, points: int, elements, near: float,
               tol: float) -> PeriodicResult:
    """The result of :func:`periodic` from the harmonics ``solved`` at one speed."""
    Omega = rpm_to_omega(rpm)
    N, V, Qk, K, error, notes, responses = solved
    N, error = int(N[0]), float(error[0])
    k = np.arange(1, N + 1)
    w = k * Omega
    V, Qk, K = V[0], Qk[0], K[0]
    found = _resonances(circuit, (N + 1) * Omega * (1 + near), notes)
    nearest, distance, unbounded = _nearest(found, w, V, Qk)
    theta = 2 * np.pi * np.arange(points) / points
    x, dx, _ = motion.evaluate(theta)
    forces, velocities, element_peaks = {}, {}, {}
    ks = sorted(int(i) for i in unbounded)
    if ks:
        notes.append("harmonic(s) " + ", ".join(
            f"k = {i} (ω = {i * Omega:.10g} rad/s)" for i in ks) +
            " fall exactly on an undamped resonance: the steady periodic force is unbounded "
            "(no finite number exists; add damping or change the speed)")
        Q = np.full(points, np.nan)
        peak, peak_theta, error = math.inf, math.nan, math.inf
    else:
        Q = _on_grid(Qk, points)
        peak, peak_theta = (float(a[0]) for a in _peaks(Qk))
        names = ([e.name for e in circuit.elements] if elements is True else list(elements))
        for name in names:
            f, u = responses(name)
            forces[name], velocities[name] = _on_grid(f[0], points), _on_grid(u[0], points)
            top, at = _peaks(f[0])
            element_peaks[name] = (float(top[0]), math.degrees(at[0]))
    near_mask = np.abs(np.nan_to_num(distance, nan=np.inf)) <= near
    return PeriodicResult(
        name=circuit.name, rpm=float(rpm), omega_shaft=Omega, angle_deg=np.degrees(theta),
        Q=Q, x=x, v=Omega * dx, k=k, omega=w, V=V, amplitude=Qk, K=K, nearest=nearest,
        distance=distance, near=near_mask, resonances=tuple((wn, z) for wn, z, _ in found),
        peak=peak, peak_angle_deg=math.degrees(peak_theta), error=error, tol=tol,
        unbounded=tuple(ks), near_fraction=near,
        forces=forces, velocities=velocities, notes=tuple(notes),
        units=units_of(circuit.drive), element_peaks=element_peaks)


def _peak_or_inf(Qk, unbounded):
    """Peak over the cycle of each row of harmonics ``Qk``; inf where ``unbounded``."""
    return np.where(unbounded, math.inf, _peaks(np.where(unbounded[:, None], 0.0, Qk))[0])


def _crossings(found, motion, kmax: int, rpm_min: float, rpm_max: float) -> list:
    """(rpm, k, ω_n, ζ, weight) where harmonic k of the motion meets a resonance, by speed."""
    c = np.abs(motion.fourier(kmax))
    weight = c / c.max() if c.max() > 0 else c
    return sorted((r, k, wn, zeta, float(weight[k - 1])) for wn, zeta, _ in found
                  for k in range(1, kmax + 1)
                  if rpm_min <= (r := convert_frequency(wn / k, "rad/s", "rpm")) <= rpm_max)


def _nearest(found, w, V, Qk):
    """For each harmonic ω = ``w``: the nearest resonance of ``found`` and the relative
    distance to it, and the harmonics (numbered from 1) whose force is unbounded
    (an infinite term, or on an undamped resonance within its error)."""
    nearest, distance = np.full(w.size, np.nan), np.full(w.size, np.nan)
    unbounded = set(np.flatnonzero(~np.isfinite(Qk) & (np.abs(V) > 0)) + 1)
    vmax = float(np.max(np.abs(V))) if w.size else 0.0
    for wn, zeta, err in found:
        d = (w - wn) / wn
        closer = np.isnan(distance) | (np.abs(d) < np.abs(distance))
        nearest[closer], distance[closer] = wn, d[closer]
        if zeta <= UNDAMPED_ZETA:
            hit = (np.abs(d) <= max(err, 4e-16)) & (np.abs(V) > 1e-13 * vmax)
            unbounded |= set(np.flatnonzero(hit) + 1)
    return nearest, distance, unbounded


# ------------------------------------------------------------------ the speed map
def speed_map(circuit: Circuit, rpm_min: float, rpm_max: float, points: int = 200, *,
              motion=None, tol: float = TOL, harmonics: int | None = None, elements=(),
              method: str = "auto") -> SpeedMap:
    """Peak drive force over the cycle versus machine speed, resonance crossings marked.

    Parameters
    ----------
    circuit, motion, tol, harmonics, method
        As for :func:`periodic` (the harmonics are chosen at each speed).
    rpm_min, rpm_max : float
        The speed range [rev/min], 0 < rpm_min < rpm_max.
    points : int
        Speeds, evenly spaced.
    elements : str or sequence of str
        Elements whose peak force to map as well.

    Returns
    -------
    SpeedMap
    """
    _validate(rpm_min, tol, harmonics)
    _validate(rpm_max, tol, harmonics)
    if not rpm_min < rpm_max:
        raise MechcircError(f"need rpm_min < rpm_max, got {rpm_min:g} and {rpm_max:g}")
    if not (isinstance(points, numbers.Integral) and 2 <= points <= 100_000):
        raise MechcircError(f"points must be an integer from 2 to 100000, got {points!r}")
    circuit, motion, amp = _prepared(circuit, motion)
    elements = (elements,) if isinstance(elements, str) else elements      # one name
    rpm = np.linspace(rpm_min, rpm_max, points)
    used, error, peak = np.zeros(points, dtype=int), np.zeros(points), np.zeros(points)
    element_peaks = {name: np.zeros(points) for name in elements}
    notes: list[str] = []
    for lo in range(0, points, SPEED_CHUNK):        # bounded memory: chunk × k_max phasors
        part = slice(lo, min(lo + SPEED_CHUNK, points))
        n, _, Qk, _, err, _, responses = _solve(
            circuit, motion, amp, rpm_to_omega(rpm[part]), tol, harmonics, method)
        unbounded = ~np.all(np.isfinite(Qk), axis=1)
        used[part], error[part] = n, np.where(unbounded, math.inf, err)
        peak[part] = _peak_or_inf(Qk, unbounded)
        for name in elements:
            element_peaks[name][part] = _peak_or_inf(responses(name)[0], unbounded)
    unbounded = ~np.isfinite(peak)
    short = (error > tol) & ~unbounded
    if short.any():
        notes.append(f"the error asked for ({tol:g}) is not met at {int(short.sum())} of the "
                     f"{points} speeds (largest estimated error {error[short].max():.3g}, at "
                     f"{rpm[short][np.argmax(error[short])]:.6g} rpm)")
    kmax = int(used.max())
    if unbounded.any():
        notes.append(f"{int(unbounded.sum())} speed(s) put a harmonic exactly on an undamped "
                     "resonance: the peak force is unbounded there (inf)")
    found = _resonances(circuit, kmax * rpm_to_omega(rpm_max) * (1 + 1e-9), notes)
    return SpeedMap(name=circuit.name, rpm=rpm, peak=peak, harmonics=used, error=error,
                    crossings=tuple(_crossings(found, motion, kmax, rpm_min, rpm_max)),
                    element_peaks=element_peaks,
                    notes=tuple(notes), units=units_of(circuit.drive))
