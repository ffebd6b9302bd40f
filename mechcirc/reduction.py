"""Series–parallel reduction of a mechanical circuit to a tree, and its evaluation.

The network between the drive's terminals is reduced by the two theorems of
mechanical circuits (DIGEST §1): elements in series add their K, elements in
parallel add their 1/K.  A lever whose secondary side closes on a sub-network
that touches the rest only at the lever (and possibly at one shared node,
such as the frame) reduces to that sub-network's K / r² on the primary.

The result is a tree of :class:`Leaf`, :class:`Series`, :class:`Parallel`
and :class:`Reflect` nodes, evaluated vectorised over ω by :func:`evaluate`
(through a flat :func:`plan` of the tree and the compiled
:mod:`mechcirc._sp_kernel` when numba is installed, else in numpy);
:func:`push_down` carries the drive's force and velocity back down the tree
to every element.  The element laws come from :func:`mechcirc.circuit.law_terms`.

Cost: the reduction is one worklist pass, O(n) in the number of elements
(O(n·L) with L levers); the plan is O(n) once per tree; evaluation is
O(n · n_omega).
"""

from __future__ import annotations

import gc
import weakref
from collections import deque
from dataclasses import dataclass
from typing import Iterator, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _jit
from .circuit import LAWS, Circuit, Element, Lever, law_terms
from .errors import NotSeriesParallelError, TopologyError, UnloadedElementWarning, warn
from .topology import check_frame_paths, loaded_groups, reachable

__all__ = ["Leaf", "Series", "Parallel", "Reflect", "Node", "Reduction",
           "reduce_circuit", "reduce_network", "evaluate", "push_down", "leaves", "depth",
           "postorder", "plan", "Plan"]


@dataclass(frozen=True, eq=False)
class Leaf:
    """One element of the circuit."""

    element: Element

    def __str__(self) -> str:
        return _format(self)


@dataclass(frozen=True, eq=False)
class Series:
    """Children carrying the same force; ``signs[i]`` is +1 where child i's
    orientation (n1 → n2) agrees with this node's, −1 where it is reversed."""

    children: tuple["Node", ...]
    signs: tuple[int, ...]

    def __str__(self) -> str:
        return _format(self)


@dataclass(frozen=True, eq=False)
class Parallel:
    """Children sharing the same velocity difference; ``signs`` as in :class:`Series`."""

    children: tuple["Node", ...]
    signs: tuple[int, ...]

    def __str__(self) -> str:
        return _format(self)


@dataclass(frozen=True, eq=False)
class Reflect:
    """A sub-network seen through a lever: K_primary = K_child / ratio².

    ``sign`` is −1 when the child's orientation runs from the lever's ``s2``
    to ``s1``.
    """

    child: "Node"
    lever: Lever
    sign: int = 1

    def __str__(self) -> str:
        return _format(self)


Node = Union[Leaf, Series, Parallel, Reflect]


@dataclass(frozen=True)
class Reduction:
    """Result of :func:`reduce_circuit`: the tree and the unloaded elements' names."""

    tree: Node
    unloaded: tuple[str, ...]


def _format(root: Node) -> str:
    """Nested expression: series ``a + b``, parallel ``a | b``, lever ``L[...]``.

    Iterative, so trees deeper than Python's recursion limit still print.
    """
    out: list[str] = []
    # Stack items: a node to print, or a literal string.
    stack: list = [(root, None)]
    while stack:
        item, parent = stack.pop()
        if isinstance(item, str):
            out.append(item)
            continue
        if isinstance(item, Leaf):
            out.append(item.element.name)
            continue
        if isinstance(item, Reflect):
            stack.append(("]", None))
            stack.append((item.child, None))
            out.append(f"{item.lever.name}[")
            continue
        sep = " + " if isinstance(item, Series) else " | "
        wrap = parent is not None
        parts: list = []
        if wrap:
            parts.append(("(", None))
        for i, child in enumerate(item.children):
            if i:
                parts.append((sep, None))
            parts.append((child, item))
        if wrap:
            parts.append((")", None))
        stack.extend(reversed(parts))
    return "".join(out)


def leaves(root: Node) -> Iterator[Element]:
    """The elements under ``root``, left to right."""
    stack = [root]
    while stack:
        node = stack.pop()
        if isinstance(node, Leaf):
            yield node.element
        elif isinstance(node, Reflect):
            stack.append(node.child)
        else:
            stack.extend(reversed(node.children))


# --------------------------------------------------------------------------
# Reduction
# --------------------------------------------------------------------------

@dataclass
class _Edge:
    n1: str
    n2: str
    node: Node


class _Binary:
    """Binary series/parallel node used while reducing (flattened afterwards)."""

    __slots__ = ("kind", "a", "b", "sign_a", "sign_b")

    def __init__(self, kind, a, sign_a, b, sign_b):
        self.kind, self.a, self.sign_a, self.b, self.sign_b = kind, a, sign_a, b, sign_b


