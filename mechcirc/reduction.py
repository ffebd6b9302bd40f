"""Series–parallel reduction of a mechanical circuit to a tree, and its evaluation.

The network between the drive's terminals is reduced by the two theorems of
mechanical circuits (Grigoriev et al. 2002): elements in series add their K, elements in
parallel add their 1/K.  A lever whose secondary side closes on a sub-network
that touches the rest only at the lever (and possibly at one shared node,
such as the frame) reduces to that sub-network's K / r² on the primary.

The result is a tree of :class:`Leaf`, :class:`Series`, :class:`Parallel`
and :class:`Reflect` nodes (:mod:`mechcirc._tree`), evaluated vectorised over
ω by :func:`evaluate` (:mod:`mechcirc._tree_eval`, with :func:`plan` and
:func:`push_down`); this module builds the tree and is the public index of all three.

Cost: the reduction is one worklist pass, O(n) in the number of elements
(O(n·L) with L levers); the plan is O(n) once per tree; evaluation is
O(n · n_omega).
"""

from __future__ import annotations

import gc
from collections import deque
from dataclasses import dataclass
from typing import Any

from ._tree import Leaf, Node, Parallel, Reduction, Reflect, Series, depth, leaves, postorder
from ._tree_eval import (KERNEL_MIN_WORK, Plan, compiled_evaluator, evaluate, evaluate_designs,
                         plan, push_down)
from .circuit import Circuit, Lever
from .errors import NotSeriesParallelError, TopologyError, UnloadedElementWarning, warn
from .topology import adjacency, check_frame_paths, loaded_groups, reachable

__all__ = ["Leaf", "Series", "Parallel", "Reflect", "Node", "Reduction",
           "reduce_circuit", "reduce_network", "evaluate", "push_down", "leaves", "depth",
           "postorder", "plan", "Plan", "evaluate_designs", "compiled_evaluator",
           "KERNEL_MIN_WORK"]


# --------------------------------------------------------------------------
# Reduction
# --------------------------------------------------------------------------

@dataclass
class _Edge:
    n1: str
    n2: str
    node: Node


def reduce_circuit(circuit: Circuit) -> Reduction:
    """Reduce ``circuit`` between its drive's terminals.

    Warns :class:`~mechcirc.errors.UnloadedElementWarning` naming elements on
    no path between the terminals.

    Parameters
    ----------
    circuit : Circuit

    Returns
    -------
    Reduction
        The tree and the unloaded elements.

    Raises
    ------
    TopologyError
        If the terminals are not connected, or the network (or a lever) is
        not series–parallel reducible; names the nodes and elements to blame.
    """
    check_frame_paths(circuit)
    d = circuit.require_drive()
    # Reduction creates many small objects and no reference cycles; the cyclic
    # collector re-scanning them made large netlists super-linear (100k elements:
    # 5.5 s with it, 1.9 s without, see docs/performance.md).
    enabled = gc.isenabled()
    gc.disable()
    try:
        red = reduce_network(circuit.elements, circuit.levers, d.n1, d.n2,
                             drive_line=d.line, source=circuit.source)
    finally:
        if enabled:
            gc.enable()
    if red.unloaded:
        warn(f"{len(red.unloaded)} element(s) lie on no path between the drive's nodes "
             f"{d.n1!r} and {d.n2!r} and carry no force: {', '.join(red.unloaded)}",
             UnloadedElementWarning)
    return red


