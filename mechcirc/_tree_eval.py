"""Evaluation of a series–parallel tree over ω: K(ω), its rounding bound, the forces.

:func:`evaluate` (vectorised numpy, or through a flat :func:`plan` of the tree
the compiled :mod:`mechcirc._sp_kernel` when numba is installed), many designs
of one topology at once (:func:`evaluate_designs`), and :func:`push_down`,
which carries the drive's force and velocity back down the tree to every
element.  The element laws come from :func:`mechcirc.circuit.law_terms`.
Re-exported by :mod:`mechcirc.reduction`.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _jit
from ._tree import Leaf, Node, Parallel, Reflect, Series, postorder
from .circuit import LAWS, Circuit, Drive, Element, law_terms

__all__ = ["evaluate", "evaluate_designs", "push_down", "plan", "Plan", "compiled_evaluator",
           "KERNEL_MIN_WORK"]


# The rounding-error bound of :func:`evaluate`.  A node forms S = Σ tᵢ from m terms (its
# leaf groups and its children; in parallel the terms are admittances 1/Kᵢ), each term known
# to a relative error ρᵢ, so that
#
#     |Ŝ − S| ≤ Σ |tᵢ| (ρᵢ + m·u),     ρ(S) = that / |S|,
#
# where a leaf group of n same-signed scalars has ρ = (n + 2)·u, a reciprocal turns ρ into
# ρ/(1 − ρ) + 4u (∞ from ρ ≥ 1 on: no digit is known)
# and a lever's division by r² adds 2u.  ρ is carried relative to the computed values, so
# only the rounding of each addition (the m·u term) is first order.  Cancellation at a node
# (Σ|tᵢ| ≫ |S|) raises the bound there; the children's errors are weighted by |tᵢ|/|S|, not
# multiplied down the tree, so a deep ladder with no cancellation keeps a bound of a few
# hundred u.  A node keeps |Ŝ| and E, the bound of |Ŝ − S|; its parent takes ρ(S) = E/|Ŝ|,
# and through a reciprocal ρ/(1 − ρ) as E/(|Ŝ| − E) (:meth:`_Value.relative`, :func:`_node_bound`).

#: Unit roundoff of float64 (half the machine epsilon): the relative error of
#: one correctly rounded operation.
_U = np.finfo(float).eps / 2
#: Relative error of a reciprocal 1/z: ≤ u for a real z; a complex division in
#: numpy (Smith's algorithm) stays within a few u, bounded here by 4u.
_U_RECIP = 4 * _U
# The constants of the per-node array operations as 0-d arrays: numpy 2 resolves a
# Python or numpy scalar operand of a ufunc at every call, which costs about half the
# operation itself on a few hundred points (measured 1.67 against 1.11 µs for ω·x at
# 401 points); a 0-d float64 array gives the same IEEE results.
_ZERO, _ONE, _MINUS_ONE, _U_RECIP_0D, _INF = (np.array(x) for x in
                                              (0.0, 1.0, -1.0, _U_RECIP, np.inf))


def evaluate(root: Node, omega: ArrayLike, *, keep: bool = False, condition: bool = False,
             error: bool = False, designs: tuple | None = None, _mode: str = "auto"):
    """K(ω) [m/(N·s)] of the tree at each ω [rad/s], vectorised.

    ``keep=True`` returns ``(K, values)``, ``values`` mapping ``id(node)`` to the K of
    every series, parallel and lever node, for :func:`push_down`.  ``error=True``
    returns ``(K, bound)``, a running forward bound of the relative rounding error of K
    at each ω (see Notes); ``condition=True`` gives that bound divided by the unit
    roundoff (for callers of the former condition number).  Exact poles and zeros give
    ±inf or 0 without warnings (bound inf); ``inf - inf`` gives NaN (callers flag it).

    ``designs=(scaled, ratios)`` evaluates D designs of the tree's topology in one numpy
    pass: ``scaled`` maps each leaf's element name to its value·η, ``ratios`` each
    lever's name to its ratio, arrays of shape (D, 1) broadcasting against ω ((W,), or
    (D, W) for each design's own points); K and the bound are then (D, W), each row the
    same IEEE operations as the single design's.  The values must be positive and finite
    (a leaf group is then present exactly where it has leaves).

    Parameters
    ----------
    root : Node
        The series–parallel tree.
    omega : array_like
        ω [rad/s].
    keep, condition, error : bool
        As above.
    designs : tuple of (dict, dict), optional
        ``(scaled, ratios)`` of D designs.

    Returns
    -------
    ndarray of complex or tuple
        K [m/(N·s)]; ``(K, values)`` with ``keep``, ``(K, bound)`` with ``error`` or
        ``condition``.

    Notes
    -----
    The leaves of a series node add up to ``r + j(a/ω + b·ω)``, those of a parallel node
    to an admittance ``g + j(c·ω + d/ω)``, so a node costs a few array operations
    whatever its number of leaves.  A lossless sub-network (no dampers) has K = jX,
    computed in real arithmetic on X (about four times cheaper; keeps 1/0 = ∞, 1/∞ = 0).
    The error bound follows the rounding through every sum, first order in the unit
    roundoff u; its rules are stated beside ``_U`` in this module's source.
    """
    omega = np.asarray(omega, dtype=float)
    if omega.ndim == 0 and (error or condition) and not keep:
        # (the bound's running sums are arrays: one point as a 1-element array)
        K, rho = evaluate(root, omega[None], error=error, condition=condition,
                          designs=designs, _mode=_mode)
        return K.reshape(()), rho.reshape(())
    if designs is not None:
        D = next(iter(designs[0].values())).shape[0]
        omega = np.broadcast_to(omega, (D, omega.shape[-1]))
    if not keep and _mode == "auto":
        return _auto(root, omega, error, condition, designs)
    track = error or condition
    with np.errstate(all="ignore"):         # (one for the tree and its root's bound)
        top, values = _postorder_values(root, omega, track, keep, _mode != "fast", designs)
        K = top.complex()
        if keep:
            return K, {k: v.complex() for k, v in values.items()}
        if not track:
            return K
        rho = _relative_to_true(top.relative()[0], omega.shape)
    return K, (rho / _U if condition and not error else rho)


def _relative_to_true(rho, shape) -> NDArray:
    """The bound ``rho`` relative to the computed |K̂| made relative to the true |K|, ∞
    for NaN (the caller holds ``np.errstate(all="ignore")``)."""
    # relative to the true |K| ≥ |K̂|(1 − ρ) it is ρ / (1 − ρ) (a scalar ρ made an array there)
    rho = through_reciprocal(rho)
    if rho.shape != shape:          # (a fresh array of that shape otherwise)
        rho = np.broadcast_to(rho, shape).astype(float)
    return np.fmin(rho, _INF, out=rho)          # (fmin: NaN → ∞)


def _auto(root: Node, omega, error: bool, condition: bool, designs):
    """The compiled plan if asked for or worth it (one design), else :func:`_fast_then_checked`."""
    if designs is None and _jit.COMPILED is not False and (
            _jit.COMPILED or _KERNEL or _plan_size(root) * omega.size >= KERNEL_MIN_WORK):
        # By default never wait for numba to compile: numpy until it is cached.
        kernel = compiled_evaluator(compile=bool(_jit.COMPILED or _KERNEL))
        if kernel is not None:
            return _evaluate_compiled(kernel, plan(root), omega, error, condition)
    return _fast_then_checked(root, omega, error, condition, designs)


def _fast_then_checked(root, omega, error, condition, designs):
    """:func:`evaluate` by the fast pass (numpy's reciprocal as is), then again with the
    exact special cases at the points that end non-finite.

    The fast pass gives NaN for 1/0 where 1/0 = ∞ is wanted, and a NaN never
    disappears downstream, so only those points (whole rows of designs) are redone.
    """
    out = evaluate(root, omega, error=error, condition=condition, designs=designs,
                   _mode="fast")
    K = out[0] if isinstance(out, tuple) else out
    if np.isfinite(K).all():
        return out
    bad = ~np.isfinite(K)
    sub = None
    if designs is not None:           # again the whole rows of those designs
        rows = bad.any(axis=1)        # (all False on an empty grid of ω)
        bad = np.broadcast_to(rows[:, None], bad.shape)
        sub = tuple({k: v[rows] for k, v in d.items()} for d in designs)
    if bad.any():
        w = omega[bad] if sub is None else omega[bad].reshape(-1, omega.shape[1])
        again = evaluate(root, w, error=error, condition=condition, designs=sub,
                         _mode="checked")
        for target, part in (zip(out, again) if isinstance(out, tuple) else [(K, again)]):
            target[bad] = part.ravel()      # (rows of designs: flattened as ``bad`` picks)
    return out


def _postorder_values(root, omega, track: bool, keep: bool, checked: bool, designs):
    """``(value of the root, values of the nodes kept)``: the tree evaluated bottom up, the
    values of a node's internal children on top of a stack when it is reached (the caller
    holds ``np.errstate(all="ignore")``)."""
    values: dict[int, _Value] = {}
    stack: list[_Value] = []
    zero = np.zeros(omega.shape) if track else None      # (the bound's, see _node_bound)
    inv_omega = _ONE / omega
    for node, reflect, n_kids, groups in _internal_postorder(root):
        if reflect:
            child = stack.pop() if n_kids else \
                _leaf_value(node.child.element, omega, inv_omega, track, designs)
            r = None if designs is None else designs[1][node.lever.name]
            val = _Value(child.imaginary, node.lever.reflect(child.array, r))
            if track:
                rho, mag = child.relative()
                val.mag = node.lever.reflect(mag, r)
                # (a full array even over a single leaf, whose ρ is a scalar)
                val.rho = np.broadcast_to(rho + 2 * _U, omega.shape).copy()
        else:
            cut = len(stack) - n_kids           # (not -n_kids: stack[-0:] is all of it)
            parts = stack[cut:]
            del stack[cut:]
            if designs is not None:
                groups = _leaf_groups(node, designs)
            val = _combine(parts, omega, inv_omega, zero, keep, checked, groups)
        stack.append(val)
        if keep:
            values[id(node)] = val
    top = stack[-1] if stack else _leaf_value(root.element, omega, inv_omega, track,
                                              designs)
    return top, values


#: root -> its internal nodes in postorder, each ``(node, is a lever, its number of
#: internal children, its leaf groups)`` (:func:`_internal_postorder`).
_ORDERS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _plan_size(root) -> int:
    """The number of nodes of :func:`plan` (internal nodes, and each leaf alone at
    the root or under a lever) without building the plan."""
    if isinstance(root, Leaf):
        return 1
    order = _internal_postorder(root)
    return len(order) + sum(1 for n, reflect, _, _ in order
                            if reflect and isinstance(n.child, Leaf))


def _internal_postorder(root) -> list:
    """The series, parallel and lever nodes of ``root``, children first, built once per
    tree: ``(node, is a lever, its number of internal children, its leaf groups)``, a
    series or parallel node's leaves folded for a single design (:func:`_leaf_groups`)."""
    found = _ORDERS.get(root) if not isinstance(root, Leaf) else []
    if found is None:
        found = []
        for n in postorder(root):
            if isinstance(n, Reflect):
                found.append((n, True, 0 if isinstance(n.child, Leaf) else 1, None))
            elif not isinstance(n, Leaf):
                found.append((n, False, sum(1 for c in n.children if not isinstance(c, Leaf)),
                              _leaf_groups(n, None)))
        _ORDERS[root] = found
    return found