def reduce_circuit(circuit: Circuit) -> Reduction:
    """Reduce ``circuit`` between its drive's terminals.

    Warns :class:`~mechcirc.errors.UnloadedElementWarning` naming elements on
    no path between the terminals.

    Raises
    ------
    TopologyError
        If the terminals are not connected, or the network (or a lever) is
        not series–parallel reducible; names the nodes and elements to blame.
    """
    check_frame_paths(circuit)
    d = circuit.drive
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
    """Series–parallel reduction of ``elements`` and ``levers`` seen between nodes ``a`` and ``b``."""
    unloaded: list[str] = []
    if not levers:
        # The common case, without the per-element ``_Edge`` records.
        tree = _reduce_edges([e.n1 for e in elements], [e.n2 for e in elements],
                             [Leaf(e) for e in elements], a, b, unloaded, drive_line, source)
    else:
        edges = [_Edge(e.n1, e.n2, Leaf(e)) for e in elements]
        tree = _reduce(edges, list(levers), a, b, unloaded, drive_line, source)
    if len(unloaded) > 1:
        # In the order the elements were given (the fast path finds them by the
        # order in which it strips dangling branches).
        order = {e.name: i for i, e in enumerate(elements)}
        unloaded.sort(key=lambda name: order.get(name, len(order)))
    return Reduction(tree, tuple(unloaded))