def reduce_network(elements, levers, a: str, b: str, *, drive_line: int = 0,
                   source: str = "<string>") -> Reduction:
    """Series–parallel reduction of ``elements`` and ``levers`` seen between nodes ``a`` and ``b``.

    Parameters
    ----------
    elements : sequence of Element
    levers : sequence of Lever
    a, b : str
        The terminals.
    drive_line : int
        The drive's line, for errors.
    source : str
        File name, for errors.

    Returns
    -------
    Reduction
    """
    unloaded: list[str] = []
    if not levers:
        # The common case, without the per-element ``_Edge`` records.
        tree = _reduce_edges([e.n1 for e in elements], [e.n2 for e in elements],
                             [_leaf(e) for e in elements], a, b, unloaded, drive_line, source)
    else:
        edges = [_Edge(e.n1, e.n2, _leaf(e)) for e in elements]
        tree = _reduce(edges, list(levers), a, b, unloaded, drive_line, source)
    if len(unloaded) > 1:
        # In the order the elements were given (the fast path finds them by the
        # order in which it strips dangling branches).
        order = {e.name: i for i, e in enumerate(elements)}
        unloaded.sort(key=lambda name: order.get(name, len(order)))
    return Reduction(tree, tuple(unloaded))


def _reduce(edges: list[_Edge], levers: list[Lever], a: str, b: str,
            unloaded: list[str], drive_line: int, source: str) -> Node:
    changed = True
    while levers and changed:
        changed = False
        for lv in levers:
            part = _secondary_part(lv, edges, levers, a, b)
            if part is None:
                continue
            sub_ids, sub_levers, t, s = part
            sub_edges = [edges[i] for i in sub_ids]
            if not sub_edges:
                where = f"{source}:{lv.line}:{lv.col or 1}"
                raise TopologyError(
                    f"lever {lv.name!r} (line {lv.line}): its secondary side {lv.s1!r}–"
                    f"{lv.s2!r} is left floating (no element closes it)",
                    nodes=(lv.s1, lv.s2), elements=(lv.name,),
                    location=where if lv.line and source != "<string>" else None)
            child = _reduce(sub_edges, sub_levers, t, s, unloaded, lv.line, source)
            sign = 1 if (t, s) == (lv.s1, lv.s2) else -1
            keep = set(range(len(edges))) - set(sub_ids)
            edges = [edges[i] for i in sorted(keep)]
            edges.append(_Edge(lv.p1, lv.p2, Reflect(child, lv, sign)))
            gone = {id(m) for m in sub_levers} | {id(lv)}
            levers = [m for m in levers if id(m) not in gone]
            changed = True
            break
    if levers:
        names = [lv.name for lv in levers]
        nodes = sorted({n for lv in levers for n in lv.terminals})
        raise NotSeriesParallelError(
            f"lever(s) {', '.join(names)} couple parts of the network that are not "
            f"series–parallel reducible (secondary sides are not closed sub-networks); "
            f"nodes {', '.join(nodes)}", nodes=nodes, elements=names)
    return _reduce_edges([e.n1 for e in edges], [e.n2 for e in edges],
                         [e.node for e in edges], a, b, unloaded, drive_line, source)


def _reduce_edges(n1s: list, n2s: list, nodes: list, a: str, b: str, unloaded: list[str],
                  drive_line: int, source: str) -> Node:
    """The tree of the two-poles ``nodes[i]`` between ``n1s[i]`` and ``n2s[i]``, seen from a → b.

    One pass (:func:`_series_parallel_runs`) strips dangling branches and
    reduces series and parallel pairs at once, building the flat nodes as it
    goes.  If that does not end in one edge between ``a`` and ``b`` (an
    unloaded part that is not itself series–parallel, a bridge, terminals
    that are not connected), the network is pruned to the drive's biconnected
    block first and the same pass runs again, now naming what is left if it
    stops short.
    """
    found = _series_parallel_runs(n1s, n2s, nodes, a, b)
    if found is None:
        # Only the edges in the biconnected block that holds the drive carry force.
        kept = loaded_groups([[pair] for pair in zip(n1s, n2s)], a, b, drive_line=drive_line,
                             source=source)
        keep = set(kept)
        unloaded.extend(el.name for i, node in enumerate(nodes) if i not in keep
                        for el in leaves(node))
        found = _series_parallel_runs([n1s[i] for i in kept], [n2s[i] for i in kept],
                                      [nodes[i] for i in kept], a, b, explain=True)
    root, dangling = found
    unloaded.extend(el.name for node in dangling for el in leaves(_close(node, 1)[0]))
    return root