#: The compiled plan (:mod:`mechcirc._sp_kernel`) evaluates when numba is installed
#: and ``mechcirc._jit.COMPILED`` is None (default), once the kernel is loaded or when
#: a call has at least :data:`KERNEL_MIN_WORK` node-points and numba has the kernel
#: in its disk cache; True always; False never.
#: Importing numba and loading the compiled kernel from its cache takes about
#: 1 s once per process (0.7–1.1 s measured): below this many plan nodes × ω
#: points (about 0.15 s of the numpy path) a sweep does not start it.  Compiling
#: it (a fresh install) takes 4–11 s of CPU: the default path does not wait for
#: that, it runs numpy while a process of its own compiles the kernel into the cache.
KERNEL_MIN_WORK = 5_000_000
_KERNEL: list = []


def compiled_evaluator(compile: bool = True):
    """The compiled plan evaluator, or None without numba (imported on first use).

    Parameters
    ----------
    compile : bool
        False: do not wait for numba to compile it.  Where it is not in
        numba's disk cache yet, return None and let a detached process compile
        it into the cache (:func:`warm_kernel`,
        :func:`mechcirc._jit.warm_in_background`); a later call loads it from there.

    Returns
    -------
    callable or None
        :func:`mechcirc._sp_kernel.evaluate_plan`, or None.
    """
    if not _KERNEL:
        from . import _sp_kernel

        if compile or not _sp_kernel.HAVE_NUMBA or _jit.in_cache(_sp_kernel.evaluate_plan):
            _KERNEL.append(_sp_kernel.evaluate_plan if _sp_kernel.HAVE_NUMBA else None)
        else:
            _jit.warm_in_background("from mechcirc._tree_eval import warm_kernel; warm_kernel()")
            return None
    return _KERNEL[0]