def _reduce(edges: list[_Edge], levers: list[Lever], a: str, b: str,
            unloaded: list[str], drive_line: int, source: str) -> Node:
    edges, levers = list(edges), list(levers)
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
                exc = TopologyError(
                    f"lever {lv.name!r} (line {lv.line}): its secondary side {lv.s1!r}–"
                    f"{lv.s2!r} is left floating (no element closes it)",
                    nodes=(lv.s1, lv.s2), elements=(lv.name,))
                if lv.line and source != "<string>":
                    exc.location = f"{source}:{lv.line}:{lv.col or 1}"
                raise exc
            child = _reduce(sub_edges, sub_levers, t, s, unloaded, lv.line, source)
            sign = 1 if (t, s) == (lv.s1, lv.s2) else -1
            keep = set(range(len(edges))) - set(sub_ids)
            edges = [edges[i] for i in sorted(keep)]
            edges.append(_Edge(lv.p1, lv.p2, Reflect(_flatten(child), lv, sign)))
            gone = {id(m) for m in sub_levers} | {id(lv)}
            levers = [m for m in levers if id(m) not in gone]
            changed = True
            break
    if levers:
        names = [lv.name for lv in levers]
        nodes = sorted({n for lv in levers for n in (lv.p1, lv.p2, lv.s1, lv.s2)})
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
    block first and reduced again, which also words the error.
    """
    found = _series_parallel_runs(n1s, n2s, nodes, a, b)
    if found is not None:
        root, dangling = found
        for node in dangling:
            unloaded.extend(el.name for el in leaves(_close(node, 1)[0]))
        return root
    edges = [_Edge(u, w, node) for u, w, node in zip(n1s, n2s, nodes)]
    edges = _prune(edges, a, b, unloaded, drive_line, source)
    return _flatten(_series_parallel(edges, a, b))


class _Run:
    """A series or parallel run being built: its operands, in the run's own
    orientation (the edge's n1 → n2 when stored), with their signs.

    ``kids`` and ``signs`` are lists, turned into deques the first time a long
    run must grow at its front (so that growing stays O(1) per operand)."""

    __slots__ = ("series", "kids", "signs")

    def __init__(self, series: bool, kids: list, signs: list):
        self.series, self.kids, self.signs = series, kids, signs

    def prepend(self, kids: list, signs: list) -> None:
        if type(self.kids) is list:
            if len(self.kids) < 64:
                self.kids[:0] = kids
                self.signs[:0] = signs
                return
            self.kids, self.signs = deque(self.kids), deque(self.signs)
        self.kids.extendleft(reversed(kids))
        self.signs.extendleft(reversed(signs))


def _close(node, sign: int):
    """``(node, sign)`` as a finished child: a run becomes a flat Series/Parallel
    turned to the parent's orientation (so that only leaves and lever
    reflections carry signs), leaves keep theirs."""
    if type(node) is not _Run:
        return node, sign
    if node.series:
        if sign > 0:
            return Series(tuple(node.kids), tuple(node.signs)), 1
        return Series(tuple(reversed(node.kids)), tuple(-s for s in reversed(node.signs))), 1
    if sign > 0:
        return Parallel(tuple(node.kids), tuple(node.signs)), 1
    return Parallel(tuple(node.kids), tuple(-s for s in node.signs)), 1


def _operands(node, sign: int, series: bool):
    """The operands ``node`` contributes to a run of kind ``series``, oriented by ``sign``:
    its own operands when it is a run of the same kind, else itself closed."""
    if type(node) is not _Run:
        return [node], [sign]
    if node.series == series:
        if sign > 0:
            return list(node.kids), list(node.signs)
        if series:
            return list(reversed(node.kids)), [-s for s in reversed(node.signs)]
        return list(node.kids), [-s for s in node.signs]
    c, s = _close(node, sign)
    return [c], [s]


def _join(x, sx: int, y, sy: int, series: bool):
    """The run of kind ``series`` of ``x`` then ``y`` with signs ``sx``, ``sy`` relative
    to the result's orientation ("path": for a series run, x's far end to y's).

    Returns ``(run, flip)``; ``flip`` is True when the run is kept in the opposite
    orientation to the path.  A run of the same kind is grown in place, the larger
    of the two when both are runs, so the whole reduction stays linear (the run
    then keeps its own orientation).
    """
    xr = type(x) is _Run and x.series == series
    yr = type(y) is _Run and y.series == series
    if xr and (not yr or len(x.kids) >= len(y.kids)):
        if not series:
            kids, signs = _operands(y, sy * sx, False)
            x.kids.extend(kids)
            x.signs.extend(signs)
        elif sx > 0:
            kids, signs = _operands(y, sy, True)
            x.kids.extend(kids)
            x.signs.extend(signs)
        else:
            # x runs against the path: in x's orientation y (reversed) comes first.
            x.prepend(*_operands(y, -sy, True))
        return x, sx < 0
    if yr:
        if not series:
            y.prepend(*_operands(x, sx * sy, False))
        elif sy > 0:
            y.prepend(*_operands(x, sx, True))
        else:
            kids, signs = _operands(x, -sx, True)
            y.kids.extend(kids)
            y.signs.extend(signs)
        return y, sy < 0
    if type(x) is _Run:
        x, sx = _close(x, sx)
    if type(y) is _Run:
        y, sy = _close(y, sy)
    return _Run(series, [x, y], [sx, sy]), False


def _series_parallel_runs(n1s: list, n2s: list, nodes: list, a: str, b: str):
    """Dangling-branch stripping and series/parallel reduction in one worklist
    pass on integer node ids.  Returns ``(root oriented a → b, dangling
    two-poles)``, or None when it does not end in one edge between a and b."""
    ids: dict = {}
    U = [ids.setdefault(x, len(ids)) for x in n1s]
    W = [ids.setdefault(x, len(ids)) for x in n2s]
    if a not in ids or b not in ids or a == b:
        return None
    ia, ib = ids[a], ids[b]
    N = len(ids)
    E = list(nodes)
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
        au[w] = eid
        adj[w][u] = eid
        alive += 1
    dangling: list = []
    queue: deque[int] = deque(range(N))
    pop, push = queue.popleft, queue.append
    while queue:
        n = pop()
        if n == ia or n == ib:
            continue
        an = adj[n]
        deg = len(an)
        if deg == 2:
            (u, e1), (w, e2) = an.items()          # far ends u (of e1) and w (of e2)
            s1 = 1 if W[e1] == n else -1           # e1 runs u -> n ?
            s2 = 1 if U[e2] == n else -1           # e2 runs n -> w ?
            an.clear()
            au, aw = adj[u], adj[w]
            del au[n], aw[n]
            # The series run u -> w, kept in e1's slot.
            run, flip = _join(E[e1], s1, E[e2], s2, True)
            E[e2] = None
            alive -= 1
            start, end = (w, u) if flip else (u, w)
            old = au.get(w)
            if old is not None:
                E[e1] = None
                _merge_parallel(old, start, run, U, W, E)
                alive -= 1
            else:
                U[e1], W[e1], E[e1] = start, end, run
                au[w] = e1
                aw[u] = e1
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
        return None
    node, sign = _close(E[eid], 1 if U[eid] == ia else -1)
    if sign < 0:
        node = Series((node,), (-1,))
    return node, dangling


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
    adj: dict[str, set[str]] = {}

    def link(u, w):
        adj.setdefault(u, set()).add(w)
        adj.setdefault(w, set()).add(u)

    for e in edges:
        link(e.n1, e.n2)
    for m in levers:
        if m is lv:
            link(m.p1, m.p2)
        else:
            link(m.p1, m.p2)
            link(m.s1, m.s2)
            link(m.p1, m.s1)
    link(a, b)
    for t, s in ((lv.s1, lv.s2), (lv.s2, lv.s1)):
        comp = reachable(adj, t, blocked=s)
        if comp & ({lv.p1, lv.p2, a, b} - {s}):
            continue
        ids = [i for i, e in enumerate(edges) if e.n1 in comp or e.n2 in comp]
        subs = [m for m in levers if m is not lv and
                ({m.p1, m.p2, m.s1, m.s2} & comp)]
        return ids, subs, t, s
    return None


def _prune(edges: list[_Edge], a: str, b: str, unloaded: list[str], drive_line: int,
           source: str) -> list[_Edge]:
    """Keep only edges in the biconnected block that holds the drive (they carry force)."""
    kept = set(loaded_groups([[(e.n1, e.n2)] for e in edges], a, b, drive_line=drive_line,
                             source=source))
    for i, e in enumerate(edges):
        if i not in kept:
            unloaded.extend(el.name for el in leaves(_flatten(e.node)))
    return [e for i, e in enumerate(edges) if i in kept]


def _series_parallel(edges: list[_Edge], a: str, b: str):
    """Worklist series/parallel reduction; returns the root node oriented a → b."""
    store: dict[int, list] = {}     # id -> [n1, n2, node]
    adj: dict[str, dict[int, None]] = {}
    pair: dict[frozenset, int] = {}
    next_id = 0
    queue: deque[str] = deque()

    def add(n1, n2, node):
        nonlocal next_id
        key = frozenset((n1, n2))
        old = pair.get(key)
        if old is not None:
            o = store[old]
            o[2] = _Binary("p", o[2], 1, node, 1 if o[0] == n1 else -1)
            queue.append(n1)    # their degrees changed
            queue.append(n2)
            return
        eid = next_id
        next_id += 1
        store[eid] = [n1, n2, node]
        adj.setdefault(n1, {})[eid] = None
        adj.setdefault(n2, {})[eid] = None
        pair[key] = eid
        queue.append(n1)
        queue.append(n2)

    def remove(eid):
        n1, n2, _ = store.pop(eid)
        del adj[n1][eid]
        del adj[n2][eid]
        del pair[frozenset((n1, n2))]

    for e in edges:
        add(e.n1, e.n2, e.node)
    while queue:
        n = queue.popleft()
        if n in (a, b) or n not in adj or len(adj[n]) != 2:
            continue
        e1, e2 = adj[n]
        u1, w1, node1 = store[e1]
        u2, w2, node2 = store[e2]
        u = w1 if u1 == n else u1          # far end of e1
        w = w2 if u2 == n else u2          # far end of e2
        s1 = 1 if w1 == n else -1          # e1 runs u -> n ?
        s2 = 1 if u2 == n else -1          # e2 runs n -> w ?
        remove(e1)
        remove(e2)
        del adj[n]
        add(u, w, _Binary("s", node1, s1, node2, s2))
    if len(store) != 1:
        blocking_nodes = sorted(n for n, es in adj.items() if es and n not in (a, b))
        names = sorted(el.name for _, _, node in store.values()
                       for el in leaves(_flatten(node)))
        raise NotSeriesParallelError(
            f"the network is not series–parallel reducible between {a!r} and {b!r}: "
            f"nodes {_some(blocking_nodes)} and elements {_some(names)} form a "
            "bridge (use nodal analysis)", nodes=blocking_nodes, elements=names)
    (n1, n2, node), = store.values()
    if n1 == a:
        return node
    # Root oriented b -> a: wrap so that the tree's orientation is a -> b.
    return _Binary("s", node, -1, None, 0)


def _some(names: list[str], limit: int = 12) -> str:
    """Names for a message: all of them, or the first ``limit`` and a count."""
    if len(names) <= limit:
        return ", ".join(names)
    return ", ".join(names[:limit]) + f" and {len(names) - limit} more"


def _flatten(root) -> Node:
    """Turn the binary reduction nodes into flat Series/Parallel tuples.

    Iterative (ladders nest deeper than the recursion limit); nested nodes of
    the same kind merge, keeping path order and orientation signs.  Linear in
    the number of nodes: each maximal run of binary nodes of one kind (a
    "head" and everything it absorbs) is gathered once into one flat node, so
    n elements in parallel or in series cost O(n), not O(n²) as merging the
    flattened children pairwise would.
    """
    if not isinstance(root, _Binary):
        return root
    done: dict[int, Node] = {}
    gathered: dict[int, list] = {}
    stack = [(root, False)]
    while stack:
        head, expanded = stack.pop()
        if id(head) in done:
            continue
        if not expanded:
            items = gathered[id(head)] = _gather(head)
            stack.append((head, True))
            stack.extend((c, False) for c, _ in items
                         if isinstance(c, _Binary) and id(c) not in done)
            continue
        children, signs = [], []
        for child, sign in gathered.pop(id(head)):
            if isinstance(child, _Binary):
                child = done[id(child)]
            if sign < 0 and isinstance(child, (Series, Parallel)):
                # Flip the child instead of marking it reversed, so that only
                # leaves and lever reflections carry orientation signs and series
                # chains print in path order.
                child, sign = _reversed(child), 1
            same = (isinstance(child, Series) and head.kind == "s") or \
                   (isinstance(child, Parallel) and head.kind == "p")
            if same:        # only when a head collapsed to a node of this kind
                children.extend(child.children)
                signs.extend(s * sign for s in child.signs)
            else:
                children.append(child)
                signs.append(sign)
        if len(children) == 1 and signs[0] == 1:
            done[id(head)] = children[0]
        else:
            cls = Series if head.kind == "s" else Parallel
            done[id(head)] = cls(tuple(children), tuple(signs))
    return done[id(root)]


def _gather(head: _Binary) -> list:
    """The operands of the run of ``head.kind`` binary nodes under ``head``, in
    path order with their signs; operands of the other kind stay binary."""
    kind = head.kind
    out = []
    stack = [(head, 1)]
    while stack:
        node, sign = stack.pop()
        if isinstance(node, _Binary) and node.kind == kind:
            items = [(c, s * sign) for c, s in _binary_items(node)]
            if kind == "s" and sign < 0:
                items.reverse()
            stack.extend(reversed(items))
        else:
            out.append((node, sign))
    return out


def _reversed(node):
    """The same two-pole with n1 and n2 exchanged."""
    signs = tuple(-s for s in node.signs)
    if isinstance(node, Series):
        return Series(node.children[::-1], signs[::-1])
    return Parallel(node.children, signs)


def _binary_items(node: _Binary):
    items = [(node.a, node.sign_a)]
    if node.b is not None:
        items.append((node.b, node.sign_b))
    return items


# --------------------------------------------------------------------------
# Evaluation
# --------------------------------------------------------------------------

def depth(root: Node) -> int:
    """Number of levels of the tree (a leaf alone: 1)."""
    deepest, stack = 1, [(root, 1)]
    while stack:
        node, d = stack.pop()
        deepest = max(deepest, d)
        if isinstance(node, (Series, Parallel)):
            stack.extend((c, d + 1) for c in node.children)
        elif isinstance(node, Reflect):
            stack.append((node.child, d + 1))
    return deepest


def postorder(root: Node) -> list[Node]:
    """Every node of the tree, children before their parent (iterative)."""
    order, stack = [], [root]
    while stack:
        node = stack.pop()
        order.append(node)
        if isinstance(node, (Series, Parallel)):
            stack.extend(node.children)
        elif isinstance(node, Reflect):
            stack.append(node.child)
    order.reverse()
    return order


#: Unit roundoff of float64 (half the machine epsilon): the relative error of
#: one correctly rounded operation.
_U = np.finfo(float).eps / 2
#: Relative error of a reciprocal 1/z: ≤ u for a real z; a complex division in
#: numpy (Smith's algorithm) stays within a few u, bounded here by 4u.
_U_RECIP = 4 * _U


def evaluate(root: Node, omega: ArrayLike, *, keep: bool = False, condition: bool = False,
             error: bool = False, _mode: str = "auto"):
    """K(ω) [m/(N·s)] of the tree at each ω [rad/s], vectorised.

    With ``keep=True`` returns ``(K, values)`` where ``values`` maps
    ``id(node)`` to the K of every series, parallel and lever node, for
    :func:`push_down`.  With ``error=True`` returns ``(K, bound)``: a running
    forward bound of the relative rounding error of K at each ω (see Notes).
    ``condition=True`` is the same bound divided by the unit roundoff (kept
    for callers of the former condition number).  Exact poles and zeros give
    ±inf or 0 without warnings (their bound is inf); ``inf - inf`` gives NaN
    (callers flag it).

    Notes
    -----
    Leaves are not evaluated one by one: the leaves of a series node add up
    to ``r + j(a/ω + b·ω)`` and those of a parallel node to an admittance
    ``g + j(c·ω + d/ω)``, so each node costs a few array operations whatever
    its number of leaves.  A lossless sub-network (no dampers) has a purely
    imaginary K = jX and is computed in real arithmetic on X, which is about
    four times cheaper than complex arithmetic and keeps 1/0 = ∞, 1/∞ = 0.

    The error bound follows the rounding through every sum, first order in the
    unit roundoff u.  A node forms S = Σ tᵢ from m terms (its leaf groups and its
    children; in parallel the terms are admittances 1/Kᵢ), each term known to a
    relative error ρᵢ, so that

        |Ŝ − S| ≤ Σ |tᵢ| (ρᵢ + m·u),     ρ(S) = that / |S|,

    where a leaf group of n same-signed scalars has ρ = (n + 2)·u, a reciprocal
    turns ρ into ρ/(1 − ρ) + 4u (taken as ρ + 2ρ² + 4u while ρ ≤ 1/2; ∞ from ρ ≥ 1 on:
    no digit is known) and a
    lever's division by r² adds 2u.  ρ is carried relative to the computed
    values, so only the rounding of each addition (the m·u term) is first order.  Cancellation at a node
    (Σ|tᵢ| ≫ |S|) raises the bound there; the children's errors are weighted by
    |tᵢ|/|S|, not multiplied down the tree, so a deep ladder with no
    cancellation keeps a bound of a few hundred u.
    """
    omega = np.asarray(omega, dtype=float)
    if not keep and _mode == "auto" and _jit.COMPILED is not False:
        p = plan(root)
        if _jit.COMPILED or _KERNEL or p.kind.size * omega.size >= KERNEL_MIN_WORK:
            kernel = compiled_evaluator()
            if kernel is not None:
                return _evaluate_compiled(kernel, p, omega, error, condition)
    if not keep and _mode == "auto":
        # Fast pass with numpy's reciprocal as is; it gives NaN for 1/0 where
        # 1/0 = ∞ is wanted, and a NaN never disappears downstream: the points
        # that end non-finite are evaluated again with the exact special cases.
        out = evaluate(root, omega, error=error, condition=condition, _mode="fast")
        K = out[0] if isinstance(out, tuple) else out
        bad = ~np.isfinite(K)
        if bad.any():
            again = evaluate(root, omega[bad], error=error, condition=condition,
                             _mode="checked")
            if isinstance(out, tuple):
                K[bad], out[1][bad] = again
            else:
                K[bad] = again
        return out
    checked = _mode != "fast"
    values: dict[int, _Value] = {}
    track = error or condition
    with np.errstate(all="ignore"):
        inv_omega = 1.0 / omega
        for node in postorder(root):
            if isinstance(node, Leaf):
                continue
            if isinstance(node, Reflect):
                child = _value_of(node.child, values, omega, inv_omega, track)
                val = _Value(child.imaginary, node.lever.reflect(child.array))
                if track:
                    val.mag = node.lever.reflect(child.mag)
                    # (a full array even over a single leaf, whose ρ is a scalar)
                    val.rho = np.broadcast_to(child.rho + 2 * _U, omega.shape).copy()
            else:
                val = _combine(node, values, omega, inv_omega, track, keep, checked)
            if not keep:
                kids = node.children if isinstance(node, (Series, Parallel)) else (node.child,)
                for c in kids:
                    values.pop(id(c), None)
            values[id(node)] = val
        top = _value_of(root, values, omega, inv_omega, track)
    K = top.complex()
    if keep:
        return K, {k: v.complex() for k, v in values.items()}
    if track:
        # ``rho`` bounds the error relative to the computed |K̂|; relative to the
        # true |K| ≥ |K̂|(1 − ρ) it is ρ / (1 − ρ).
        with np.errstate(all="ignore"):
            rho = _through_reciprocal(np.atleast_1d(np.asarray(top.rho, dtype=float)))
        rho = np.broadcast_to(rho, omega.shape).astype(float)
        rho[np.isnan(rho)] = np.inf
        return K, (rho / _U if condition and not error else rho)
    return K


#: The compiled plan (:mod:`mechcirc._sp_kernel`) evaluates when numba is installed
#: and ``mechcirc._jit.COMPILED`` is None (default), once the kernel is loaded or when
#: a call has at least :data:`KERNEL_MIN_WORK` node-points; True always; False never.
#: Importing numba and loading the compiled kernel from its cache takes about
#: 1 s once per process (0.7–1.1 s measured): below this many plan nodes × ω
#: points (about 0.15 s of the numpy path) a sweep does not start it.
KERNEL_MIN_WORK = 5_000_000
_KERNEL: list = []


def compiled_evaluator():
    """The compiled plan evaluator, or None without numba (imported on first use)."""
    if not _KERNEL:
        from . import _sp_kernel

        _KERNEL.append(_sp_kernel.evaluate_plan if _sp_kernel.HAVE_NUMBA else None)
    return _KERNEL[0]


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

    def arrays(self) -> tuple:
        return (self.kind, self.cplx, self.c_real, self.c_inv, self.c_om, self.e_real,
                self.e_inv, self.e_om, self.mu, self.kstart, self.kids, self.ratio,
                self.slot, self.n_slots)

    @property
    def designs(self) -> int:
        """D, the number of designs whose values the plan holds."""
        return self.c_real.shape[0]

    def with_values(self, scaled: ArrayLike, ratios: ArrayLike | None = None) -> "Plan":
        """The same plan for D designs: ``scaled[l, d]`` is value·η of leaf ``leaves[l]``
        in design d, ``ratios[r, d]`` the ratio of lever ``levers[r]`` (default: its own)."""
        scaled = np.asarray(scaled, dtype=float)
        if ratios is None:
            ratios = np.array([[lv.ratio] for lv in self.levers], dtype=float).reshape(-1, 1)
        return _fold_values(self.kind, self.kstart, self.kids, self.slot, self.n_slots,
                            self.leaves, self.levers, self._fold, scaled,
                            np.asarray(ratios, dtype=float))


_PLANS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


_KIND_CODE = {kind: i for i, kind in enumerate(LAWS)}


def _leaf_table() -> tuple:
    """Arrays indexed ``[kind code, series]`` of slot, coefficient and ``divides``,
    read off :func:`~mechcirc.circuit.law_terms` at unit value: a leaf's term is
    coefficient / (value·η) when ``divides`` (an impedance, in a series node),
    else coefficient · (value·η); slots as in :func:`_leaf_term` (0 real, +1 ω,
    −1 1/ω)."""
    slot = np.zeros((len(_KIND_CODE), 2), dtype=np.int64)
    coef = np.zeros((len(_KIND_CODE), 2))
    for kind, code in _KIND_CODE.items():
        p = LAWS[kind].power
        for series in (0, 1):
            sl = p if series else -p
            real, inv, om = law_terms(kind, 1.0, admittance=not series)
            slot[code, series] = sl
            coef[code, series] = real if sl == 0 else om if sl > 0 else inv
    return slot, coef


_LEAF_SLOT, _LEAF_COEF = _leaf_table()


def plan(root: Node) -> Plan:
    """The evaluation plan of ``root``, built once per tree (linear in its size).

    Each node's leaves are folded into three coefficients by the element laws
    (:func:`~mechcirc.circuit.law_terms`), with the constants of their error
    terms, exactly as :func:`evaluate`'s numpy path forms them at every call
    (the same IEEE operations in the same order, here vectorised over the
    leaves and, for a batch of designs, over the designs: :meth:`Plan.with_values`).
    """
    found = _PLANS.get(root)
    if found is not None:
        return found
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

    for node in postorder(root):
        cls = type(node)
        if cls is Leaf:
            continue
        if cls is Reflect:
            c = node.child
            ci = lone_leaf(c.element) if type(c) is Leaf else index[id(c)]
            kind.append(2)
            kids.append(ci)
            kstart.append(len(kids))
            levers.append(node.lever)
            index[id(node)] = len(kind) - 1
            continue
        me = len(kind)
        kind.append(0 if cls is Series else 1)
        for c in node.children:
            if type(c) is Leaf:
                leaf_of.append(me)
                leaf_el.append(c.element)
            else:
                kids.append(index[id(c)])
        kstart.append(len(kids))
        index[id(node)] = me
    if type(root) is Leaf:
        lone_leaf(root.element)
    kind_a = np.array(kind, dtype=np.int8)
    kstart_a = np.array(kstart, dtype=np.int64)
    kids_a = np.array(kids, dtype=np.int64)
    owner = np.array(leaf_of, dtype=np.int64)
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
        U = float(_U)
        n_kids = np.diff(kstart)[:, None]
        m_u = (n_kids + (real != 0) + (inv != 0) + (om != 0)) * U
        e_real = np.abs(real) * ((count[:, 0:1] + 2) * U + m_u)
        e_inv = np.abs(inv) * ((count[:, 2:3] + 4) * U + m_u)
        e_om = np.abs(om) * ((count[:, 1:2] + 4) * U + m_u)
    lever = kind == 2
    m_u[lever] = 0.0
    ratio = np.zeros((M, D))
    ratio[lever] = ratios
    # A node has a real part if its leaves give one (in any design) or any child has one.
    has = ((real != 0) | np.isnan(real)).any(axis=1).tolist()
    ks, kd = kstart.tolist(), kids.tolist()
    for i in range(M):
        if not has[i]:
            for q in range(ks[i], ks[i + 1]):
                if has[kd[q]]:
                    has[i] = True
                    break

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
    (D = 1) is the single sweep.  Raises RuntimeError without numba.
    """
    kernel = kernel or compiled_evaluator()
    if kernel is None:
        raise RuntimeError("evaluating a batch of designs needs numba (pip install numba)")
    omega = np.ascontiguousarray(np.atleast_2d(np.asarray(omega, dtype=float)))
    D = p.designs
    if omega.shape[0] not in (1, D):
        raise ValueError(f"omega must have 1 or {D} rows, got shape {omega.shape}")
    K = np.empty((D, omega.shape[1]), dtype=complex)
    rho = np.empty(K.shape if error else (D, 0))
    kernel(omega, *p.arrays(), error, K, rho)
    return K, (rho if error else None)


