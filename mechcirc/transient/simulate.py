"""Transients of a circuit: drive waveforms, exact linear propagation, clearances.

Linear circuits: ż = A z + B u is propagated exactly between the samples of
the drive, with u taken piecewise linear (first-order hold):

    z_{k+1} = Φ z_k + Γ₁ u_k + Γ₂ (u_{k+1} − u_k),

Φ, Γ₁, Γ₂ from one matrix exponential of the augmented matrix
[[A h, B h, 0], [0, 0, 1], [0, 0, 0]] (``scipy.linalg.expm``).  The only error
is the drive's interpolation between samples, bounded by h²/8 · max|ü|,
estimated from the second differences of the samples and reported.  The
recurrence runs in blocks of L steps with precomputed powers Φʲ, so its cost
is a few matrix products instead of one Python step per sample.

Circuits with clearances integrate with the embedded Dormand–Prince 5(4) loop
of :mod:`mechcirc.transient._kernels` (contacts evaluated inside the
right-hand side, steps ending on every output time); its error is estimated
by the same run with a 100× tighter tolerance.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.linalg as la

from ..circuit import Circuit
from ..errors import MechcircError
from .model import StateSpace, backlash_elements, state_space

__all__ = ["Waveform", "TransientResult", "transient", "parse_drive", "MAX_SAMPLES"]

#: Most output samples of one run (each node's x and v are kept for every one).
MAX_SAMPLES = 2_000_000


@dataclass(frozen=True)
class Waveform:
    """A drive waveform, in units of the drive's amplitude (multiplied by it).

    ``kind``: ``"rest"`` (0), ``"harmonic"`` (sin ω t), ``"step"`` (1 for t ≥ 0),
    ``"impulse"`` (a unit-area pulse at t = 0: momentum for a force drive, a
    displacement step of amplitude × 1 s for a velocity drive), ``"samples"``
    (``times``, ``values``: linear interpolation, held beyond the ends; values
    are absolute, not scaled) or ``"callable"`` (``func(t)``, absolute).
    """

    kind: str
    omega: float = 0.0
    times: tuple = ()
    values: tuple = ()
    func: Callable | None = field(default=None, compare=False)

    def sample(self, t: np.ndarray, amplitude: float) -> np.ndarray:
        if self.kind in ("rest", "impulse"):
            return np.zeros_like(t)
        if self.kind == "harmonic":
            return amplitude * np.sin(self.omega * t)
        if self.kind == "step":
            return np.full_like(t, amplitude)
        if self.kind == "samples":
            return np.interp(t, np.asarray(self.times), np.asarray(self.values))
        if self.kind == "callable":
            out = np.asarray(self.func(t), dtype=float)
            if out.shape != t.shape:
                out = np.array([float(self.func(float(s))) for s in t])
            if not np.all(np.isfinite(out)):
                raise MechcircError("the drive function returned a non-finite value")
            return out
        raise ValueError(f"unknown waveform kind {self.kind!r}")


def parse_drive(text: str | None) -> Waveform:
    """``harmonic:OMEGA`` | ``step`` | ``impulse`` | ``csv:PATH`` | ``rest`` (or None) → Waveform."""
    if text is None or text == "rest":
        return Waveform("rest")
    if text in ("step", "impulse"):
        return Waveform(text)
    if text.startswith("harmonic:"):
        from ..units import OMEGA_UNITS  # noqa: F401  (units accepted as in --omega-*)
        from ..units import parse_omega

        try:
            omega = parse_omega(text[len("harmonic:"):])
        except Exception as exc:  # noqa: BLE001 - reported as a user error
            raise MechcircError(f"--drive {text!r}: {exc}") from None
        if not (math.isfinite(omega) and omega > 0):
            raise MechcircError(f"--drive {text!r}: ω must be a finite number > 0 [rad/s]")
        return Waveform("harmonic", omega=omega)
    if text.startswith("csv:"):
        return read_csv_drive(text[4:])
    raise MechcircError(f"--drive {text!r} is not understood; expected harmonic:OMEGA, step, "
                        "impulse, csv:PATH or rest")


def read_csv_drive(path: str) -> Waveform:
    """Drive samples from a CSV file of two columns, time [s] and value (one header line allowed)."""
    from ..sources import read_source

    text = read_source(path, "a CSV file of drive samples (time,value)")
    times, values = [], []
    for lineno, row in enumerate(csv.reader(text.splitlines()), start=1):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if len(row) < 2:
            raise MechcircError(f"{path}:{lineno}: expected two columns time,value, got "
                                f"{len(row)}")
        try:
            t, v = float(row[0]), float(row[1])
        except ValueError:
            if not times and lineno == 1:
                continue                        # a header line
            raise MechcircError(f"{path}:{lineno}: {row[0]!r},{row[1]!r} are not two numbers "
                                "(expected time,value)") from None
        if not (math.isfinite(t) and math.isfinite(v)):
            raise MechcircError(f"{path}:{lineno}: non-finite time or value")
        if times and t <= times[-1]:
            raise MechcircError(f"{path}:{lineno}: time {t:g} is not after the previous "
                                f"{times[-1]:g} (times must increase)")
        times.append(t)
        values.append(v)
    if len(times) < 2:
        raise MechcircError(f"{path}: needs at least two samples (time,value)")
    return Waveform("samples", times=tuple(times), values=tuple(values))


@dataclass
class TransientResult:
    """The transient on the time grid ``time`` [s] (plain arrays; picklable).

    ``x``, ``v``: node displacements [m or rad] and velocities, shape (nt, n_nodes),
    columns in ``nodes`` order; ``force``, ``dv``: every element's force [N] and
    velocity difference v(n1) − v(n2), shape (nt, n_elements), columns in
    ``elements`` order; ``drive_force`` (velocity drive) or ``drive_velocity``
    (force drive) [nt] or None; ``drive`` the drive's value u(t) [nt] (None
    without a drive); ``error`` an estimate of the largest error of ``x``
    [same unit] and ``notes`` what the run had to say.
    """

    time: np.ndarray
    nodes: tuple
    x: np.ndarray
    v: np.ndarray
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

    def node(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(x, v) of node ``name``."""
        i = self.nodes.index(name)
        return self.x[:, i], self.v[:, i]

    def element_force(self, name: str) -> np.ndarray:
        """Force [N] through element ``name`` (n1 → n2)."""
        return self.force[:, self.elements.index(name)]

    def to_json(self) -> dict:
        """The ``--json`` document (issue 12 §4)."""
        doc = {"time": self.time,
               "nodes": {n: {"x": self.x[:, i], "v": self.v[:, i]}
                         for i, n in enumerate(self.nodes)},
               "elements": {e: {"force": self.force[:, j], "dv": self.dv[:, j]}
                            for j, e in enumerate(self.elements)},
               "drive": ({"force": self.drive_force} if self.drive_force is not None else
                         {"velocity": self.drive_velocity} if self.drive_velocity is not None
                         else {}),
               "error": self.error, "method": self.method, "notes": list(self.notes)}
        return doc

    def write_csv(self, fh) -> None:
        """Columns: t, x(node), v(node) for each node, F(element) for each element, drive."""
        header = ["t"] + [f"x({n})" for n in self.nodes] + [f"v({n})" for n in self.nodes] \
            + [f"F({e})" for e in self.elements]
        cols = [self.time, *self.x.T, *self.v.T, *self.force.T]
        if self.drive_force is not None:
            header.append("F(drive)")
            cols.append(self.drive_force)
        elif self.drive_velocity is not None:
            header.append("v(drive)")
            cols.append(self.drive_velocity)
        fh.write(",".join(header) + "\n")
        data = np.column_stack(cols)
        np.savetxt(fh, data, delimiter=",", fmt="%.12g")

    def plot(self, ax=None, nodes=None, what: str = "x"):
        """Plot x (or v) of ``nodes`` (default all, at most 8) against time; returns the axes."""
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots(figsize=(8, 4.5))
        names = list(nodes) if nodes is not None else list(self.nodes)[:8]
        data = self.x if what == "x" else self.v
        for n in names:
            ax.plot(self.time, data[:, self.nodes.index(n)], label=f"{what}({n})")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("displacement" if what == "x" else "velocity")
        ax.set_title(f"{self.name}: transient")
        ax.grid(True, alpha=0.3)
        if names:
            ax.legend(loc="best", fontsize="small")
        return ax