def warm_kernel() -> None:
    """Compile the plan evaluator into numba's disk cache (the argument types a sweep uses)."""
    c = Circuit((Element("spring", "k", "a", "b", 1.0), Element("mass", "m", "b", "0", 1.0),
                 Element("damper", "c", "a", "0", 1.0)), Drive("V", "a", "0", "velocity", 1.0))
    kernel = compiled_evaluator()
    if kernel is not None:
        _evaluate_compiled(kernel, plan(c.tree), np.array([1.0, 2.0]), True, False)


@dataclass(frozen=True, eq=False)
class Plan:
    """A tree compiled into flat arrays for :mod:`mechcirc._sp_kernel` (see
    :func:`plan`): one entry per series, parallel and lever node (and per leaf
    that stands alone, at the root or under a lever), children first.

    The value-dependent arrays (leaf coefficients, their error constants,
    ``mu`` and the lever ratios) have one row per design, shape (D, M): D = 1
    for the tree's own values, D > 1 for a batch of designs of the same
    topology (:meth:`with_values`)."""

    kind: NDArray[np.int8]
    cplx: NDArray[np.bool_]
    c_real: NDArray[np.float64]
    c_inv: NDArray[np.float64]
    c_om: NDArray[np.float64]
    e_real: NDArray[np.float64]
    e_inv: NDArray[np.float64]
    e_om: NDArray[np.float64]
    mu: NDArray[np.float64]
    kstart: NDArray[np.int64]
    kids: NDArray[np.int64]
    ratio: NDArray[np.float64]
    slot: NDArray[np.int64]
    n_slots: int
    #: The folded leaves' elements, in fold order (rows of :meth:`with_values`'s ``scaled``).
    leaves: tuple = ()
    #: The lever of each lever node, in node order (rows of ``ratios``).
    levers: tuple = ()
    _fold: tuple = ()
    #: ``(tree, scaled, ratios)`` for the numpy evaluation of these designs when the
    #: compiled kernel is not used (:func:`evaluate` with ``designs=(scaled, ratios)``).
    numpy: tuple | None = None

    def arrays(self) -> tuple:
        """The arguments of :func:`mechcirc._sp_kernel.evaluate_plan` after ω: the fields
        from ``kind`` to ``n_slots``, in order."""
        return tuple(getattr(self, f.name) for f in fields(self)[:14])

    @property
    def designs(self) -> int:
        """D, the number of designs whose values the plan holds."""
        return self.c_real.shape[0]

    def with_values(self, scaled: ArrayLike, ratios: ArrayLike | None = None) -> "Plan":
        """The same plan for D designs: ``scaled[l, d]`` is value·η of leaf ``leaves[l]``
        in design d, ``ratios[r, d]`` the ratio of lever ``levers[r]`` (default: its own)."""
        scaled = np.asarray(scaled, dtype=float)
        if ratios is None:          # each lever's own ratio in every design
            ratios = np.array([[lv.ratio] for lv in self.levers], dtype=float).reshape(-1, 1) \
                .repeat(scaled.shape[-1], axis=1)
        return _fold_values(self.kind, self.kstart, self.kids, self.slot, self.n_slots,
                            self.leaves, self.levers, self._fold, scaled,
                            np.asarray(ratios, dtype=float))


