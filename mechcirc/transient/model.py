"""State-space form of a circuit for the time domain, from the nodal assembly.

The nodal matrices of :func:`mechcirc.nodal.assemble` (``whole=True``) give,
for node displacements x (frame = 0) and lever forces λ,

    M ẍ + D ẋ + Kₛ x + Gᵀ λ = f,      G x = 0   (levers: r (x_p1 − x_p2) = x_s1 − x_s2)

No element law is written here: M, D and Kₛ are the frequency-domain stamps
read as ``s² M + s D + Kₛ``.  The constraints are eliminated exactly:

* levers (and, for a velocity drive, the drive constraint x_a − x_b = X(t))
  by a null-space basis T: x = T q + p X, where p is the minimum-kinetic-energy
  particular solution (Tᵀ M p = 0, so the drive's acceleration never enters);
  X = ∫V is carried as one more state, so a piecewise-linear V stays exact;
* massless coordinates: directions without mass but with damping become
  first-order states; directions with neither are condensed statically
  (exact: M and D vanish on them since both are positive semidefinite).

The result is ż = A z + B u with the drive value u (velocity V or force F)
and output maps x = Cx z + Dx u, v = Cv z + Dv u + Ev u̇.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as la

from .._memo import Memos
from ..circuit import FRAME, Circuit, Element
from ..errors import MechcircError, TopologyError
from ..topology import adjacency, force_groups, reachable

__all__ = ["StateSpace", "state_space", "backlash_elements", "MAX_NODES"]

#: Most nodes (plus levers) a transient accepts: the model is dense, O(n²) memory
#: and O(n³) set-up (2000 nodes: 32 MB per matrix, a few seconds).
MAX_NODES = 2000


@dataclass(frozen=True, eq=False)
class StateSpace(Memos):
    """ż = A z + B u; x = Cx z + Dx u; v = Cv z + Dv u + Ev u̇ (node-space, ``nodes`` order).

    ``kind`` is the drive's kind (``"velocity"``, ``"force"`` or ``None``); ``g``
    the drive's incidence (e_a − e_b), ``h`` the row giving the drive's force
    from the nodal residual r = M a + D v + Kₛ x = Gᵀ μ + g Q: any h with
    [G; g] h = e_last gives Q = h·r.  A velocity drive takes h = p, its generalised
    force, in which a part moving rigidly with the drive adds exactly nothing (with
    the minimum-norm h, a 105 kg inerter's rounding inside a floating part was 3e-9
    of the force of the 0.05 kg mass driven); a force drive the minimum-norm h, solved
    as such (scipy's ``pinv([Gᵀ g])`` was 6.8e-8 off it behind levers of ratios 185
    and 919).  ``massive`` is true when every
    coordinate carries mass (required with clearances).  ``z0`` maps the
    circuit's initial conditions into the state.
    """

    nodes: tuple
    elements: tuple
    kind: str | None
    A: np.ndarray
    B: np.ndarray
    Cx: np.ndarray
    Dx: np.ndarray
    Cv: np.ndarray
    Dv: np.ndarray
    Ev: np.ndarray
    M: np.ndarray
    D: np.ndarray
    K: np.ndarray
    g: np.ndarray
    h: np.ndarray | None
    massive: bool
    initial: tuple              # (z0, notes)
    drop: tuple                 # element names left out of M, D, K (clearance elements)
    extra: np.ndarray | None    # (N, E): state rate per unit force of each clearance element

    @property
    def size(self) -> int:
        return self.A.shape[0]

    def drive_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Mᵀh, Dᵀh, Kₛᵀh), the drive's force Q = h·(M a + D v + Kₛ x) as rows on a, v, x.

        Summed element by element, m (g_eᵀh) g_e: an element inside a part that h
        moves rigidly adds exactly 0 (from the summed matrices, the rounding of a
        105 kg inerter's diagonal entry was 4e-9 of a 0.05 kg mass's force).
        """
        def rows():
            index, n = {nd: i for i, nd in enumerate(self.nodes)}, len(self.nodes)
            out = {kind: np.zeros(n) for kind in ("mass", "damper", "spring")}
            for e in self.elements:
                ge = incidence(index, e.n1, e.n2, n)
                out[e.kind] += (e.value * e.eta * (ge @ self.h)) * ge
            return out["mass"], out["damper"], out["spring"]
        return self.memo("_drive_rows", rows)