def _grid(t_end: float, dt: float | None, waveform: Waveform) -> np.ndarray:
    if not (math.isfinite(t_end) and t_end > 0):
        raise MechcircError(f"--t-end must be a finite time > 0 [s], got {t_end:g}")
    if dt is None:
        dt = t_end / 2000
        if waveform.kind == "harmonic":
            dt = min(dt, 2 * math.pi / waveform.omega / 40)
    if not (math.isfinite(dt) and dt > 0):
        raise MechcircError(f"--dt must be a finite time > 0 [s], got {dt:g}")
    n = int(round(t_end / dt))
    if n + 1 > MAX_SAMPLES:
        raise MechcircError(f"t_end/dt = {n} samples, the limit is {MAX_SAMPLES}; "
                            "give a larger --dt or a shorter --t-end")
    n = max(n, 1)
    return np.linspace(0.0, n * dt, n + 1)


def transient(circuit: Circuit, t_end: float, dt: float | None = None,
              drive: Waveform | str | Callable | None = None, *,
              amplitude: float | None = None, linearise: bool = False,
              rtol: float = 1e-9) -> TransientResult:
    """Integrate ``circuit`` from its ``.ic`` state over [0, t_end] on a grid of step ``dt``.

    Parameters
    ----------
    circuit : Circuit
        Any circuit (a drive is optional).
    t_end, dt : float
        End time and output step [s] (dt default: t_end/2000, and at least 40
        samples per period of a harmonic drive).
    drive : Waveform, str, callable or None
        The drive's waveform (see :class:`Waveform` and :func:`parse_drive`);
        None keeps the drive at rest (velocity drive held, force drive off).
    amplitude : float
        Scales the harmonic, step and impulse waveforms (default: the drive's
        amplitude in the netlist).
    linearise : bool
        Take every clearance as closed (the frequency domain's reading).
    rtol : float
        Relative tolerance of the clearance integrator (ignored when linear).
    """
    if callable(drive) and not isinstance(drive, Waveform):
        drive = Waveform("callable", func=drive)
    elif not isinstance(drive, Waveform):
        drive = parse_drive(drive)
    d = circuit.drive
    notes = []
    if d is None and drive.kind != "rest":
        raise MechcircError(f"the netlist has no drive line, so --drive {drive.kind} has "
                            "nothing to act on (add 'drive NAME N1 N2 force=F0')")
    amp = (d.amplitude if d is not None else 0.0) if amplitude is None else float(amplitude)
    t = _grid(t_end, dt, drive)
    h = t[1] - t[0]
    ss = state_space(circuit, linearise=linearise)
    notes.extend(ss.initial[1])
    u = drive.sample(t, amp)
    z0 = ss.initial[0].copy()
    if drive.kind == "impulse":
        if ss.kind == "force":
            z0 = z0 + ss.inject * amp
        else:
            z0[-1] += amp * 1.0         # velocity impulse of area amp·1 s: X jumps
    if drive.kind == "step" and ss.kind == "velocity":
        notes.append("a velocity step makes the drive's nodes jump in velocity: the force "
                     "through the drive has an impulse at t = 0 that samples cannot show")
    interp = _interpolation_error(u, drive)
    has_clear = bool(backlash_elements(circuit)) and not linearise
    if has_clear:
        Z, method, err = _nonlinear(ss, circuit, z0, t, u, rtol)
    else:
        Z = _propagate(ss.A, ss.B, z0, u, h)
        method, err = "exact (matrix exponential, first-order hold of the drive)", 0.0
    if interp > 0:
        notes.append(f"drive interpolated linearly between samples: its error is at most "
                     f"{interp:.3g} (h²/8·max|ü|, from the samples' second differences)")
    return _outputs(ss, circuit, t, Z, u, h, drive, method, err, interp, notes)