_new, _set = object.__new__, object.__setattr__


def _leaf(element) -> Leaf:
    """``Leaf(element)`` without the frozen dataclass's ``__init__`` (35% of the cost):
    the same object, as compact (its fields set as ``__init__`` sets them, no instance
    dict made; while Leaf has that one field: tests/test_reduction.py compares them)."""
    node = _new(Leaf)
    _set(node, "element", element)
    return node


def _branches(cls, children: tuple, signs: tuple):
    """``cls(children, signs)`` for Series or Parallel, as :func:`_leaf` (20% of the cost)."""
    node = _new(cls)
    _set(node, "children", children)
    _set(node, "signs", signs)
    return node


class _Run:
    """A series or parallel run being grown (:class:`_SeriesRun`, :class:`_ParallelRun`):
    its operands, in the run's own orientation (the edge's n1 → n2 when stored), with
    their signs.

    A join of two operands neither of which is a run of its kind makes the
    finished Series or Parallel node at once (most runs end at two operands, as
    in a ladder); only a third operand reopens it as a run, whose ``children``
    and ``signs`` are lists, turned into deques the first time a long run must
    grow at its front (so that growing stays O(1) per operand)."""

    __slots__ = ("children", "signs")

    def __init__(self, children: list, signs: list):
        self.children: Any = children      # list, or deque once grown at the front
        self.signs: Any = signs

    def extend(self, children: tuple, signs: tuple) -> None:
        self.children.extend(children)
        self.signs.extend(signs)

    def prepend(self, children: tuple, signs: tuple) -> None:
        if type(self.children) is list:
            if len(self.children) < 64:
                self.children[:0] = children
                self.signs[:0] = signs
                return
            self.children, self.signs = deque(self.children), deque(self.signs)
        self.children.extendleft(reversed(children))
        self.signs.extendleft(reversed(signs))


class _SeriesRun(_Run):
    __slots__ = ()


class _ParallelRun(_Run):
    __slots__ = ()


#: The kind of a run: True series, False parallel (a Leaf or a Reflect: none); an
#: edge's Series or Parallel node is a run of two that may still grow.
_KINDS: dict[type, bool] = {Series: True, Parallel: False, _SeriesRun: True,
                            _ParallelRun: False}
#: Kind -> (its finished node, its run).
_NODE = {True: Series, False: Parallel}
_RUN = {True: _SeriesRun, False: _ParallelRun}


def _oriented(run, sign: int, series: bool) -> tuple[tuple, tuple]:
    """The operands of ``run`` (a run of kind ``series``) and their signs, turned to the
    orientation ``sign`` (a series run reversed runs its operands in the opposite order)."""
    if sign > 0:
        return tuple(run.children), tuple(run.signs)
    if series:
        return tuple(reversed(run.children)), tuple(-s for s in reversed(run.signs))
    return tuple(run.children), tuple(-s for s in run.signs)


def _close(node, sign: int):
    """``(node, sign)`` as a finished child: a run becomes a flat Series/Parallel
    turned to the parent's orientation (so that only leaves and lever
    reflections carry signs), leaves keep theirs."""
    series = _KINDS.get(type(node))
    if series is None or sign > 0 and type(node) is _NODE[series]:
        return node, sign
    return _branches(_NODE[series], *_oriented(node, sign, series)), 1


def _operands(node, sign: int, series: bool):
    """The operands ``node`` contributes to a run of kind ``series``, oriented by ``sign``:
    its own operands when it is a run of the same kind, else itself closed."""
    if _KINDS.get(type(node)) is series:
        return _oriented(node, sign, series)
    c, s = _close(node, sign)
    return (c,), (s,)