def backlash_elements(circuit: Circuit) -> list[tuple[Element, Element | None]]:
    """(spring, companion damper or None) for every spring with a clearance ≥ 1e-10.

    Parameters
    ----------
    circuit : Circuit

    Returns
    -------
    list of (Element, Element or None)
    """
    by_name, out = {e.name: e for e in circuit.elements}, []
    for e in circuit.elements:
        if e.kind == "spring" and e.backlash >= 1e-10:
            comp = by_name.get(f"{e.name}_damping")
            if comp is not None and (comp.kind != "damper" or {comp.n1, comp.n2} != {e.n1, e.n2}):
                comp = None
            out.append((e, comp))
    return out


def _split(S: np.ndarray, basis: np.ndarray, full: float, rel: float = 1e-13):
    """Orthonormal bases of the range and null space of a PSD matrix restricted to ``basis``.

    An eigenvalue counts when above ``rel`` × the largest and above 1e-13 × ``full``
    (the largest entry of the node matrix times the basis T of the free motion): the
    restriction's rounding is of order ε × ``full``, T's own rounding included (not
    the node matrix's largest entry: a 1e15 kg velocity-driven mass, which T does not
    move, made a 1 kg mass behind a spring massless: session 28).  A direction with
    none of S (a lever-held node pair beside
    the velocity-driven mass) came out with mass 1e-34, made a massive state
    whose A held 1.5e48, and no periodic state existed at any ω (crosscheck
    campaign, seed 3, network 116); and a real mass of 4.5e-9 beside 1.4e4 (a
    0.0009 kg mass behind a lever of 844, seed 5, network 40) was dropped, with
    its mode at 17,262 rad/s, when ``rel`` was 1e-11.
    """
    if basis.shape[1] == 0:
        return basis, basis
    R = basis.T @ S @ basis
    w, U = la.eigh(0.5 * (R + R.T))
    big = w > max(rel * np.abs(w).max(), 1e-13 * full, 0.0)
    return basis @ U[:, big], basis @ U[:, ~big]


def state_space(circuit: Circuit, *, linearise: bool = False) -> StateSpace:
    """The state-space model of ``circuit`` (clearance elements left out unless ``linearise``).

    With ``linearise`` the clearances are taken closed (the frequency domain's
    reading); otherwise the clearance springs and their companion dampers are
    left out of A and their forces enter through ``extra``.

    Parameters
    ----------
    circuit : Circuit
    linearise : bool

    Returns
    -------
    StateSpace
    """
    clear, drop, work = _working(circuit, linearise)
    nodes, index, M, D, K, G = _node_matrices(work, clear)
    n, d = len(nodes), circuit.drive
    g = np.zeros(n)
    if d is not None:
        g = incidence(index, d.n1, d.n2, n)
        if not g.any():
            raise TopologyError(f"drive {d.name!r} connects nodes no element uses")
    kind = d.kind if d is not None else None
    vel = kind == "velocity"
    Cons = np.vstack([G, g[None, :]]) if vel else G
    T = np.eye(n) if Cons.shape[0] == 0 else la.null_space(Cons, rcond=1e-12)
    nq = T.shape[1]
    MT, DT = M @ T, D @ T
    Mq, Dq, Kq = T.T @ MT, T.T @ DT, T.T @ K @ T
    B1, B0 = _split(Mq, np.eye(nq), np.abs(MT).max(initial=0.0))
    p = _particular(work, index, M, Cons, T @ B1) if vel and d is not None else np.zeros(n)
    # Generalised force per unit drive value u and per unit drive displacement X.
    Fu, Fx = np.zeros(nq), np.zeros(nq)
    if kind == "force":
        Fu = T.T @ g
    elif vel:
        Fu, Fx = -(T.T @ D @ p), -(T.T @ K @ p)
    Bd, Bs = _split(Dq, B0, np.abs(DT).max(initial=0.0))
    n1, n0, ns = B1.shape[1], Bd.shape[1], Bs.shape[1]
    Y = np.hstack([B1, Bd])
    Ky, Fyu, Fyx, S_y, S_u, S_x = _condense(Kq, Fu, Fx, Y, Bs, (T, nodes))
    A, Bv, M11_inv = _dynamics(Y.T @ Mq @ Y, Y.T @ Dq @ Y, Ky, Fyu, Fyx, n1, n0, vel)
    N = A.shape[0]
    Cx, Dx, Cv, Dv = _outputs(T, B1, Bd, Bs, (S_y, S_u, S_x), p, A, Bv, vel)
    # Q = h·r, r = M a + D v + K x = Gᵀ μ + g Q, for any h with [G; g] h = e_last (StateSpace)
    h = p if vel else _min_norm(np.vstack([G, g[None, :]])) if kind is not None else None
    massive = n0 == 0 and ns == 0
    extra = _clearance_map(clear, index, N, M11_inv, Y[:, :n1], T, massive) if clear else None
    z0, notes = _initial(circuit, nodes, index, Cx, Cv, N, vel)
    return StateSpace(tuple(nodes), tuple(work.elements), kind, A, Bv, Cx, Dx, Cv, Dv, Dx,
                      M, D, K, g, h, massive, (z0, tuple(notes)), tuple(sorted(drop)),
                      extra)