class _Value:
    """K of a node: ``array`` is X with K = jX when ``imaginary``, else K itself.

    With error tracking, ``mag`` is |K| and ``rho`` the bound of its relative error.
    """

    __slots__ = ("imaginary", "array", "mag", "rho")

    def __init__(self, imaginary: bool, array: NDArray, mag=None, rho=None):
        self.imaginary, self.array, self.mag, self.rho = imaginary, array, mag, rho

    def complex(self) -> NDArray[np.complex128]:
        if not self.imaginary:
            return self.array
        out = np.zeros(self.array.shape, dtype=complex)
        out.imag = self.array
        return out

    def reciprocal(self, checked: bool = True) -> "_Value":
        if self.imaginary:
            return _Value(True, -1.0 / self.array)     # 1/(jX) = j(-1/X)
        if not checked:
            return _Value(False, np.reciprocal(self.array))
        return _Value(False, _reciprocal(self.array))


def _value_of(node: Node, values: dict, omega, inv_omega, track: bool = False) -> _Value:
    if isinstance(node, Leaf):
        e = node.element
        real, inv, om = law_terms(e.kind, _scaled(e))
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
    return values[id(node)]


def _scaled(e: Element) -> np.float64:
    """value · η as a numpy float, so that 1/0 = ∞ (flagged) instead of ZeroDivisionError
    when the product underflows (a value near 1e-308 times a small η)."""
    return np.float64(e.value) * np.float64(e.eta)


