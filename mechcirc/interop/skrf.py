"""scikit-rf networks and Touchstone files for mechanical mobilities.

A mechanical circuit's kinematic characteristic K = v/Q [m/(N·s)] is a
*mobility*: in the mobility analogy (force ↔ current, velocity ↔ voltage) it
plays the part of an impedance.  scikit-rf's Z parameters therefore carry K
unchanged, but their unit is m/(N·s), **not ohms**: every network and file
written here says so in its name and comments.

Touchstone files are written as Z parameters (``# Hz Z RI R <R>``).  The
reference R [m/(N·s)] is a power of two near the typical |K| of the data:
dividing by it is exact, so the file holds K/R without rounding, and the S
parameters scikit-rf stores internally ((Z − R)/(Z + R)) stay well
conditioned, so that ``skrf.Network(path).z`` gives K back to about 1e-13
relative.  With a reference of 1 (or scikit-rf's default 50 Ω) a mobility of
1e-8 m/(N·s) would come back with only ~8 correct digits.

Frequencies: Touchstone and scikit-rf work in hertz, f = ω/(2π); mechcirc's
ω is in rad/s.  Points where K is not finite (ω = 0 for a mass, exact poles)
cannot be written; they are left out and counted.

scikit-rf is imported inside the functions, so ``import mechcirc`` stays fast.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import MechcircError, TopologyError, did_you_mean
from ..units import in_unit
from .touchstone import read_touchstone_one_port

if TYPE_CHECKING:  # pragma: no cover
    from ..circuit import Circuit
    from .._sweep import Method, Sweep

__all__ = ["to_skrf", "two_port", "two_port_z", "write_touchstone", "read_mobility",
           "compare", "Comparison", "reference_mobility", "MOBILITY_NOTE"]

#: The sentence every network and file carries about its unit (``{unit}``: m/(N*s), or
#: rad/(N*m*s) for a rotary drive).
MOBILITY_NOTE = ("mechanical mobility K = v/Q in {unit} (mobility analogy: force ~ current, "
                 "velocity ~ voltage), NOT ohms")


def reference_mobility(Z: ArrayLike) -> float:
    """A power of two [m/(N·s)] near the geometric mean of the finite nonzero |Z|.

    Used as the Touchstone/S-parameter reference: division by it is exact.

    Parameters
    ----------
    Z : array_like
        Mobilities [m/(N·s)].

    Returns
    -------
    float
        1.0 when no |Z| is finite and nonzero.
    """
    mag = np.abs(np.asarray(Z))
    mag = mag[np.isfinite(mag) & (mag > 0)]
    return float(2.0 ** round(float(np.mean(np.log2(mag))))) if mag.size else 1.0


def _kept(omega, Z, R, empty: str):
    """The points with ω > 0 and finite Z (a mask), the reference mobility (``R``, else
    :func:`reference_mobility` of those points) and how many points are left out;
    ``empty`` is the error's message when none is kept."""
    keep = np.isfinite(omega) & (omega > 0) & np.isfinite(Z).reshape(Z.shape[0], -1).all(axis=1)
    if not keep.any():
        raise MechcircError(empty)
    return keep, reference_mobility(Z[keep]) if R is None else float(R), int((~keep).sum())


def to_skrf(sweep: "Sweep", *, z0: float | None = None):
    """The sweep's K(ω) as a one-port ``skrf.Network`` of Z parameters.

    Parameters
    ----------
    sweep : Sweep
    z0 : float, optional
        Reference mobility [m/(N·s)] for scikit-rf's S parameters; by default
        a power of two near the typical |K| (see the module docstring).

    Returns
    -------
    skrf.Network
        ``network.z[:, 0, 0]`` is K [m/(N·s)] at f = ω/(2π) [Hz].  Points
        where K is not finite (or ω ≤ 0) are left out; ``network.comments``
        states the unit and how many points were dropped.
    """
    return _network(np.asarray(sweep.omega, dtype=float),
                    np.asarray(sweep.K, dtype=complex).reshape(-1, 1, 1), z0, sweep.name,
                    f"{sweep.name} mobility K [{_ascii(sweep.units['K'])}]",
                    "no sweep point has ω > 0 and a finite K; nothing to convert",
                    unit=_ascii(sweep.units["K"]))


