"""The nodal equations of a mechanical circuit, in the mobility analogy.

Force plays the part of current and velocity that of voltage.  Unknowns are
the velocities of the nodes (the frame is the reference, velocity 0) and one
force per lever.  Each element stamps its admittance S = 1/K between its
nodes, so that the system matrix is

    A(ω) = D + C + j (ω M − Kₛ / ω)

with M the masses (S = jωm·η), Kₛ the springs (S = k·η/(jω)), D the dampers
(S = c·η) and C the constant lever block: a lever of ratio r adds the unknown
Q_S with KCL entries (r at p1, −r at p2, −1 at s1, +1 at s2) and the
constraint row r(v_p1 − v_p2) − (v_s1 − v_s2) = 0; C is symmetric.

K seen by the drive is the velocity difference between its nodes for a unit
force injected at n1 and taken out at n2.

This module is the one place the nodal equations are written:
:func:`stamps` stamps every element and lever, :func:`assemble` builds the
matrices (of the loaded part, or with ``whole=True`` of the whole network,
as the time domain and two-ports need them), and :func:`combine` forms
A(ω) from them.  Solving them is :mod:`mechcirc.nodal`'s.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._memo import Memos
from .circuit import FRAME, Circuit, Element, Lever
from .topology import check_frame_paths, force_groups, loaded_groups, node_names

__all__ = ["NodalSystem", "assemble", "stamps", "combine", "susceptance", "dense_matrices",
           "held", "KINDS"]


@dataclass(frozen=True, eq=False)
class NodalSystem(Memos):
    """The nodal matrices of the loaded part of a circuit.

    Attributes
    ----------
    nodes : tuple of str
        Unknown node velocities, in matrix order (the reference node excluded).
    levers : tuple of Lever
        Lever force unknowns follow the nodes, in this order.
    elements : tuple of Element
        The elements that carry force.
    unloaded : tuple of str
        Elements and levers on no path between the drive's nodes.
    n : int
        Number of unknowns (also :attr:`size`).
    M, D, Ks, C : scipy.sparse.csr_matrix, shape (n, n)
        Mass [kg], damping [N·s/m], stiffness [N/m] and lever matrices, built
        from ``stamps`` on first use (scipy is imported only then; the dense
        arrays of small systems come from :meth:`dense` without it).
    a, b : int
        Indices of the drive's nodes, −1 for the reference node.
    stamps : dict
        The unsummed entries ``kind -> (rows, cols, values)`` of M, D, Kₛ and C,
        for residuals in double-double (a summed diagonal is already rounded).
    """

    nodes: tuple[str, ...]
    levers: tuple[Lever, ...]
    elements: tuple[Element, ...]
    unloaded: tuple[str, ...]
    n: int
    a: int
    b: int
    stamps: dict

    @property
    def size(self) -> int:
        """Number of unknowns (node velocities and lever forces)."""
        return self.n

    M = property(lambda self: self.sparse("mass"), doc="Mass matrix [kg] (sparse).")
    D = property(lambda self: self.sparse("damper"), doc="Damping matrix [N·s/m] (sparse).")
    Ks = property(lambda self: self.sparse("spring"), doc="Stiffness matrix [N/m] (sparse).")
    C = property(lambda self: self.sparse("lever"), doc="Lever matrix (sparse).")

    def sparse(self, kind: str) -> Any:
        """The matrix of ``kind`` (one of :data:`KINDS`) as a ``scipy.sparse.csr_matrix``.

        Parameters
        ----------
        kind : str
            ``"mass"``, ``"damper"``, ``"spring"`` or ``"lever"``.

        Returns
        -------
        scipy.sparse.csr_matrix
            Shape (n, n), the stamps summed; built once.
        """
        def build():
            import scipy.sparse as sp

            r, c, v = self.stamps[kind]
            return sp.csr_matrix((v, (r, c)), shape=(self.n, self.n))

        return self.memo("_sparse_" + kind, build)

    def dense(self, kind: str) -> NDArray[np.float64]:
        """The matrix of ``kind`` (as in :meth:`sparse`) as a dense (n, n) array, without
        scipy (small systems): equal to ``self.sparse(kind).toarray()``, the stamps
        summed in their order as the sparse matrix sums them; built once.

        Parameters
        ----------
        kind : str
            Which matrix: ``"mass"``, ``"damper"``, ``"spring"`` or ``"lever"``.

        Returns
        -------
        ndarray, shape (n, n)
            Shared between calls: not to be written to.
        """
        return self.memo("_dense_" + kind,
                         lambda: self._summed(kind, False).reshape(self.n, self.n))

    def diagonal(self, kind: str) -> NDArray[np.float64]:
        """The diagonal of the matrix of ``kind`` (as in :meth:`sparse`), summed from the
        stamps without scipy: equal to ``self.sparse(kind).diagonal()``, shape (n,).

        Parameters
        ----------
        kind : str
            The matrix whose diagonal is summed: ``"mass"``, ``"damper"``,
            ``"spring"`` or ``"lever"``.

        Returns
        -------
        ndarray, shape (n,)
            A new array at each call.
        """
        return self._summed(kind, True)

    def _summed(self, kind: str, diagonal: bool) -> NDArray[np.float64]:
        """The stamps of ``kind`` summed into the flat n × n matrix, or into its diagonal.

        bincount adds each entry's weights in their order from 0.0, as
        np.add.at into zeros does (the same bits), at a fraction of its cost.
        """
        r, c, v = (np.asarray(x) for x in self.stamps[kind])
        r, c, v = r.astype(np.intp), c.astype(np.intp), v.astype(float)
        n = self.n
        on = r == c
        flat = np.bincount(r[on], v[on], n) if diagonal else np.bincount(r * n + c, v, n * n)
        return np.asarray(flat, dtype=float)            # (float already: no copy)

    def injection(self) -> NDArray[np.float64]:
        """Right-hand side: unit force into node a, out of node b."""
        rhs = np.zeros(self.size)
        if self.a >= 0:
            rhs[self.a] += 1.0
        if self.b >= 0:
            rhs[self.b] -= 1.0
        return rhs

    def difference(self, x: NDArray, a: int | None = None, b: int | None = None) -> NDArray:
        """Velocity difference v_a − v_b from solutions ``x`` of shape (..., n): of the
        drive's nodes, or of the rows ``a`` and ``b`` given (−1: the reference)."""
        a, b = self.a if a is None else a, self.b if b is None else b
        out = np.zeros(x.shape[:-1], dtype=x.dtype)
        if a >= 0:
            out = out + x[..., a]
        if b >= 0:
            out = out - x[..., b]
        return out