_PLANS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


_KIND_CODE = {kind: i for i, kind in enumerate(LAWS)}


def _slot_term(kind: str, series, real, inv, om) -> tuple[int, Any]:
    """``(slot, coefficient)`` of an element of ``kind`` whose law gives ``real + j(inv/ω +
    om·ω)`` in a series node (``series``) or a parallel one (see :func:`_leaf_term`)."""
    slot = LAWS[kind].power if series else -LAWS[kind].power
    return slot, (real if slot == 0 else om if slot > 0 else inv)


def _leaf_table() -> tuple:
    """Arrays indexed ``[kind code, series]`` of slot, coefficient and ``divides``,
    read off :func:`~mechcirc.circuit.law_terms` at unit value: a leaf's term is
    coefficient / (value·η) when ``divides`` (an impedance, in a series node),
    else coefficient · (value·η); slots as in :func:`_leaf_term` (0 real, +1 ω,
    −1 1/ω)."""
    slot, coef = np.zeros((len(_KIND_CODE), 2), dtype=np.int64), np.zeros((len(_KIND_CODE), 2))
    for kind, code in _KIND_CODE.items():
        for series in (0, 1):
            slot[code, series], coef[code, series] = _slot_term(
                kind, series, *law_terms(kind, 1.0, admittance=not series))
    return slot, coef


_LEAF_SLOT, _LEAF_COEF = _leaf_table()


def _flat_nodes(root: Node) -> tuple:
    """The tree in postorder as flat lists: ``(kind, kids, kstart, leaf_of, leaf_el,
    levers)``, kind 0 series, 1 parallel, 2 lever, 3 a lone leaf; node i's internal
    children are ``kids[kstart[i]:kstart[i + 1]]``; leaf j is ``leaf_el[j]`` of node
    ``leaf_of[j]``."""
    kind: list[int] = []
    kids: list[int] = []
    kstart = [0]
    leaf_of: list[int] = []          # the node each folded leaf belongs to
    leaf_el: list[Element] = []
    levers: list = []
    index: dict[int, int] = {}

    def lone_leaf(e: Element) -> int:
        # A leaf at the root or under a lever: a node of its own (kind 3),
        # holding the leaf as a one-term series node would.
        kind.append(3)
        kstart.append(len(kids))
        leaf_of.append(len(kind) - 1)
        leaf_el.append(e)
        return len(kind) - 1

    node: Any                     # dispatched on its exact type below
    for node in postorder(root):
        cls = type(node)
        if cls is Leaf:
            continue
        if cls is Reflect:
            c = node.child
            kids.append(lone_leaf(c.element) if type(c) is Leaf else index[id(c)])
            kind.append(2)
            levers.append(node.lever)
        else:
            me = len(kind)
            kind.append(0 if cls is Series else 1)
            for c in node.children:
                if type(c) is Leaf:
                    leaf_of.append(me)
                    leaf_el.append(c.element)
                else:
                    kids.append(index[id(c)])
        kstart.append(len(kids))
        index[id(node)] = len(kind) - 1
    if type(root) is Leaf:
        lone_leaf(root.element)
    return kind, kids, kstart, leaf_of, leaf_el, levers


def plan(root: Node) -> Plan:
    """The evaluation plan of ``root``, built once per tree (linear in its size).

    Each node's leaves are folded into three coefficients by the element laws
    (:func:`~mechcirc.circuit.law_terms`), with the constants of their error
    terms, exactly as :func:`evaluate`'s numpy path forms them at every call
    (the same IEEE operations in the same order, here vectorised over the
    leaves and, for a batch of designs, over the designs: :meth:`Plan.with_values`).

    Parameters
    ----------
    root : Node
        The tree compiled.

    Returns
    -------
    Plan
    """
    found = _PLANS.get(root)
    if found is not None:
        return found
    kind, kids, kstart, leaf_of, leaf_el, levers = _flat_nodes(root)
    kind_a = np.array(kind, dtype=np.int8)
    kstart_a, kids_a, owner = (np.array(x, dtype=np.int64) for x in (kstart, kids, leaf_of))
    code = np.array([_KIND_CODE[e.kind] for e in leaf_el], dtype=np.int64)
    scaled = np.array([e.value for e in leaf_el], dtype=float) * \
        np.array([e.eta for e in leaf_el], dtype=float)
    series = (kind_a[owner] != 1).astype(np.int64)
    slot = _LEAF_SLOT[code, series]
    count = np.zeros((len(kind), 3), dtype=np.int64)
    np.add.at(count, (owner, slot % 3), 1)        # 0 real, 1 ω, 2 (= −1) 1/ω
    n_kids = np.diff(kstart_a)
    # Postorder keeps every subtree contiguous, so a node's internal children are
    # the top rows of a stack when it is reached: its value takes the first of them.
    stack_slot = np.cumsum(1 - n_kids) - 1
    fold = (owner, series, slot % 3, _LEAF_COEF[code, series], count)
    ratios = np.array([lv.ratio for lv in levers], dtype=float).reshape(-1, 1)
    out = _fold_values(kind_a, kstart_a, kids_a, stack_slot.astype(np.int64),
                       int(stack_slot.max(initial=0)) + 1, tuple(leaf_el), tuple(levers),
                       fold, scaled[:, None], ratios)
    _PLANS[root] = out
    return out