def _network(omega, Z, z0, name: str, title: str, empty: str, extra: tuple = (),
             unit: str = "m/(N*s)"):
    """The points of Z(ω) with ω > 0 and finite Z as an ``skrf.Network`` called ``title``,
    with the unit's comments (and the lines ``extra``); ``empty`` is the error's
    message when there is none."""
    import skrf

    keep, R, dropped = _kept(omega, Z, z0, empty)
    comments = [*_comments(name, dropped, R, unit), *extra]
    freq = skrf.Frequency.from_f(in_unit(omega[keep], "Hz"), unit="hz")
    return skrf.Network.from_z(Z[keep], frequency=freq, z0=R, name=title,
                               comments="\n".join(comments))


def _ascii(unit: str) -> str:
    """A unit label as Touchstone's ASCII comments write it: rad/(N·m·s) → rad/(N*m*s)."""
    return unit.replace("·", "*")


def _comments(name: str, dropped: int, R: float, unit: str) -> list[str]:
    return [f"mechcirc: {name}", MOBILITY_NOTE.format(unit=unit),
            f"reference R = {R!r} {unit} (a power of two, for precision); "
            "frequency f = omega/(2*pi) in Hz"] + \
        ([f"{dropped} point(s) with omega <= 0 or a non-finite K left out"] if dropped else [])


def write_touchstone(path: str | os.PathLike, omega: ArrayLike, Z: ArrayLike, *,
                     name: str = "circuit", R: float | None = None,
                     unit: str = "m/(N*s)") -> int:
    """Write Z parameters [m/(N·s)] over ``omega`` [rad/s] as a Touchstone v1 file.

    ``Z`` has shape (n,) for a one-port or (n, p, p) for a p-port; the file
    should be named ``.s1p``/``.s2p`` accordingly.  Values are written as K/R
    with 17 significant digits (exact: R is a power of two).  Returns the
    number of points left out because ω ≤ 0 or Z is not finite.

    Written atomically (temporary file, then rename).

    Parameters
    ----------
    path : str or PathLike
    omega : array_like
        ω [rad/s], shape (n,).
    Z : array_like
        Shape (n,) or (n, p, p) [m/(N·s)].
    name : str
        The file's comment line.
    R : float, optional
        Reference mobility (:func:`reference_mobility` when None).
    unit : str
        The unit of Z named in the comments (ASCII: ``"rad/(N*m*s)"`` for a rotary drive).

    Returns
    -------
    int
        Points left out.
    """
    from ..outputs import atomic_open

    omega = np.asarray(omega, dtype=float)
    Z = np.asarray(Z, dtype=complex)
    if Z.ndim == 1:
        Z = Z.reshape(-1, 1, 1)
    keep, R, dropped = _kept(omega, Z, R, "no point has ω > 0 and a finite K; nothing to write")
    p = Z.shape[1]
    with atomic_open(path, "w", encoding="ascii") as fh:
        for line in _comments(name, dropped, R, unit):
            fh.write(f"! {line}\n")
        fh.write(f"# Hz Z RI R {R!r}\n")
        for w, z in zip(omega[keep], Z[keep] / R):
            # Touchstone v1 order: two-ports N11 N21 N12 N22; larger: row by row.
            entries = z.T.ravel() if p == 2 else z.ravel()
            fields = [float(in_unit(w, "Hz"))] + [float(x) for v in entries
                                                  for x in (v.real, v.imag)]
            fh.write(" ".join(map(repr, fields)) + "\n")
    return dropped


#: Read a one-port Touchstone file as ``(omega [rad/s], K [m/(N·s)], name)``: the
#: text parser of :mod:`mechcirc.interop.touchstone` under this module's name, never
#: ``skrf.Network(path)``, which would unpickle a file that is a pickle.
read_mobility = read_touchstone_one_port


# --------------------------------------------------------------------------
# Two-ports
# --------------------------------------------------------------------------