def assemble(circuit: Circuit, whole: bool = False) -> NodalSystem:
    """Build the nodal matrices of the part of ``circuit`` that carries force.

    With ``whole=True`` every element and lever is kept, loaded by the drive
    or not, no drive is needed, and nothing is checked: the matrices of
    M ẍ + D ẋ + Kₛ x = f for the whole network (velocities referred to the
    frame ``"0"``, or to the drive's second node where there is no frame), as
    the time-domain (:mod:`mechcirc.transient`) and two-port analyses need
    them.  ``a`` and ``b`` index the drive's nodes (−1 where a node is the
    reference or there is no drive).

    Parameters
    ----------
    circuit : Circuit
        The network.
    whole : bool
        Keep every element and lever (see above).

    Returns
    -------
    NodalSystem
        Nodes, levers, elements, the unloaded ones and the sparse M, D, Kₛ, C.

    Raises
    ------
    TopologyError
        If the drive's nodes are not connected or a node is reached only
        through a lever's other side (singular at every frequency); not
        with ``whole=True``.
    """
    d = circuit.drive
    unloaded: tuple[str, ...] = ()
    if whole:
        elements, levers = tuple(circuit.elements), tuple(circuit.levers)
    else:
        elements, levers, unloaded = _loaded_part(circuit)
        d = circuit.require_drive()
    names = node_names(elements, levers)
    reference = FRAME if FRAME in names or d is None or not names else d.n2
    nodes = tuple(n for n in names if n != reference)
    index = {n: i for i, n in enumerate(nodes)}
    index[reference] = -1
    n = len(nodes) + len(levers)
    triplets: dict[str, tuple[list, list, list]] = {k: ([], [], []) for k in KINDS}
    for kind, row, col, sign, source, ratio in stamps(elements, levers, index):
        rows, cols, vals = triplets[kind]
        rows.append(row)
        cols.append(col)
        vals.append(sign * (source.ratio if ratio else 1.0) if kind == "lever"
                    else sign * source.value * source.eta)
    stamped = {kind: tuple(np.asarray(a) for a in t) for kind, t in triplets.items()}
    return NodalSystem(nodes, levers, elements, unloaded, n,
                       index.get(d.n1, -1) if d else -1, index.get(d.n2, -1) if d else -1,
                       stamped)


def _loaded_part(circuit: Circuit) -> tuple[tuple, tuple, tuple[str, ...]]:
    """(elements, levers, names of the rest): the part of ``circuit`` its drive loads, checked."""
    check_frame_paths(circuit)
    d = circuit.require_drive()
    groups = force_groups(circuit.elements, circuit.levers)
    kept = set(loaded_groups(groups, d.n1, d.n2, drive_line=d.line, source=circuit.source))
    n_el = len(circuit.elements)
    elements = tuple(e for i, e in enumerate(circuit.elements) if i in kept)
    levers = tuple(lv for i, lv in enumerate(circuit.levers) if n_el + i in kept)
    unloaded = tuple(e.name for i, e in enumerate(circuit.elements) if i not in kept) + \
        tuple(lv.name for i, lv in enumerate(circuit.levers) if n_el + i not in kept)
    return elements, levers, unloaded