def _grown(run, s: int, other, so: int, series: bool, after: bool):
    """:func:`_join`'s ``(run, flip)`` where ``run`` (sign ``s``), a run of kind ``series``
    or its finished node, takes ``other`` (sign ``so``) ``after`` it on the path or
    before it.  A series run kept against the path (s < 0) holds the path's order
    reversed, so ``other`` goes to its other end; turned to the run's orientation,
    ``other``'s sign is ``so·s`` (signs are ±1)."""
    if type(run) is _NODE[series]:
        run = _RUN[series](list(run.children), list(run.signs))
    operands = _operands(other, so * s, series)
    if (not series or s > 0) == after:
        run.extend(*operands)
    else:
        run.prepend(*operands)
    return run, s < 0


def _join(x, sx: int, y, sy: int, series: bool):
    """The run of kind ``series`` of ``x`` then ``y`` with signs ``sx``, ``sy`` relative
    to the result's orientation ("path": for a series run, x's far end to y's).

    Returns ``(run, flip)``; ``flip`` is True when the run is kept in the opposite
    orientation to the path.  A run of the same kind is grown in place, the larger
    of the two when both are runs, so the whole reduction stays linear (the run
    then keeps its own orientation).
    """
    kx, ky = _KINDS.get(type(x)), _KINDS.get(type(y))
    if kx is series and (ky is not series or len(x.children) >= len(y.children)):
        return _grown(x, sx, y, sy, series, True)
    if ky is series:
        return _grown(y, sy, x, sx, series, False)
    # (_close but where it would change nothing: a leaf, a reflection, a node as it stands)
    if kx is not None and (sx < 0 or type(x) is not _NODE[kx]):
        x, sx = _close(x, sx)
    if ky is not None and (sy < 0 or type(y) is not _NODE[ky]):
        y, sy = _close(y, sy)
    return _branches(_NODE[series], (x, y), (sx, sy)), False


def _series_parallel_runs(n1s: list, n2s: list, nodes: list, a: str, b: str,
                          explain: bool = False):
    """Dangling-branch stripping and series/parallel reduction in one worklist
    pass on integer node ids.  Returns ``(root oriented a → b, dangling
    two-poles)``, or None when it does not end in one edge between a and b;
    with ``explain``, raises instead the error naming the nodes and elements
    left (:func:`_not_reducible`)."""
    ids: dict = {}
    U = [ids.setdefault(x, len(ids)) for x in n1s]
    W = [ids.setdefault(x, len(ids)) for x in n2s]
    E = list(nodes)
    built = None if a not in ids or b not in ids or a == b else _adjacency(U, W, E, len(ids))
    if built is None:
        if explain:
            raise _not_reducible(list(ids), nodes, a, b)
        return None
    adj, alive = built
    ia, ib = ids[a], ids[b]
    dangling: list = []
    queue: deque[int] = deque(range(len(ids)))
    pop, push = queue.popleft, queue.append
    while queue:
        n = pop()
        if n == ia or n == ib:
            continue
        an = adj[n]
        deg = len(an)
        if deg == 2:
            u, w, merged = _series_step(n, adj, U, W, E)
            alive -= 2 if merged else 1
            push(u)
            push(w)
        elif deg == 1:
            ((far, eid),) = an.items()
            an.clear()
            del adj[far][n]
            dangling.append(E[eid])
            E[eid] = None
            alive -= 1
            push(far)
    eid = adj[ia].get(ib)
    if alive != 1 or eid is None:
        if explain:
            raise _not_reducible([x for x, i in ids.items() if adj[i]],
                                 [_close(e, 1)[0] for e in E if e is not None], a, b)
        return None
    node, sign = _close(E[eid], 1 if U[eid] == ia else -1)
    if sign < 0:
        node = Series((node,), (-1,))
    return node, dangling