def _outputs(T, B1, Bd, Bs, S, p, A, Bv, vel):
    """(Cx, Dx, Cv, Dv): node displacements and velocities from the state z and drive u."""
    S_y, S_u, S_x = S
    nq, N, n1, n0 = T.shape[1], A.shape[0], B1.shape[1], Bd.shape[1]
    # q = B1 y1 + Bd y0 + Bs s, with z = [y1, v1, y0, (X)].
    Qz = np.zeros((nq, N))
    Qz[:, :n1] = B1 + Bs @ S_y[:, :n1]
    Qz[:, 2 * n1:2 * n1 + n0] = Bd + Bs @ S_y[:, n1:]
    if vel:
        Qz[:, N - 1] += Bs @ S_x
    Cx, Dx = T @ Qz, T @ (Bs @ S_u)
    if vel:
        Cx[:, N - 1] += p
    # v = d/dt x = Cx ż + Dx u̇ = Cx A z + Cx B u + Dx u̇
    return Cx, Dx, Cx @ A, Cx @ Bv


def _working(circuit: Circuit, linearise: bool) -> tuple[list, set, Circuit]:
    """(clearance pairs, names dropped, the circuit without them), size-checked."""
    clear = [] if linearise else backlash_elements(circuit)
    drop = {e.name for e, _ in clear} | {c.name for _, c in clear if c is not None}
    kept = tuple(e for e in circuit.elements if e.name not in drop)
    if drop and not kept:
        raise MechcircError("the circuit has only clearance elements; add a mass")
    work = dataclasses.replace(circuit, elements=kept) if drop else circuit
    count = len({nd for e in work.elements for nd in (e.n1, e.n2)}) + len(work.levers)
    if count > MAX_NODES:
        raise MechcircError(f"the network has {count} nodes and levers; transients are limited "
                            f"to {MAX_NODES} (dense matrices); reduce it first "
                            "('mechcirc reduce')")
    return clear, drop, work


def _node_matrices(work: Circuit, clear: list):
    """Node list and index, dense M, D, Kₛ and lever rows G (clearance-only nodes appended)."""
    from ..nodal import assemble

    system = assemble(work, whole=True)
    # clearance-only nodes still need a coordinate: appended, in order of appearance
    nodes = list(dict.fromkeys([*system.nodes, *(nd for e, _ in clear for nd in (e.n1, e.n2)
                                                 if nd != "0")]))
    n = len(nodes)
    nn = len(system.nodes)
    # dense, summed from the stamps without scipy (building scipy's sparse matrices cost
    # 0.3 ms of a small circuit's first transient), then sliced
    M, D, K = (np.zeros((n, n)) for _ in range(3))
    for X, kind in ((M, "mass"), (D, "damper"), (K, "spring")):
        X[:nn, :nn] = system.dense(kind)[:nn, :nn]
    G = np.zeros((len(system.levers), n))
    if system.levers:
        G[:, :nn] = system.dense("lever")[nn:, :nn]
    return nodes, {nd: i for i, nd in enumerate(nodes)}, M, D, K, G


def incidence(index: dict, n1: str, n2: str, n: int) -> np.ndarray:
    """e_n1 − e_n2 over the coordinates ``index`` (nodes not in it add nothing)."""
    g = np.zeros(n)
    if n1 in index:
        g[index[n1]] += 1.0
    if n2 in index:
        g[index[n2]] -= 1.0
    return g