def two_port_z(circuit: "Circuit", P1: str, P2: str, S1: str, S2: str,
               omega: ArrayLike) -> NDArray[np.complex128]:
    """Open-circuit Z parameters [m/(N·s)] of ``circuit`` between ports P1–P2 and S1–S2.

    ``Z[k, i, j]`` is the velocity difference across port i per unit force
    injected at port j (into its first node, out of its second), all other
    ports unloaded (force 0), at ``omega[k]`` [rad/s].  The circuit's drive
    is removed (an ideal force source of zero amplitude): the two-port is the
    passive network of its elements and levers.  Nodal analysis, mobility
    analogy (see :mod:`mechcirc.nodal`); levers enter as in
    :func:`mechcirc.nodal.assemble`.

    Parameters
    ----------
    circuit : Circuit
    P1, P2, S1, S2 : str
        The nodes of port 1 and port 2.
    omega : array_like
        ω [rad/s].

    Returns
    -------
    ndarray of complex, shape (n, 2, 2)

    Raises
    ------
    TopologyError
        If a port node is not in the circuit, the frame ``"0"`` is missing,
        or the network is singular (a part not tied to the frame).
    """
    from ..nodal import assemble, dense_matrices

    # The whole network (assemble(..., whole=True)): the drive's loaded part is
    # not enough, a two-port needs every element, including those reached only
    # from the second port.
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    system = assemble(circuit, whole=True)
    rhs = _port_incidence(circuit, system, P1, P2, S1, S2)
    Z = np.full((omega.size, 2, 2), np.nan, dtype=complex)
    ok = np.isfinite(omega) & (omega > 0)
    if ok.any():
        A = dense_matrices(system, omega[ok])
        for k, i in enumerate(np.flatnonzero(ok)):
            try:
                x = np.linalg.solve(A[k], rhs.T)       # columns: unit force at each port
            except np.linalg.LinAlgError:
                continue                               # exactly singular: NaN
            Z[i] = rhs @ x          # rows of rhs pick v(a) − v(b) of each port
        if np.isnan(Z[ok]).all():
            raise TopologyError("the network is singular at every frequency asked (a part "
                                "not tied to the frame, or levers in parallel)")
    return Z


def _port_incidence(circuit, system, P1, P2, S1, S2) -> NDArray[np.float64]:
    """The (2, n) rows of +1 at each port's first node and −1 at its second among the
    nodal ``system``'s unknowns (the frame has none); a TopologyError for bad ports."""
    from ..circuit import FRAME
    from ..topology import node_names
    from ..transient.model import incidence

    names = set(system.nodes) | set(node_names(circuit.elements, circuit.levers))
    for port in (P1, P2, S1, S2):
        if port not in names:
            raise TopologyError(f"port node {port!r} is not a node of the circuit"
                                f"{did_you_mean(str(port), names)} (nodes: "
                                f"{', '.join(sorted(names))})", nodes=(port,))
    if P1 == P2 or S1 == S2:
        raise TopologyError("each port needs two different nodes", nodes=(P1, P2, S1, S2))
    if FRAME not in names:
        raise TopologyError("the circuit has no frame node '0' to refer velocities to")
    index = {n: i for i, n in enumerate(system.nodes)}      # (no frame: it is not an unknown)
    return np.array([incidence(index, a, b, system.size) for a, b in ((P1, P2), (S1, S2))])