#: The four matrices of a nodal system, in the order of :class:`NodalSystem`.
KINDS = ("mass", "damper", "spring", "lever")


def stamps(elements, levers, index: dict[str, int]):
    """Every unsummed entry of the nodal matrices — the one place elements are stamped.

    Yields ``(kind, row, col, sign, source, ratio)``: ``kind`` one of
    :data:`KINDS`; ``source`` the :class:`Element` or :class:`Lever`; the entry
    is ``sign × value × eta`` of an element, and ``sign × ratio`` (``ratio``
    true) or ``sign × 1`` of a lever.  ``index`` maps node names to rows (−1,
    or no entry, for the reference node, whose rows are dropped); lever force unknowns
    follow the ``max(index) + 1`` node rows, in order.  The numeric matrices
    (:func:`assemble`) and the symbolic ones (:mod:`mechcirc.interop.formula`)
    are both built from these entries.

    Parameters
    ----------
    elements : sequence of Element
        The elements to stamp.
    levers : sequence of Lever
        The levers to stamp.
    index : dict[str, int]
        Node name → row (−1 or absent: the reference).

    Yields
    ------
    tuple
        ``(kind, row, col, sign, source, ratio)``.
    """
    n_nodes = sum(1 for i in index.values() if i >= 0)
    for e in elements:
        i, j = index.get(e.n1, -1), index.get(e.n2, -1)
        for r, c, s in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
            if r >= 0 and c >= 0:
                yield e.kind, r, c, s, e, False
    for k, lv in enumerate(levers):
        col = n_nodes + k
        for node, s, ratio in ((lv.p1, 1.0, True), (lv.p2, -1.0, True),
                               (lv.s1, -1.0, False), (lv.s2, 1.0, False)):
            i = index.get(node, -1)
            if i >= 0:
                yield "lever", i, col, s, lv, ratio
                yield "lever", col, i, s, lv, ratio


def combine(dc, m, k, omega):
    """A(ω) = D + C + j(ωM − Kₛ/ω) from its parts — the one place A(ω) is formed.

    ``dc``, ``m``, ``k`` are arrays of one shape (dense matrices, or the
    aligned nonzeros of a sparse pattern, in any float precision) and
    ``omega`` broadcasts against them.  Entries beyond float64 (ω·m above
    1.8e308) come out non-finite; callers flag them.

    Parameters
    ----------
    dc, m, k : ndarray
        D + C, M and Kₛ.
    omega : float or ndarray
        ω [rad/s].

    Returns
    -------
    ndarray of complex
        A(ω), of the broadcast shape.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        return dc + 1j * susceptance(m, k, omega)


def susceptance(m, k, omega):
    """The imaginary part ωM − Kₛ/ω of A(ω) (see :func:`combine`)."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return omega * m - k / omega


def dense_matrices(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """A(ω) for each ω as one dense array of shape (n_ω, n, n).

    Parameters
    ----------
    system : NodalSystem
        From :func:`assemble`.
    omega : array_like
        ω [rad/s], shape (n_ω,).

    Returns
    -------
    ndarray of complex, shape (n_ω, n, n)
        A(ω) [N·s/m].
    """
    omega = np.asarray(omega)
    omega = omega.astype(complex if np.iscomplexobj(omega) else float).reshape(-1, 1, 1)
    dc = system.dense("damper") + system.dense("lever")
    return combine(dc, system.dense("mass"), system.dense("spring"), omega)


def held(system: NodalSystem) -> NodalSystem:
    """The system with the drive held: one more unknown q and the row v_a − v_b = 1.

    [[A, c], [cᵀ, 0]] [x; q] = [0; 1] with c = e_a − e_b gives q = −1/K (the
    force through the drive per unit velocity difference, negated), computed
    without the near-singular A at an anti-resonance.  Like a lever, the
    constraint goes into the symmetric C block; the drive of the returned
    system points at q (``a = n``, ``b = −1``).

    Parameters
    ----------
    system : NodalSystem
        From :func:`assemble`, with a drive.

    Returns
    -------
    NodalSystem
        One unknown larger, driven at q.
    """
    n = system.size
    rows, cols, vals = (list(v) for v in system.stamps["lever"])
    for i, s in ((system.a, 1.0), (system.b, -1.0)):
        if i >= 0:
            rows += [i, n]
            cols += [n, i]
            vals += [s, s]
    lever = (np.asarray(rows, dtype=int), np.asarray(cols, dtype=int),
             np.asarray(vals, dtype=float))
    return NodalSystem(system.nodes, system.levers, system.elements, system.unloaded,
                       n + 1, n, -1, {**system.stamps, "lever": lever})