def _leaf_term(e: Element, series: bool, fast: bool = False) -> tuple[int, float]:
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
            real, inv, om = (float(t) for t in
                             law_terms(e.kind, _scaled(e), admittance=not series))
    else:
        real, inv, om = law_terms(e.kind, _scaled(e), admittance=not series)
    p = LAWS[e.kind].power
    slot = p if series else -p
    return slot, (real if slot == 0 else om if slot > 0 else inv)


def _combine(node, values: dict, omega, inv_omega, track: bool = False,
             keep: bool = True, checked: bool = True) -> _Value:
    """Series: K = Σ K_i.  Parallel: 1/K = Σ 1/K_i.  Leaves are grouped by kind."""
    series = isinstance(node, Series)
    real = im_inv = im_omega = 0.0      # leaf terms: real + j(im_inv/ω + im_omega·ω)
    n_real = n_inv = n_omega = 0
    parts: list[_Value] = []
    for c in node.children:
        if isinstance(c, Leaf):
            slot, term = _leaf_term(c.element, series)
            if slot == 0:
                real += term
                n_real += 1
            elif slot > 0:
                im_omega += term
                n_omega += 1
            else:
                im_inv += term
                n_inv += 1
        else:
            parts.append(values[id(c)])
    if not series:
        terms = [v.reciprocal(checked) for v in parts]
    else:
        terms = parts
    imag = None
    if im_inv:
        imag = inv_omega * im_inv
    if im_omega:
        imag = omega * im_omega if imag is None else imag + omega * im_omega
    cplx = None
    # A parallel node's terms are fresh reciprocals, and without ``keep`` a
    # child's value is dropped after this sum: the first term's array is then
    # reused in place instead of copied.
    own = keep and series
    for v in terms:
        if v.imaginary:
            if imag is None:
                imag = v.array.copy() if own else v.array
            else:
                imag += v.array
        else:
            if cplx is None:
                cplx = v.array.copy() if own else v.array
            else:
                cplx += v.array
    if real:
        cplx = np.full(omega.shape, real, dtype=complex) if cplx is None else cplx + real
    if cplx is None and imag is None:
        # Every term was exactly 0 (a value·η of ∞ gives 1/∞ = 0): the sum is 0.
        imag = np.zeros(omega.shape)
    if cplx is None:
        total = _Value(True, imag)
    else:
        if imag is not None:
            cplx.imag += imag
        total = _Value(False, cplx)
    if track:
        m = len(parts) + (real != 0) + (im_inv != 0) + (im_omega != 0)
        mu = m * _U
        # Leaf groups: n same-signed scalars summed (n·u), value·η and 1/s (2u),
        # times ω or 1/ω (2u).
        bound = None
        if im_inv:
            bound = (abs(im_inv) * ((n_inv + 4) * _U + mu)) * inv_omega
        if im_omega:
            t = (abs(im_omega) * ((n_omega + 4) * _U + mu)) * omega
            bound = t if bound is None else np.add(bound, t, out=bound)
        for v in parts:
            if series:
                t = v.rho + mu
                t *= v.mag
            else:
                t = _through_reciprocal(v.rho)
                t += _U_RECIP + mu
                t /= v.mag
            bound = t if bound is None else np.add(bound, t, out=bound)
        if bound is None:
            bound = np.zeros(omega.shape)
        if real:
            bound += abs(real) * ((n_real + 2) * _U + mu)
        mag = np.abs(total.array)
        inv = np.reciprocal(mag)
        bound *= inv
        rho = bound
        if series:
            total.mag, total.rho = mag, rho
        else:
            total = total.reciprocal(checked)
            rho = _through_reciprocal(rho)
            rho += _U_RECIP
            total.mag, total.rho = inv, rho
        return total
    return total if series else total.reciprocal(checked)