def _particular(work: Circuit, index: dict, M: np.ndarray, Cons: np.ndarray,
                TB1: np.ndarray) -> np.ndarray:
    """Minimum-kinetic-energy p with Cons p = e_last (Tᵀ M p = 0), ``TB1`` the massive
    directions of the free motion (T B1).

    p is unique only on the coordinates with mass.  Where a part of the network
    is held by the drive's node alone (reached from it without passing the
    drive's other node or the frame), that part moves rigidly with the drive:
    p = ±1 on it, exact, when that satisfies the constraints and Tᵀ M p = 0
    (else the springs of a floating part see X(t) through static condensation,
    whose rounding put 1.5e-4 of error on the drive's force where X reached
    359 m: crosscheck campaign, seed 2, network 28).  Otherwise p is the
    minimum-norm solution p₀ of the constraints with its massive part removed,
    p = p₀ − T B1 (B1ᵀ Mq B1)⁻¹ (T B1)ᵀ M p₀: two solves, not
    one saddle-point system ([M Cᵀ; C 0], whose least-squares solution was
    7e-8 off behind levers of ratios 185 and 919 and moved a free mass).
    """
    e = np.eye(Cons.shape[0])[-1]
    d = work.require_drive()
    adj = adjacency(pair for group in force_groups(work.elements, work.levers) for pair in group)
    for a, b, sign in ((d.n1, d.n2, 1.0), (d.n2, d.n1, -1.0)):
        part = reachable(adj, a, blocked=b) if a in index else {FRAME}
        if FRAME not in part:
            p = np.zeros(M.shape[0])
            p[[index[nd] for nd in part if nd in index]] = sign
            # Tᵀ M p = 0 row by row to within the rounding of its own terms (relative to
            # the largest mass, a 1e12 kg driven mass passed a spring's 1 kg: session 28)
            if np.array_equal(Cons @ p, e) and np.all(np.abs(TB1.T @ (M @ p)) <= 1e-12 * (
                    np.abs(TB1.T) @ (np.abs(M) @ np.abs(p)))):
                return p
    p = _min_norm(Cons)
    if TB1.shape[1]:
        p -= TB1 @ la.solve(TB1.T @ M @ TB1, TB1.T @ (M @ p), assume_a="pos")
    if np.abs(Cons @ p - e).max() > 1e-8 * max(1.0, np.abs(p).max()):
        raise TopologyError(f"the velocity drive {d.name!r} contradicts the levers "
                            "(its nodes' relative motion is fixed by them)")
    return p


def _min_norm(C: np.ndarray) -> np.ndarray:
    """The minimum-norm solution of C h = e_last."""
    return la.lstsq(C, np.eye(C.shape[0])[-1])[0]


def _condense(Kq, Fu, Fx, Y, Bs, where):
    """Static condensation of the coordinates ``Bs`` (neither mass nor damping).

    Returns Ky, Fyu, Fyx on the kept coordinates ``Y`` and s = S_y y + S_u u + S_x X;
    ``where`` = (T, nodes) maps coordinates to node names for the error.
    """
    if Bs.shape[1]:
        Kss = Bs.T @ Kq @ Bs
        try:
            Kss_inv = la.inv(Kss)
            if not np.all(np.isfinite(Kss_inv)) or np.linalg.cond(Kss) > 1e13:
                raise la.LinAlgError
        except la.LinAlgError:
            loose = where[0] @ Bs @ la.svd(Kss)[2][-1]     # the least stiff motion
            names = [where[1][i] for i in np.flatnonzero(abs(loose) > 1e-6 * abs(loose).max())]
            raise TopologyError(f"node(s) {', '.join(names)} can move with no mass, damping or "
                                "spring resisting (their motion is undetermined): join them to "
                                "the frame '0' or the drive's part, or remove them") from None
        S_y, S_u = -Kss_inv @ (Bs.T @ Kq @ Y), Kss_inv @ (Bs.T @ Fu)
        S_x = Kss_inv @ (Bs.T @ Fx)
    else:
        S_y, S_u, S_x = np.zeros((0, Y.shape[1])), np.zeros(0), np.zeros(0)
    KyS = Y.T @ Kq @ Bs
    return (Y.T @ Kq @ Y + KyS @ S_y, Y.T @ Fu - KyS @ S_u, Y.T @ Fx - KyS @ S_x,
            S_y, S_u, S_x)


def _dynamics(My, Dy, Ky, Fyu, Fyx, n1: int, n0: int, vel: bool):
    """A, B over z = [y1, v1, y0, (X)] and M₁₁⁻¹ (y1 massive, y0 damped only)."""
    N = 2 * n1 + n0 + (1 if vel else 0)
    A, Bv = np.zeros((N, N)), np.zeros(N)
    i_y1, i_v1, i_y0 = slice(0, n1), slice(n1, 2 * n1), slice(2 * n1, 2 * n1 + n0)

    def force(r):       # rows r of the forces over z, −K y − D₁ v1 (+ Fx X): not y0's damping
        out = np.zeros((len(Fyu[r]), N))
        out[:, i_y1], out[:, i_v1], out[:, i_y0] = -Ky[r, :n1], -Dy[r, :n1], -Ky[r, n1:]
        if vel:
            out[:, N - 1] = Fyx[r]
        return out
    # ẏ0 = D00⁻¹ (F0 − D01 v1 − K0 y)  as  rows over z and u
    dy0_z, dy0_u = np.zeros((n0, N)), np.zeros(n0)
    if n0:
        D00_inv = la.inv(Dy[n1:, n1:])
        dy0_z, dy0_u = D00_inv @ force(slice(n1, None)), D00_inv @ Fyu[n1:]
    A[i_y1, i_v1] = np.eye(n1)
    A[i_y0], Bv[i_y0] = dy0_z, dy0_u
    M11_inv = np.zeros((0, 0))
    if n1:
        M11_inv = la.inv(My[:n1, :n1])
        A[i_v1] = M11_inv @ (force(slice(0, n1)) - Dy[:n1, n1:] @ dy0_z)
        Bv[i_v1] = M11_inv @ (Fyu[:n1] - Dy[:n1, n1:] @ dy0_u)
    if vel:
        Bv[N - 1] = 1.0
    return A, Bv, M11_inv