def _fold_values(kind, kstart, kids, slot, n_slots, leaves, levers, fold, scaled,
                 ratios) -> Plan:
    """The plan with the leaves' values·η ``scaled`` (L, D) and lever ``ratios`` (R, D)
    folded into each node's coefficients and error constants, one row per design."""
    owner, series, col, coef, count = fold
    M, D = kind.shape[0], scaled.shape[1]
    if scaled.shape != (len(leaves), D) or ratios.shape != (len(levers), D):
        raise ValueError(f"need values of shape ({len(leaves)}, D) and ratios of shape "
                         f"({len(levers)}, D), got {scaled.shape} and {ratios.shape}")
    with np.errstate(all="ignore"):
        term = np.where((series == 1)[:, None], coef[:, None] / scaled, coef[:, None] * scaled)
        # Summed in child order from 0.0, as _combine sums them (ufunc.at is
        # unbuffered and applies the terms in the order given).
        acc = np.zeros((3, M, D))
        np.add.at(acc, (col, owner), term)
        real, om, inv = acc[0], acc[1], acc[2]
        m_u = _node_mu((real, inv, om), np.diff(kstart)[:, None])
        e_real, e_inv, e_om = _leaf_bound_terms((real, inv, om), (
            count[:, 0:1], count[:, 2:3], count[:, 1:2]), m_u)
    lever = kind == 2
    m_u[lever] = 0.0
    ratio = np.zeros((M, D))
    ratio[lever] = ratios
    # A node has a real part if its leaves give one (in any design) or any child has one.
    has = ((real != 0) | np.isnan(real)).any(axis=1).tolist()
    ks, kd = kstart.tolist(), kids.tolist()
    for i in range(M):      # (children first: their has[] is final)
        if not has[i]:
            has[i] = any(has[kd[q]] for q in range(ks[i], ks[i + 1]))

    def rows(x):                  # one contiguous row of M values per design
        return np.ascontiguousarray(x.T)

    return Plan(kind, np.array(has, dtype=bool), rows(real), rows(inv), rows(om), rows(e_real),
                rows(e_inv), rows(e_om), rows(m_u), kstart, kids, rows(ratio), slot, n_slots,
                leaves, levers, fold)


def _evaluate_compiled(kernel, p: Plan, omega: NDArray, error: bool, condition: bool):
    """:func:`evaluate` (without ``keep``) by the compiled plan."""
    flat = np.ascontiguousarray(omega.ravel())
    K, rho = evaluate_designs(p, flat[None, :], error or condition, kernel)
    K = K.reshape(omega.shape)
    if not (error or condition):
        return K
    rho = rho.reshape(omega.shape)
    return K, (rho / _U if condition and not error else rho)


def evaluate_designs(p: Plan, omega: NDArray, error: bool = False, kernel=None):
    """K (and the bound of its relative error, else None) of the plan's D designs
    at ``omega`` of shape (W,) (every design at the same ω) or (D, W), by the
    compiled plan; returns arrays of shape (D, W).

    This is :func:`evaluate`'s compiled path, a design at a time: one design
    (D = 1) is the single sweep.  Without numba (or with ``mechcirc._jit.COMPILED``
    False) a plan that carries :attr:`Plan.numpy` is evaluated by :func:`evaluate`
    over its designs, in chunks of rows (the same numbers); RuntimeError otherwise.
    By default (``COMPILED`` None) such a plan is not compiled for: where numba's
    cache does not hold the kernel yet, numpy runs (see :func:`compiled_evaluator`).

    Parameters
    ----------
    p : Plan
        From :func:`plan`, with the designs' values.
    omega : ndarray
        ω [rad/s], shape (W,) or (D, W).
    error : bool
        Also the bound of the relative error.
    kernel : callable, optional
        The compiled evaluator (:func:`compiled_evaluator` when None).

    Returns
    -------
    tuple of (ndarray, ndarray or None)
        K [m/(N·s)] and the bound, shape (D, W).
    """
    if kernel is None and _jit.COMPILED is not False:
        # Not compiled here by default where numpy can stand in (see evaluate).
        kernel = compiled_evaluator(compile=bool(_jit.COMPILED or _KERNEL) or p.numpy is None)
    omega = np.ascontiguousarray(np.atleast_2d(np.asarray(omega, dtype=float)))
    D = p.designs
    if omega.shape[0] not in (1, D):
        raise ValueError(f"omega must have 1 or {D} rows, got shape {omega.shape}")
    if kernel is None and p.numpy is None:
        raise RuntimeError("evaluating this plan needs numba (pip install numba)")
    K = np.empty((D, omega.shape[1]), dtype=complex)
    rho = np.empty(K.shape if error else (D, 0))
    if kernel is None:
        _evaluate_numpy(p.numpy, omega, error, K, rho)
    else:
        kernel(omega, *p.arrays(), error, K, rho)
    return K, (rho if error else None)


