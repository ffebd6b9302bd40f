"""The sley models linearised at a crank angle θ0: matrices, eigenfrequencies, netlist.

Frozen-coefficient linearisation of eqs. (4)/(9) about the rigid motion at crank
angle θ0: μ = μ(θ0) is held fixed, the velocity-squared terms I4 μ ν ω2P² and
the beat-up moment are dropped, the clearances are closed (ϕ = 0).  With the
driven shaft φ2 held, the small motions x = (φ2P, [φ5P,] φ4P) obey
M ẍ + C ẋ + K x = 0 with (one side)::

    M = diag(I2P + I4 μ², I4P)
    K = [[C2 + C4 μ², −C4 μ], [−C4 μ, C4]]
    C = [[k2 + k4 μ², −k4 μ], [−k4 μ, k4]]

and, both sides, a third coordinate φ5P with I5P + I7 μ², C5 + C7 μ², rod 7
joining it to the sley like rod 4 (both cranks are at θ0).

This is exactly the mechanical circuit of :func:`to_circuit`: crank inertia
I2P + I4 μ² and the rod C2 ∥ k2 on the crank side, the lever μ (or the sley
side reflected with η = μ²) and the rod C4 ∥ k4 and inertia I4P on the rocker
side.  Its resonances (K = 0 with the drive held) are the eigenfrequencies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..circuit import Circuit, Drive, Element, Lever
from ..sources import real_values, summary_repr
from ..units import convert_frequency
from .models import ParameterError, SleyParameters

__all__ = ["LinearModel", "linearise", "eigenfrequencies", "to_circuit", "to_netlist", "SleyMode"]


@dataclass(frozen=True)
class LinearModel:
    """M ẍ + C ẋ + K x = b φ2(t) + d φ̇2(t): the linearised sley at crank angle θ0.

    Attributes
    ----------
    theta0 : float
        Crank angle of the linearisation [rad].
    mu : float
        μ(θ0) = dφ4/dθ [1].
    M, C, K : ndarray, shape (n, n)
        Inertia [kg·m²], damping [kg·m²/s] and stiffness [N·m/rad] matrices;
        coordinates (φ2P, φ4P) or (φ2P, φ5P, φ4P).
    K_drive, C_drive : ndarray, shape (n,)
        Stiffness and damping coupling of the driven shaft φ2 into each equation
        [N·m/rad], [kg·m²/s].
    names : tuple of str
        Coordinate names.
    """

    __repr__ = summary_repr

    theta0: float
    mu: float
    M: NDArray[np.float64]
    C: NDArray[np.float64]
    K: NDArray[np.float64]
    K_drive: NDArray[np.float64]
    C_drive: NDArray[np.float64]
    names: tuple[str, ...]

    def state_matrix(self) -> NDArray[np.float64]:
        """A of ż = A z for z = (x, ẋ) with the drive held [1/s]."""
        from ..scene.simulation import state_matrix

        return state_matrix(self.M, self.C, self.K)

    def receptance(self, omega) -> NDArray[np.complex128]:
        """Complex amplitude X(ω)/Φ2 of each coordinate for φ2 = Φ2 e^{jωt}, shape (len(omega), n)."""
        w = np.atleast_1d(np.asarray(omega, dtype=float)).reshape(-1, 1, 1)
        dyn = -w * w * self.M + 1j * w * self.C + self.K
        x = np.linalg.solve(dyn, (self.K_drive + 1j * w[:, 0] * self.C_drive)[..., None])
        return np.asarray(x[..., 0], dtype=np.complex128)

    def drive_moment(self, omega) -> NDArray[np.complex128]:
        """Moment the driven shaft must supply, per unit shaft *velocity* amplitude [N·m·s/rad].

        Q0/V0 in the mechanical-circuit sense: for φ̇2 = V0 e^{jωt} the rod
        C2 ∥ k2 carries Q = (C2/(jω) + k2)(V0 − jω X2P) (plus rod C5 ∥ k5 for
        both sides); returns Q / V0 = 1/K.
        """
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        x = self.receptance(omega)                # coordinates per unit φ2 amplitude
        q = np.zeros(omega.size, dtype=complex)
        for i in np.flatnonzero(self.K_drive):    # every rod that the shaft drives
            q += (self.K_drive[i] / (1j * omega) + self.C_drive[i]) * (1.0 - x[:, i])
        return q


@dataclass(frozen=True)
class SleyMode:
    """One mode of the linearised sley: its undamped frequency and its damped eigenvalue.

    Not a :class:`mechcirc.modes.Mode` (a root of K with its shape, energies and
    sensitivities) and not a :class:`mechcirc.resonances.Resonance`: its
    ``omega_n`` is the frequency of the undamped problem K v = ω² M v (the
    dampers removed), while ``Resonance.omega`` is |s| of the damped root,
    here ``abs(eigenvalue)``; the two differ by up to 0.23 % over the 14
    presets and the crank circle.

    Attributes
    ----------
    omega_n : float
        Undamped natural frequency [rad/s] (from M, K only).
    omega_d : float
        Damped natural frequency, imaginary part of the eigenvalue [rad/s].
    zeta : float
        Damping ratio −Re λ / |λ| [1].
    eigenvalue : complex
        λ of ż = A z [1/s].
    """

    omega_n: float
    omega_d: float
    zeta: float
    eigenvalue: complex

    @property
    def f_hz(self) -> float:
        """Undamped natural frequency [Hz]."""
        return convert_frequency(self.omega_n, "rad/s", "Hz")


def _mck(p: SleyParameters, mu):
    """Stacked M, C, K [kg·m², kg·m²/s, N·m/rad], shape (len(mu), n, n), and drive couplings.

    Each crank side (I_crank, I_rod, C_crank, C_rod, k_crank, k_rod) adds its crank's
    coordinate, joined by its rod (the lever μ) to the sley's, the last.
    """
    mu = np.atleast_1d(np.asarray(mu, dtype=float))
    m2 = mu * mu
    sides = _sides(p)
    n = len(sides) + 1
    M, C, K = np.zeros((3, mu.size, n, n))
    M[:, -1, -1] = p.I4P
    for i, (inertia, i_rod, c, c_rod, k, k_rod) in enumerate(sides):
        M[:, i, i] = inertia + i_rod * m2
        for A, crank, rod in ((K, c, c_rod), (C, k, k_rod)):
            A[:, i, i] = crank + rod * m2
            A[:, i, -1] = A[:, -1, i] = -rod * mu
            A[:, -1, -1] += rod
    kd = np.array([side[2] for side in sides] + [0.0])
    cd = np.array([side[4] for side in sides] + [0.0])
    return M, C, K, kd, cd


def _sides(p: SleyParameters) -> list:
    """Each crank side's (I_crank, I_rod, C_crank, C_rod, k_crank, k_rod): crank 2P with
    rocker 4, and on both sides crank 5P with rocker 7."""
    return [(p.I2P, p.I4, p.C2, p.C4, p.k2, p.k4)] + \
        ([p.second_side()] if p.drive == "both-sides" else [])


def linearise(params: SleyParameters, theta0: float, *, mu: float | None = None) -> LinearModel:
    """The frozen-coefficient linear model of ``params`` at crank angle ``theta0`` [rad].

    ``mu`` overrides μ(θ0).

    Parameters
    ----------
    params : SleyParameters
        The sley whose equations of motion (4) or (9) are linearised.
    theta0 : float
        Crank angle [rad] of the rigid motion about which they are linearised.
    mu : float, optional
        Transmission ratio μ used instead of μ(θ0).

    Returns
    -------
    LinearModel
        M, C, K and the drive's coefficients at θ0.
    """
    theta0 = _angle(theta0)
    mu = float(params.fourbar().transfer(theta0)[1]) if mu is None else \
        float(real_values(mu, "mu", "1", ParameterError))
    M, C, K, kd, cd = _mck(params, mu)
    names = ("phi2P", "phi4P") if params.drive == "one-side" else ("phi2P", "phi5P", "phi4P")
    return LinearModel(float(theta0), float(mu), M[0], C[0], K[0], kd, cd, names)


def eigenfrequencies(params: SleyParameters, theta0: float) -> list[SleyMode]:
    """Modes of the linearised model at ``theta0`` [rad], ascending in ω_n.

    Undamped ω_n from the generalised symmetric eigenproblem K v = ω² M v; the
    damped eigenvalues λ from the state matrix, paired with ω_n in order.

    Parameters
    ----------
    params : SleyParameters
        The sley whose modes are sought.
    theta0 : float
        Crank angle [rad] at which it is linearised (:func:`linearise`).

    Returns
    -------
    list of SleyMode
        The modes, ascending in ω_n.
    """
    from scipy.linalg import eigh

    lin = linearise(params, theta0)
    w2 = eigh(lin.K, lin.M, eigvals_only=True)
    omega_n = np.sqrt(np.clip(w2, 0.0, None))
    lam = np.linalg.eigvals(lin.state_matrix())
    lam = lam[lam.imag > 0] if np.count_nonzero(lam.imag > 0) == len(omega_n) else \
        np.sort_complex(lam)[-len(omega_n):]
    lam = lam[np.argsort(np.abs(lam))]
    return [SleyMode(float(wn), float(lm.imag), float(-lm.real / abs(lm)), complex(lm))
            for wn, lm in zip(np.sort(omega_n), lam)]


def to_circuit(params: SleyParameters, theta0: float, *, lever: bool = False,
               damping: bool = True, velocity: float | None = None) -> Circuit:
    """The mechanical circuit of the linearised sley at ``theta0`` [rad], built as objects.

    Mobility analogy, rotational reading (inertia [kg·m²] as ``mass``, torsional
    rigidity [N·m/rad] as ``spring``, torsional damping [kg·m²/s] as ``damper``).
    Node 0 is the frame, node ``shaft`` the driven crank shaft (the ``drive``,
    velocity ω), ``crank`` the crank 2P beyond rod C2 ∥ k2 with inertia
    I2P + I4 μ² to the frame.  The rocker side (rod C4 ∥ k4 to the sley
    inertia I4P) hangs either behind an ideal ``lever`` of ratio |μ(θ0)|
    (``lever=True``) or directly on the crank node with every element
    reflected through ``eta = μ²`` (default; series-parallel, no lever
    needed).  Both sides adds ``shaft``→``crank5`` (C5 ∥ k5, I5P + I7 μ²) and rod
    7 from crank 5 to the same sley.

    Parameters
    ----------
    params : SleyParameters
        The sley whose linearised model the circuit is.
    theta0 : float
        Crank angle [rad] of the linearisation; μ(θ0) sets the lever ratio |μ| or η = μ².
    lever : bool
        Use a ``lever`` element instead of η reflection.
    damping : bool
        Include the dampers k2, k4 (, k5, k7).
    velocity : float, optional
        Drive velocity amplitude [rad/s]; default ``params.omega``.

    Returns
    -------
    Circuit
        Named ``sley``, source ``<sley LABEL>`` (the label or the drive).

    Raises
    ------
    ParameterError
        ``theta0`` is a dead centre (μ = 0: the sley is decoupled from the drive).

    Notes
    -----
    With ``lever=False`` the two-sided circuit is a bridge (the sley joins two
    branches), which needs nodal analysis; the one-sided one is series-parallel.
    """
    p = params
    mu = _coupling(p, theta0)
    mu2 = mu * mu
    v = p.omega if velocity is None else real_values(velocity, "velocity", "rad/s", ParameterError)
    elements: list = []
    levers = []
    for (a, b, crank, rocker), (inertia, i_rod, c, c_rod, k, k_rod) in zip(
            (("2", "4", "crank", "rocker"), ("5", "7", "crank5", "rocker7")), _sides(p)):
        elements += _rod(a, "shaft", crank, c, k, 1.0, damping)
        elements.append(Element("mass", f"J{a}", crank, "0", inertia + i_rod * mu2))
        levers += [Lever(f"L{b}", crank, "0", rocker, "0", abs(mu))] if lever else []
        elements += _rod(b, rocker if lever else crank, "sley", c_rod, k_rod,
                         1.0 if lever else mu2, damping)
    elements.append(Element("mass", "I4P", "sley", "0", p.I4P, 1.0 if lever else mu2))
    return Circuit(tuple(elements),
                   Drive("V", "shaft", "0", "velocity", float(v), rotational=True),
                   tuple(levers), name="sley", source=f"<sley {p.label or p.drive}>")


def _rod(tag: str, a: str, b: str, c: float, k: float, eta: float, damping: bool) -> list:
    """Rod ``tag``: rigidity C ∥ damping k (with ``damping`` and k > 0) between nodes
    a and b, reflected through ``eta``."""
    out = [Element("spring", f"C{tag}", a, b, c, eta)]
    if damping and k > 0:
        out.append(Element("damper", f"k{tag}", a, b, k, eta))
    return out


def to_netlist(params: SleyParameters, theta0: float, *, lever: bool = False,
               damping: bool = True, velocity: float | None = None) -> str:
    """:func:`to_circuit` as netlist text (:func:`mechcirc.netlist_writer.write`).

    The same parameters and errors as :func:`to_circuit`; the text starts with
    comments giving θ0, μ(θ0) and how the rocker side is reflected, and
    ``mechcirc.parse`` of it gives the same circuit.

    Parameters
    ----------
    params, theta0, lever, damping, velocity
        As :func:`to_circuit`.

    Returns
    -------
    str
        The netlist text.
    """
    from ..netlist_writer import write

    circuit = to_circuit(params, theta0, lever=lever, damping=damping, velocity=velocity)
    mu = _coupling(params, theta0)
    how = (f"rocker side behind levers of ratio |mu| = {abs(mu)!r}" if lever else
           f"rocker side reflected with eta = mu^2 = {mu * mu!r}")
    return write(circuit, (f"Mrázek sley ({params.drive}), linearised at crank angle "
                           f"{math.degrees(theta0):.6g} deg; mu = {mu!r}", how))


def _coupling(p: SleyParameters, theta0: float) -> float:
    """μ(θ0) [1], refused at a dead centre."""
    theta0 = _angle(theta0)
    mu = float(p.fourbar().transfer(theta0)[1])
    if abs(mu) < 1e-9:
        raise ParameterError(
            f"at crank angle {math.degrees(theta0):.6g} deg the four-bar is at a dead centre "
            f"(mu = {mu:.3g}): the sley is decoupled from the drive and the circuit would "
            "be singular; choose a crank angle away from the dead centres")
    return mu


def _angle(theta0) -> float:
    """``theta0`` [rad] as a float; a :class:`ParameterError` naming it if it is no finite number."""
    return float(real_values(theta0, "theta0", "rad", ParameterError))