def _interpolation_error(u: np.ndarray, drive: Waveform) -> float:
    if drive.kind in ("rest", "step", "impulse") or u.size < 3:
        return 0.0
    return float(np.abs(np.diff(u, 2)).max() / 8.0)


def discretise(A: np.ndarray, B: np.ndarray, h: float):
    """(Φ, Γ₁, Γ₂) of the first-order hold: z⁺ = Φ z + Γ₁ u + Γ₂ (u⁺ − u)."""
    N = A.shape[0]
    big = np.zeros((N + 2, N + 2))
    big[:N, :N] = A * h
    big[:N, N] = B * h
    big[N, N + 1] = 1.0
    E = la.expm(big)
    return E[:N, :N], E[:N, N], E[:N, N + 1]


def _propagate(A, B, z0, u, h, block: int = 64) -> np.ndarray:
    """All states z_k, k = 0..nt−1, of the FOH recurrence, in blocks of ``block`` steps."""
    N = A.shape[0]
    nt = u.size
    Z = np.empty((nt, N))
    if N == 0:
        return Z
    Phi, G1, G2 = discretise(A, B, h)
    L = max(1, min(block, nt - 1))
    P = np.empty((L + 1, N, N))
    P[0] = np.eye(N)
    for j in range(1, L + 1):
        P[j] = P[j - 1] @ Phi
    # Input responses h_m = Φ^m Γ, and the drive as (u_k, u_{k+1} − u_k) per step.
    H1 = P[:L] @ G1
    H2 = P[:L] @ G2
    nb = -(-(nt - 1) // L)
    pad = nb * L + 1
    up = np.empty(pad)
    up[:nt] = u
    up[nt:] = u[-1]
    du = np.diff(up)
    ub = up[:-1].reshape(nb, L)
    dub = du.reshape(nb, L)
    # Forced part inside a block: F[b, j] = Σ_{i<j} h[j−1−i] w[b, i], j = 1..L.
    idx = np.arange(L)
    lag = idx[:, None] - 1 - idx[None, :]                 # (j−1) − i for j = 1..L rows
    jj = np.arange(1, L + 1)
    lag = (jj[:, None] - 1) - idx[None, :]
    mask = lag >= 0
    T1 = np.where(mask[..., None], H1[np.clip(lag, 0, L - 1)], 0.0)   # (L, L, N)
    T2 = np.where(mask[..., None], H2[np.clip(lag, 0, L - 1)], 0.0)
    F = np.einsum("jin,bi->bjn", T1, ub) + np.einsum("jin,bi->bjn", T2, dub)   # (nb, L, N)
    starts = np.empty((nb, N))
    z = z0.astype(float).copy()
    PL = P[L]
    for b in range(nb):
        starts[b] = z
        z = PL @ z + F[b, -1]
    full = np.einsum("jmn,bn->bjm", P[1:], starts) + F                    # steps 1..L
    Z[0] = z0
    Z[1:] = full.reshape(nb * L, N)[:nt - 1]
    return Z


def _nonlinear(ss: StateSpace, circuit, z0, t, u, rtol):
    from . import _kernels as kern

    clear = backlash_elements(circuit)
    index = {n: i for i, n in enumerate(ss.nodes)}
    E = len(clear)
    N = ss.size
    cx = np.zeros((E, N))
    dx = np.zeros(E)
    cv = np.zeros((E, N))
    dv = np.zeros(E)
    prm = np.zeros((E, 3))
    for k, (e, comp) in enumerate(clear):
        ge = np.zeros(len(ss.nodes))
        if e.n1 in index:
            ge[index[e.n1]] += 1.0
        if e.n2 in index:
            ge[index[e.n2]] -= 1.0
        cx[k], dx[k] = ge @ ss.Cx, ge @ ss.Dx
        cv[k], dv[k] = ge @ ss.Cv, ge @ ss.Dv
        damping = comp.value * comp.eta if comp is not None else e.damping * e.eta
        prm[k] = (e.value * e.eta, damping, e.backlash)
    h = t[1] - t[0]
    args = (np.ascontiguousarray(ss.A), np.ascontiguousarray(ss.B), cx, dx, cv, dv,
            np.ascontiguousarray(ss.extra), prm, np.ascontiguousarray(u))

    def run(tol):
        out = np.empty((t.size, N))
        z = z0.astype(float).copy()
        scale = max(np.abs(z0).max(), 1e-300)
        atol = tol * scale if np.abs(z0).max() > 0 else tol
        steps = kern.dopri_run(z, 0.0, h, t.size, *args[:8], args[8], tol, atol, h,
                               kern._A, kern._B5, kern._B4, kern._C, out)
        if steps < 0:
            raise MechcircError("the clearance integrator's step fell below 1e-14 s "
                                "(the network is too stiff for it)")
        return out

    Z = run(rtol)
    Z2 = run(rtol / 100)
    xs1 = Z @ ss.Cx.T
    xs2 = Z2 @ ss.Cx.T
    err = float(np.abs(xs1 - xs2).max())
    backend = "numba" if kern.HAVE_NUMBA else "Python"
    return Z2, f"Dormand-Prince 5(4), rtol {rtol / 100:g} ({backend}); clearances in the RHS", err


def _outputs(ss, circuit, t, Z, u, h, drive, method, err, interp, notes) -> TransientResult:
    udot = np.gradient(u, h) if u.size > 1 else np.zeros_like(u)
    X = Z @ ss.Cx.T + np.outer(u, ss.Dx)
    V = Z @ ss.Cv.T + np.outer(u, ss.Dv) + np.outer(udot, ss.Ev)
    clear = {e.name: (e, comp) for e, comp in backlash_elements(circuit)} if ss.extra is not None else {}
    comp_of = {comp.name: e.name for e, comp in clear.values() if comp is not None}
    index = {n: i for i, n in enumerate(ss.nodes)}
    need_acc = any(e.kind == "mass" for e in circuit.elements) or ss.h is not None
    if need_acc:
        Zdot = Z @ ss.A.T + np.outer(u, ss.B)
        Acc = Zdot @ ss.Cv.T + np.outer(udot, ss.Dv)

    def diff(Y, e):
        out = np.zeros(Y.shape[0])
        if e.n1 in index:
            out = out + Y[:, index[e.n1]]
        if e.n2 in index:
            out = out - Y[:, index[e.n2]]
        return out

    names, forces, dvs = [], [], []
    law_cache = {}
    for e in circuit.elements:
        dve = diff(V, e)
        if e.name in clear or e.name in comp_of:
            sp = clear[e.name][0] if e.name in clear else clear[comp_of[e.name]][0]
            if sp.name not in law_cache:
                law_cache[sp.name] = _law_forces(sp, clear[sp.name][1], diff(X, sp), diff(V, sp))
            total, spring = law_cache[sp.name]
            f = spring if e.name == sp.name else total - spring
        elif e.kind == "mass":
            f = e.value * e.eta * diff(Acc, e)
        elif e.kind == "spring":
            f = e.value * e.eta * diff(X, e)
        else:
            f = e.value * e.eta * dve
        names.append(e.name)
        forces.append(f)
        dvs.append(dve)
    force = np.column_stack(forces) if forces else np.zeros((t.size, 0))
    dvm = np.column_stack(dvs) if dvs else np.zeros((t.size, 0))
    drive_force = drive_velocity = None
    if ss.kind is not None:
        r = Acc @ ss.M.T + V @ ss.D.T + X @ ss.K.T
        for name, (e, comp) in clear.items():
            ge = np.zeros(len(ss.nodes))
            if e.n1 in index:
                ge[index[e.n1]] += 1.0
            if e.n2 in index:
                ge[index[e.n2]] -= 1.0
            r += np.outer(law_cache[name][0], ge)
        Q = r @ ss.h
        if ss.kind == "velocity":
            drive_force = Q
        else:
            drive_velocity = V @ ss.g
    if ss.Ev.any() and drive.kind not in ("rest", "impulse"):
        notes.append("some nodes carry neither mass nor damping: their velocities use the "
                     "drive's derivative estimated from the samples")
    scale = float(np.abs(X).max()) if X.size else 0.0
    err_total = err
    return TransientResult(time=t, nodes=ss.nodes, x=X, v=V, elements=tuple(names), force=force,
                           dv=dvm, drive_kind=ss.kind,
                           drive=u if ss.kind is not None else None,
                           drive_force=drive_force, drive_velocity=drive_velocity,
                           error=err_total, method=method, notes=notes, name=circuit.name)


def _law_forces(spring, comp, e, w):
    from . import _kernels as kern

    c = spring.value * spring.eta
    d = comp.value * comp.eta if comp is not None else spring.damping * spring.eta
    total = np.empty(e.size)
    part = np.empty(e.size)
    kern.law_many(np.ascontiguousarray(e), np.ascontiguousarray(w), c, d, spring.backlash,
                  total, part)
    return total, part