def _adjacency(U: list, W: list, E: list, N: int):
    """``(adj, edges alive)`` of the edges U[i] → W[i] on N nodes, or None on a self-loop."""
    # adj[n] maps each neighbour of node n to the one edge between them (a second
    # edge between the same two nodes is merged in parallel at once).
    adj: list[dict] = [{} for _ in range(N)]
    alive = 0
    for eid in range(len(E)):
        u, w = U[eid], W[eid]
        if u == w:
            return None
        au = adj[u]
        old = au.get(w)
        if old is not None:
            _merge_parallel(old, u, E[eid], U, W, E)
            E[eid] = None
            continue
        au[w] = adj[w][u] = eid
        alive += 1
    return adj, alive


def _series_step(n: int, adj: list, U: list, W: list, E: list):
    """Join node ``n``'s two edges in series: ``(u, w, merged in parallel with an edge u–w)``."""
    an = adj[n]
    (u, e1), (w, e2) = an.items()          # far ends u (of e1) and w (of e2)
    s1 = 1 if W[e1] == n else -1           # e1 runs u -> n ?
    s2 = 1 if U[e2] == n else -1           # e2 runs n -> w ?
    an.clear()
    au, aw = adj[u], adj[w]
    del au[n], aw[n]
    # The series run u -> w, kept in e1's slot.
    run, flip = _join(E[e1], s1, E[e2], s2, True)
    E[e2] = None
    start, end = (w, u) if flip else (u, w)
    old = au.get(w)
    if old is not None:
        E[e1] = None
        _merge_parallel(old, start, run, U, W, E)
        return u, w, True
    U[e1], W[e1], E[e1] = start, end, run
    au[w] = aw[u] = e1
    return u, w, False


def _merge_parallel(old: int, u: int, node, U: list, W: list, E: list) -> None:
    """Put ``node`` (running from ``u``) in parallel with edge ``old``."""
    sign = 1 if U[old] == u else -1
    run, flip = _join(E[old], 1, node, sign, False)
    E[old] = run
    if flip:
        U[old], W[old] = W[old], U[old]


def _secondary_part(lv: Lever, edges: list[_Edge], levers: list[Lever], a: str, b: str):
    """Find the sub-network closing ``lv``'s secondary, if it is separable.

    Returns ``(edge indices, levers, t, s)`` where the sub-network lies between
    ``t`` and ``s`` and touches the rest of the network at most at ``s``;
    ``None`` if the secondary side is entangled with the primary side.
    """
    pairs = [(e.n1, e.n2) for e in edges]
    for m in levers:
        pairs.append((m.p1, m.p2))
        if m is not lv:
            pairs += [(m.s1, m.s2), (m.p1, m.s1)]
    adj = adjacency([*pairs, (a, b)])
    for t, s in ((lv.s1, lv.s2), (lv.s2, lv.s1)):
        comp = reachable(adj, t, blocked=s)
        if comp & ({lv.p1, lv.p2, a, b} - {s}):
            continue
        ids = [i for i, e in enumerate(edges) if e.n1 in comp or e.n2 in comp]
        subs = [m for m in levers if m is not lv and set(m.terminals) & comp]
        return ids, subs, t, s
    return None


def _not_reducible(nodes: list[str], parts: list, a: str, b: str) -> NotSeriesParallelError:
    """The error naming the nodes and the elements (under ``parts``) left when the reduction
    stops short."""
    blocking_nodes = sorted(n for n in nodes if n not in (a, b))
    names = sorted(el.name for part in parts for el in leaves(part))
    return NotSeriesParallelError(
        f"the network is not series–parallel reducible between {a!r} and {b!r}: "
        f"nodes {_some(blocking_nodes)} and elements {_some(names)} form a "
        "bridge (use nodal analysis)", nodes=blocking_nodes, elements=names)


def _some(names: list[str], limit: int = 12) -> str:
    """Names for a message: all of them, or the first ``limit`` and a count."""
    if len(names) <= limit:
        return ", ".join(names)
    return ", ".join(names[:limit]) + f" and {len(names) - limit} more"