def two_port(circuit: "Circuit", P1: str, P2: str, S1: str, S2: str, omega: ArrayLike, *,
             z0: float | None = None):
    """A two-port ``skrf.Network`` of the circuit's Z parameters [m/(N·s)].

    See :func:`two_port_z` for the conventions; frequencies are f = ω/(2π)
    [Hz].  ``z0`` is the reference mobility of the stored S parameters
    (default: a power of two near the typical |Z|).

    Parameters
    ----------
    circuit, P1, P2, S1, S2, omega
        As :func:`two_port_z`.
    z0 : float, optional
        Reference mobility [m/(N·s)].

    Returns
    -------
    skrf.Network
        The points with ω > 0 and finite Z.
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    return _network(omega, two_port_z(circuit, P1, P2, S1, S2, omega), z0, circuit.name,
                    f"{circuit.name} two-port mobility [m/(N*s)]",
                    "no frequency gives finite Z parameters",
                    (f"port 1: {P1}-{P2}, port 2: {S1}-{S2}; drive removed",))


# --------------------------------------------------------------------------
# Model against measurement
# --------------------------------------------------------------------------

@dataclass(frozen=True)
class Comparison:
    """A measured mobility beside the model's, on the measurement's frequencies.

    Attributes
    ----------
    omega : ndarray, shape (n,)
        Angular frequency [rad/s] of the measured points.
    K_model, K_measured : ndarray of complex, shape (n,)
        Mobilities [m/(N·s)].
    rel_error : ndarray, shape (n,)
        |K_measured − K_model| / |K_model| [1] (inf where K_model = 0).
    db_error : ndarray, shape (n,)
        20·log10(|K_measured| / |K_model|) [dB].
    phase_error_deg : ndarray, shape (n,)
        arg(K_measured / K_model) [deg], in (−180, 180].
    flags : ndarray of int8
        The model sweep's flags (poles and zeros of K).
    """

    omega: NDArray[np.float64]
    K_model: NDArray[np.complex128]
    K_measured: NDArray[np.complex128]
    rel_error: NDArray[np.float64]
    db_error: NDArray[np.float64]
    phase_error_deg: NDArray[np.float64]
    flags: NDArray[np.int8]

    def summary(self) -> dict:
        """Largest, median and RMS errors over the regular (unflagged, finite) points."""
        ok = (self.flags == 0) & np.isfinite(self.rel_error) & np.isfinite(self.db_error)
        out = {"points": int(self.omega.size), "compared": int(ok.sum()),
               "omega_min": float(self.omega.min()), "omega_max": float(self.omega.max())}
        if ok.any():
            rel, db, ph = self.rel_error[ok], self.db_error[ok], self.phase_error_deg[ok]
            worst = int(np.argmax(rel))
            out.update(rel_max=float(rel.max()), rel_median=float(np.median(rel)),
                       omega_at_rel_max=float(self.omega[ok][worst]),
                       db_rms=float(np.sqrt(np.mean(db ** 2))), db_max=float(np.abs(db).max()),
                       phase_max_deg=float(np.abs(ph).max()))
        return out


def compare(circuit: "Circuit", path: str | os.PathLike, *, method: "Method" = "auto",
            omega_min: float | None = None, omega_max: float | None = None) -> Comparison:
    """Evaluate ``circuit`` at the frequencies of a measured one-port Touchstone file.

    ``omega_min`` / ``omega_max`` [rad/s] keep only the measured points in
    that band (a band with no point is an error).

    Parameters
    ----------
    circuit : Circuit
    path : str or PathLike
        The ``.s1p`` file.
    method : {"auto", "sp", "nodal"}
        As :func:`mechcirc.sweep`.
    omega_min, omega_max : float, optional
        The band [rad/s].

    Returns
    -------
    Comparison
        ω, model and measured K, their relative difference, dB and phase, flags.
    """
    omega, K_meas, _ = read_mobility(path)
    lo = 0 if omega_min is None else omega_min          # (the file's ω are ≥ 0)
    hi = math.inf if omega_max is None else omega_max
    keep = (omega >= lo) & (omega <= hi)
    if not keep.any():
        raise MechcircError(f"{os.fspath(path)}: no measured point between {lo:g} and {hi:g} "
                            f"rad/s (the file spans {omega.min():g} .. {omega.max():g} rad/s)")
    omega, K_meas = omega[keep], K_meas[keep]
    result = circuit.sweep(omega, method=method)
    K = result.K
    with np.errstate(all="ignore"):
        rel = np.abs(K_meas - K) / np.abs(K)
        db = 20 * np.log10(np.abs(K_meas) / np.abs(K))
        phase = np.degrees(np.angle(K_meas / K))
    return Comparison(omega, K, K_meas, rel, db, phase, result.flags)