def _clearance_map(clear: list, index: dict, N: int, M11_inv, Y1, T, massive: bool):
    """(N, E): state rate per unit force of each clearance element (its force f_e,
    n1 → n2, acts as −g_e f_e on the left side); every coordinate needs mass."""
    if not massive:
        raise MechcircError(
            "clearances (backlash=) need mass at every node of the network "
            "(this one has massless nodes); add small masses or remove the clearance")
    n1, extra = Y1.shape[1], np.zeros((N, len(clear)))
    for j, (e, _) in enumerate(clear):
        ge = incidence(index, e.n1, e.n2, T.shape[0])
        extra[n1:2 * n1, j] = M11_inv @ (Y1.T @ (T.T @ (-ge)))
    return extra


def _initial(circuit, nodes, index, Cx, Cv, N, vel):
    """State z0 matching the ``.ic`` lines (least squares; a warning if not attainable)."""
    z0, notes = np.zeros(N), []
    if not circuit.initial:
        return z0, notes
    n = len(nodes)
    x0, v0 = np.zeros(n), np.zeros(n)
    for node, x, v in circuit.initial:
        if node in index:
            x0[index[node]] = x
            v0[index[node]] = v
    # Rows x and v of every node (drive at rest, u = 0).  The named nodes'
    # values are met first (least squares if not attainable); the freedom left
    # keeps the other nodes as close to rest as it can.
    Mat, rhs = np.vstack([Cx, Cv]), np.concatenate([x0, v0])
    cols = np.ones(N, bool)
    d = circuit.drive
    if vel and not any(nd in (d.n1, d.n2) for nd, _, _ in circuit.initial):
        cols[-1] = False            # X(0) = 0: the drive starts from its reference
    named_idx = {index[nd] for nd, _, _ in circuit.initial if nd in index}
    rows = np.array([i in named_idx for i in range(n)] * 2)
    Mz = Mat[:, cols]
    # Lexicographic least squares: named rows, then the other nodes' x, then their v
    # (a massless damped node's velocity follows from the displacements).
    is_x = np.arange(2 * n) < n
    zp, Nn = np.zeros(Mz.shape[1]), np.eye(Mz.shape[1])
    for group in (rows, ~rows & is_x, ~rows & ~is_x):
        if not group.any() or Nn.shape[1] == 0:
            continue
        Ag = Mz[group] @ Nn
        xi = la.lstsq(Ag, rhs[group] - Mz[group] @ zp)[0]
        zp = zp + Nn @ xi
        Nn = Nn @ la.null_space(Ag) if Ag.size else Nn
    z0[cols] = zp
    resid = Mat @ z0 - rhs
    bad = [nodes[i] for i in range(n)
           if i in named_idx and (abs(resid[i]) > 1e-9 * (1 + abs(x0[i]))
                                  or abs(resid[n + i]) > 1e-9 * (1 + abs(v0[i])))]
    if bad:
        notes.append("initial state of node(s) " + ", ".join(bad) + " is not attainable "
                     "(levers, the drive or massless nodes fix it); the closest attainable "
                     "state was used")
    return z0, notes


def drive_map(ss: StateSpace) -> tuple[np.ndarray, Any, Any] | None:
    """(w, Du, Dud): the drive's output (velocity of a force drive, force of a
    velocity drive) is w·z + Du·u + Dud·u̇ when the network is linear; None
    without a drive."""
    if ss.kind == "velocity":
        a, b, c = ss.drive_rows()
        return (a @ (ss.Cv @ ss.A) + b @ ss.Cv + c @ ss.Cx,
                a @ (ss.Cv @ ss.B) + b @ ss.Dv + c @ ss.Dx, a @ ss.Dv + b @ ss.Ev)
    return (ss.g @ ss.Cv, ss.g @ ss.Dv, ss.g @ ss.Ev) if ss.kind == "force" else None