#: Design × ω points per numpy pass over designs (a few MB per array).
_NUMPY_CHUNK = 1 << 16


def _evaluate_numpy(numpy, omega: NDArray, error: bool, K: NDArray, rho: NDArray) -> None:
    """:func:`evaluate_designs` by :func:`evaluate` over rows of designs, into ``K`` and
    ``rho`` (``numpy`` is :attr:`Plan.numpy`)."""
    root, scaled, ratios = numpy
    D, W = K.shape
    step = max(1, _NUMPY_CHUNK // max(W, 1))
    for lo in range(0, D, step):
        part = slice(lo, lo + step)
        w = omega if omega.shape[0] == 1 else omega[part]
        out = evaluate(root, w, error=error, designs=tuple(
            {k: v[part] for k, v in d.items()} for d in (scaled, ratios)))
        if error:
            K[part], rho[part] = out
        else:
            K[part] = out


class _Value:
    """K of a node: ``array`` is X with K = jX when ``imaginary``, else K itself.

    With error tracking, ``mag`` is |K| and ``rho`` the bound of its relative error
    (:meth:`relative`); a series or parallel node leaves them unformed and keeps
    those of its sum S instead: ``sum_mag`` |S| and ``sum_err`` the bound of |Ŝ − S|,
    K being S (series) or 1/S (parallel, ``recip``).
    """

    __slots__ = ("imaginary", "array", "mag", "rho", "sum_err", "sum_mag", "recip")

    def __init__(self, imaginary: bool, array: NDArray, mag=None, rho=None):
        self.imaginary, self.array, self.mag, self.rho = imaginary, array, mag, rho
        self.sum_mag: Any = None
        self.sum_err: Any = None
        self.recip = False

    def relative(self) -> tuple:
        """``(ρ, |K|)``: the bound of K's relative error and |K| (the caller holds
        ``np.errstate(all="ignore")``)."""
        if self.rho is None:
            E, A = self.sum_err, self.sum_mag
            if self.recip:       # ρ(1/S) = ρ(S)/(1 − ρ(S)) + 4u, |1/S| = 1/|S|
                self.rho = _over_excess(E, A)
                self.rho += _U_RECIP_0D
                self.mag = np.reciprocal(A)
            else:
                self.rho, self.mag = E / A, A
        return self.rho, self.mag

    def complex(self) -> NDArray[np.complex128]:
        if not self.imaginary:
            return self.array
        out = np.zeros(self.array.shape, dtype=complex)
        out.imag = self.array
        return out


def _leaf_value(e: Element, omega, inv_omega, track: bool = False,
                designs: tuple | None = None) -> _Value:
    """K of a leaf standing alone (the root, or under a lever)."""
    real, inv, om = law_terms(e.kind, _scaled(e, designs))
    if LAWS[e.kind].power < 0:
        v = _Value(True, inv_omega * inv)
    elif LAWS[e.kind].power > 0:
        v = _Value(True, omega * om)
    else:
        v = _Value(False, np.full(omega.shape, real, dtype=complex))
    if track:
        v.mag = np.abs(v.array)
        v.rho = 4 * _U      # value·η, 1/s, 1/ω and the product
    return v


def _scaled(e: Element, designs: tuple | None = None):
    """value · η as a numpy float, so that 1/0 = ∞ (flagged) instead of ZeroDivisionError
    when the product underflows (a value near 1e-308 times a small η); with
    ``designs`` (see :func:`evaluate`) the designs' values·η, shape (D, 1)."""
    return designs[0][e.name] if designs is not None else np.float64(e.value) * np.float64(e.eta)


def _leaf_term(e: Element, series: bool, fast: bool = False,
               designs: tuple | None = None) -> tuple[int, Any]:
    """Where element ``e`` enters a series node's impedance sum (``series``) or a
    parallel node's admittance sum, and its coefficient there: slot 0 the real
    part, +1 the part times ω, −1 the part times 1/ω (by :func:`~mechcirc.circuit.law_terms`).

    ``fast``: in Python floats (the same IEEE operations as numpy scalars, without
    their per-operation overhead), numpy's only where value·η is 0 (1/0 = ∞).
    """
    if fast:
        try:
            real, inv, om = law_terms(e.kind, e.value * e.eta, admittance=not series)
        except ZeroDivisionError:
            with np.errstate(divide="ignore"):     # 1/0 = ∞ (flagged), not a warning
                real, inv, om = (float(t) for t in
                                 law_terms(e.kind, _scaled(e), admittance=not series))
    else:
        real, inv, om = law_terms(e.kind, _scaled(e, designs), admittance=not series)
    return _slot_term(e.kind, series, real, inv, om)



def _combine(parts: list, omega, inv_omega, zero, keep: bool, checked: bool,
             groups: list) -> _Value:
    """Series: K = Σ K_i.  Parallel: 1/K = Σ 1/K_i, over the node's internal children's
    values ``parts`` and its leaf groups ``groups`` (:func:`_leaf_groups`)."""
    series, sums, counts, has, bterms = groups
    real, im_inv, im_omega = sums       # leaf terms: real + j(im_inv/ω + im_omega·ω)
    has_real, has_inv, has_omega = has
    imag = inv_omega * im_inv if has_inv else None
    if has_omega:
        imag = omega * im_omega if imag is None else imag + omega * im_omega
    # A parallel node's terms are fresh reciprocals, and without ``keep`` a
    # child's value is dropped after this sum: the first term's array is then
    # reused in place instead of copied.
    own = keep and series
    cplx = None
    for v in parts:
        a = v.array if series else _inverse(v.array, v.imaginary, checked)
        if v.imaginary:
            imag = _plus(imag, a, own)
        else:
            cplx = _plus(cplx, a, own)
    if has_real:
        cplx = np.full(omega.shape, real, dtype=complex) if cplx is None else cplx + real
    if cplx is None:
        if imag is None:
            # Every term was exactly 0 (a value·η of ∞ gives 1/∞ = 0): the sum is 0.
            imag = np.zeros(omega.shape)
        total = _Value(True, imag)
    else:
        if imag is not None:
            cplx.imag += imag
        total = _Value(False, cplx)
    if zero is not None:
        _node_bound(total, parts, omega, inv_omega, groups, zero)
    if not series:              # K = 1/S
        total.array = _inverse(total.array, total.imaginary, checked)
    return total


def _inverse(a, imaginary: bool, checked: bool):
    """1/a of a value: 1/(jX) = j(−1/X) for an imaginary one (``a`` holds X), else the
    complex reciprocal (with :func:`_reciprocal`'s limits when ``checked``)."""
    return _MINUS_ONE / a if imaginary else _reciprocal(a) if checked else np.reciprocal(a)


def _plus(total, a, copy: bool):
    """``total`` + ``a``, in place; ``a`` itself (or its copy when ``copy``) where there is
    no ``total`` yet."""
    if total is None:
        return a.copy() if copy else a
    total += a
    return total


def _node_bound(total: _Value, parts: list, omega, inv_omega, groups: list, zero) -> None:
    """The bound E of |Ŝ − S| of a series or parallel node's sum S (``total``, before
    the reciprocal of a parallel node) and |Ŝ| into ``total`` (see :func:`evaluate`):
    Σ |tᵢ| (ρᵢ + m·u) over its leaf groups and its internal children's values ``parts``;
    ``zero`` is 0 in ω's shape."""
    series, sums, counts, has, bterms = groups
    if bterms is None:         # (kept for the next call with one design)
        mu = _node_mu(sums, len(parts))
        # (0-d arrays: see _ZERO)
        bterms = groups[4] = (np.asarray(mu), np.asarray(_U_RECIP + mu), tuple(
            np.asarray(t) for t in _leaf_bound_terms(sums, counts, mu)))
    mu, c, (b_real, b_inv, b_omega) = bterms
    # The leaf groups' share: b_real + b_inv/ω + b_omega·ω.
    bound = b_inv * inv_omega if has[1] else None
    if has[2]:
        t = b_omega * omega
        bound = t if bound is None else np.add(bound, t, bound)
    if has[0]:
        bound = np.full(omega.shape, b_real) if bound is None else np.add(bound, b_real, bound)
    spare = None                # a child's |S|, free once its term is formed
    for v in parts:             # Σ |tᵢ| (ρᵢ + m·u) of the internal children's terms
        if v.rho is None and v.recip is series:
            # The term is 1/S of the child's sum S (a parallel child's K, or the
            # admittance of a series child): |1/S| (ρ(S)/(1 − ρ(S)) + 4u + m·u), ρ(S)/(1 − ρ(S))
            # as E/(|S| − E) (:func:`_over_excess` written out: a call costs about as much
            # as one of its operations on a few hundred points).  Outputs positional and
            # the clamp against ``zero`` (ω's shape): 0.25 against 0.42 µs with a 0-d 0.
            E, A = spare = v.sum_err, v.sum_mag
            t = A - E
            np.maximum(t, zero, out=t)
            np.divide(E, t, t)
            np.add(t, c, t)
            np.divide(t, A, t)
        else:
            rho, mag = v.relative()
            if series:
                t = rho + mu
                t *= mag
            else:
                t = through_reciprocal(rho)
                t += c
                t /= mag
        bound = t if bound is None else np.add(bound, t, bound)
    total.sum_err = zero.copy() if bound is None else bound
    total.sum_mag = np.abs(total.array, out=None if spare is None else spare[1])
    total.recip = not series


def _leaf_groups(node, designs) -> list:
    """``[series, sums, counts, has, bound terms]`` of a series or parallel ``node``: its
    leaves summed by slot, real + j(im_inv/ω + im_omega·ω) (``sums``, of ``counts``
    leaves), which of the three take part, and ``(m·u, 4u + m·u, the leaves' share of
    the bound)`` (:func:`_leaf_bound_terms`), None until :func:`_combine` first needs it."""
    series = isinstance(node, Series)
    sums: list = [0.0, 0.0, 0.0]
    counts = [0, 0, 0]
    for c in node.children:
        if isinstance(c, Leaf):
            slot, term = _leaf_term(c.element, series, designs is None, designs)
            i = 0 if slot == 0 else (2 if slot > 0 else 1)
            sums[i] += term
            counts[i] += 1
    has = tuple(n > 0 for n in counts) if designs is not None else \
        tuple(bool(t) for t in sums)
    return [series, sums, counts, has, None]


def _node_mu(sums, n_parts: int):
    """m·u of a node's sum: m terms, its internal children and its nonzero leaf groups."""
    real, im_inv, im_omega = sums
    return (n_parts + (real != 0) + (im_inv != 0) + (im_omega != 0)) * _U


def _leaf_bound_terms(sums, counts, mu) -> tuple:
    """``(real, inv, omega)`` coefficients of the leaf groups' share of Σ |tᵢ| (ρᵢ + m·u)
    (see :func:`evaluate`), ``mu`` = m·u (:func:`_node_mu`): the share is real + inv/ω +
    omega·ω; scalars for a node of :func:`evaluate`, arrays for :func:`plan`'s nodes.

    A group of n same-signed scalars summed has ρ = n·u, and 2u more for value·η and 1/s,
    and 2u more (the imaginary groups) for the product with ω or 1/ω."""
    return tuple(abs(t) * ((n + extra) * _U + mu)
                 for t, n, extra in zip(sums, counts, (2, 4, 4)))


def through_reciprocal(rho: NDArray) -> NDArray:
    """A bound of the relative error of 1/x̂ given |x̂ − x| ≤ ρ|x̂|: ρ / (1 − ρ).

    The one reciprocal rule of the error bounds (the tree's parallel nodes, the
    resonances' anti-resonance function −1/X); :mod:`mechcirc._sp_kernel` computes
    the same in its compiled loop.  Callers hold ``np.errstate(all="ignore")``.

    Parameters
    ----------
    rho : ndarray or float
        The bound ρ of the relative error of x̂.

    Returns
    -------
    ndarray
        ρ / (1 − ρ), at least 1-d; ∞ from ρ ≥ 1 on (a zero denominator), NaN for NaN.
    """
    if not (isinstance(rho, np.ndarray) and rho.ndim):
        # A scalar ρ (a leaf's, constant in ω: fuzz seed 599): work on an array.
        rho = np.atleast_1d(np.asarray(rho, dtype=float))
    return _over_excess(rho, _ONE)          # ρ/(1 − ρ) as E/(A − E), A = 1


def _over_excess(E: NDArray, A: NDArray) -> NDArray:
    """ρ/(1 − ρ) for ρ = E/A, as E/(A − E): ∞ where E ≥ A (a zero denominator)."""
    out = A - E
    np.maximum(out, _ZERO, out=out)
    np.divide(E, out, out=out)
    return out


def _reciprocal(K: NDArray[np.complex128]) -> NDArray[np.complex128]:
    """1/K with 1/0 = ∞ and 1/∞ = 0 (numpy's complex division gives NaN for both)."""
    Y = np.reciprocal(K)       # as accurate as 1.0 / K (within 1.4e-16), twice as fast
    if not np.isfinite(Y).all():
        Y[np.isinf(K)] = 0.0
        Y[K == 0] = np.inf
    return Y


def _node_K(node: Node, values: dict, omega) -> NDArray[np.complex128]:
    return node.element.mobility(omega) if isinstance(node, Leaf) else values[id(node)]


def push_down(root: Node, values: dict, Q: NDArray, v: NDArray,
              omega: NDArray) -> dict[str, tuple]:
    """Carry the root's force ``Q`` [N] and velocity ``v`` [m/s] down to every element.

    Series children share Q, parallel children share v, a lever scales
    v by r and Q by 1/r.  Returns ``{element name: (Q, v)}`` arrays over ω.

    Parameters
    ----------
    root : Node
        The tree whose root carries ``Q`` and ``v``.
    values : dict
        ``id(node)`` → K, from ``evaluate(root, omega, keep=True)``.
    Q : ndarray
        The root's force [N].
    v : ndarray
        The root's velocity [m/s].
    omega : ndarray
        ω [rad/s].

    Returns
    -------
    dict[str, tuple of ndarray]
        Element name → (Q, v).
    """
    out: dict[str, tuple] = {}
    stack = [(root, Q, v)]
    with np.errstate(all="ignore"):
        while stack:
            node, q, u = stack.pop()
            if isinstance(node, Leaf):
                out[node.element.name] = (q, u)
            elif isinstance(node, Series):
                for c, s in zip(node.children, node.signs):
                    qc = q if s > 0 else -q
                    stack.append((c, qc, _node_K(c, values, omega) * qc))
            elif isinstance(node, Parallel):
                for c, s in zip(node.children, node.signs):
                    uc = u if s > 0 else -u
                    stack.append((c, uc / _node_K(c, values, omega), uc))
            else:
                r = node.lever.ratio * node.sign
                stack.append((node.child, q / r, u * r))
    return out