def _through_reciprocal(rho: NDArray) -> NDArray:
    """A bound of the relative error of 1/x̂ given |x̂ − x| ≤ ρ|x̂|, ρ / (1 − ρ): as
    ρ + 2ρ² for ρ ≤ 1/2 (no smaller there), ∞ from ρ ≥ 1 on (and for NaN).

    Callers hold ``np.errstate(all="ignore")``; :mod:`mechcirc._sp_kernel` computes the same.
    """
    if not (isinstance(rho, np.ndarray) and rho.ndim):
        # A scalar ρ (a leaf's, constant in ω: fuzz seed 599): work on an array.
        rho = np.atleast_1d(np.asarray(rho, dtype=float))
    out = rho * rho
    out *= 2.0
    out += rho
    big = ~(rho <= 0.5)
    if big.any():
        out[big] = rho[big] / (1.0 - rho[big])
        out[~(rho < 1.0)] = np.inf
    return out


def _reciprocal(K: NDArray[np.complex128]) -> NDArray[np.complex128]:
    """1/K with 1/0 = ∞ and 1/∞ = 0 (numpy's complex division gives NaN for both)."""
    Y = np.reciprocal(K)       # as accurate as 1.0 / K (within 1.4e-16), twice as fast
    if not np.isfinite(Y).all():
        Y[np.isinf(K)] = 0.0
        Y[K == 0] = np.inf
    return Y


def _node_K(node: Node, values: dict, omega) -> NDArray[np.complex128]:
    if isinstance(node, Leaf):
        return node.element.mobility(omega)
    return values[id(node)]


def push_down(root: Node, values: dict, Q: NDArray, v: NDArray,
              omega: NDArray) -> dict[str, tuple]:
    """Carry the root's force ``Q`` [N] and velocity ``v`` [m/s] down to every element.

    Series children share Q, parallel children share v, a lever scales
    v by r and Q by 1/r.  Returns ``{element name: (Q, v)}`` arrays over ω.
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
