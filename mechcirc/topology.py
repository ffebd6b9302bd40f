"""Graph questions about a circuit, shared by the series–parallel and nodal methods.

* which elements carry force at all (those in the biconnected block that holds
  the drive; anything hanging off an articulation point carries none);
* whether every node can be referred to the frame (a node reached only through
  the far side of levers has no defined velocity: the network is singular).
"""

from __future__ import annotations

from collections import deque
from typing import Iterator, Sequence

from .circuit import FRAME, Circuit, node_names  # node_names: re-exported here
from .errors import TopologyError

__all__ = ["loaded_groups", "force_groups", "node_names", "check_frame_paths", "reachable"]


def adjacency(pairs) -> dict[str, set[str]]:
    """The undirected adjacency sets of the node pairs ``pairs`` (each pair both ways)."""
    adj: dict[str, set[str]] = {}
    for u, w in pairs:
        adj.setdefault(u, set()).add(w)
        adj.setdefault(w, set()).add(u)
    return adj


def reachable(adj: dict[str, set[str]], start: str, blocked: str | None = None) -> set[str]:
    """Nodes reachable from ``start`` in the adjacency map ``adj``, never entering ``blocked``.

    A breadth-first search on the plain map rather than networkx: the
    series–parallel reduction asks this once per lever side, and converting the
    whole map to a ``networkx.Graph`` each time made ``Circuit.tree`` 2.5–3.5×
    slower on a 300-lever network (1.6–2.5 s against 0.6–0.9 s), while the
    search itself only visits the (small) component it returns.

    Parameters
    ----------
    adj : dict[str, set of str]
    start : str
    blocked : str, optional

    Returns
    -------
    set of str
    """
    seen, queue = {start}, deque([start])
    while queue:
        u = queue.popleft()
        for w in adj.get(u, ()):
            if w != blocked and w not in seen:
                seen.add(w)
                queue.append(w)
    return seen


def force_groups(elements, levers) -> list[list[tuple[str, str]]]:
    """The groups of node pairs that carry force together, for :func:`loaded_groups`.

    One group per two-pole element (its two nodes), then one per lever: the six
    pairs of the clique of its four terminals, which a lever couples all together.
    Group ``i < len(elements)`` is ``elements[i]``, group ``len(elements) + k`` is
    ``levers[k]``.

    Parameters
    ----------
    elements : sequence of Element
        One group each, in order.
    levers : sequence of Lever
        One group of six pairs each, after the elements'.

    Returns
    -------
    list of list of (str, str)
    """
    groups = [[(e.n1, e.n2)] for e in elements]
    for lv in levers:
        t = lv.terminals
        groups.append([(t[i], t[j]) for i in range(4) for j in range(i + 1, 4)])
    return groups


def loaded_groups(groups: Sequence[Sequence[tuple[str, str]]], a: str, b: str,
                  *, drive_line: int = 0, source: str = "") -> list[int]:
    """Indices of the groups that lie in the block joining nodes ``a`` and ``b``.

    Each group is a list of node pairs that belong together: one pair for a
    two-pole, the pairs of a clique for a lever (its four terminals are coupled).

    Parameters
    ----------
    groups : sequence of sequence of (str, str)
    a, b : str
    drive_line : int
        For errors.
    source : str
        For errors.

    Returns
    -------
    list of int

    Raises
    ------
    TopologyError
        If no path of groups joins ``a`` and ``b``.
    """
    # Plain adjacency sets and an iterative Tarjan search, not networkx: the
    # sweep and resonance paths of the command line then do not import it
    # (≈ 0.1–0.15 s of start-up); tests/test_ux_notebooks.py checks the block
    # against networkx.biconnected_component_edges on random graphs.
    adj = adjacency(p for pairs in groups for p in pairs)  # (a self-loop: skipped by _block_with)
    # Joined by a path of elements: a, b neighbours (or one node), or else the block of
    # the drive's edge a–b (added below) holds a third node, a cycle through that edge
    # (the edge alone, a bridge, has no other path): no search of its own for the path.
    joined = a in adj and b in adj and (a == b or b in adj[a])
    if a in adj and b in adj:
        adj[a].add(b)
        adj[b].add(a)
        block = _block_with(adj, a, b)
        joined = joined or len(block) > 2
    if not joined:
        where = f" (line {drive_line})" if drive_line else ""
        raise TopologyError(
            f"the drive's nodes {a!r} and {b!r}{where} are not connected by any path "
            "of elements", nodes=(a, b),
            location=f"{source}:{drive_line}:1" if source and drive_line else None)
    # A lever whose sides share a node (p2 = s2 = '0') has a pair (u, u) in its
    # clique: it couples nothing and belongs to no block, so it is not asked for.
    # A pair (an edge) lies in the block when both its nodes do: two blocks share
    # at most one node, so an edge between two of a block's nodes is the block's
    # (every group, where the block holds every node).
    if len(block) == len(adj):
        return list(range(len(groups)))
    return [i for i, pairs in enumerate(groups)
            if all(u in block and w in block for u, w in pairs if u != w)]


def _block_with(adj: dict[str, set[str]], a: str, b: str) -> set[str]:
    """The nodes of the biconnected block of the simple graph ``adj`` that holds the
    edge a–b (Tarjan's lowpoints, iterative; self-loops belong to no block)."""
    disc, low = {a: 0}, {a: 0}
    edges: list[tuple[str, str]] = []
    stack: list[tuple[str, str | None, Iterator[str]]] = [(a, None, iter(adj[a]))]
    seen, push = disc.get, edges.append
    while stack:
        u, parent, it = stack[-1]
        du = disc[u]
        for w in it:
            if w == parent or w == u:
                continue
            dw = seen(w)
            if dw is None:
                disc[w] = low[w] = len(disc)
                push((u, w))
                stack.append((w, u, iter(adj[w])))
                break
            if dw < du:                     # a back edge to an ancestor
                if dw < low[u]:
                    low[u] = dw
                push((u, w))
        else:
            stack.pop()
            if not stack:
                break
            p = stack[-1][0]
            if low[u] < low[p]:
                low[p] = low[u]
            if low[u] >= disc[p]:           # p separates u's subtree: a block ends
                block: set[str] = set()
                while True:
                    e = edges.pop()
                    block.update(e)
                    if e == (p, u):
                        break
                if a in block and b in block:
                    return block
    return set()


def check_frame_paths(circuit: Circuit) -> None:
    """Raise if some node is joined to the frame only through a lever's other side.

    Elements join their two nodes; a lever joins its primary nodes and its
    secondary nodes but not the two sides.  The drive's nodes count as
    referenced when the circuit has no frame node at all (a free-floating
    network driven between two of its own nodes).

    Parameters
    ----------
    circuit : Circuit
    """
    if not circuit.levers:
        return          # only a lever can leave a node unreferenced
    d = circuit.require_drive()
    adj = adjacency([(e.n1, e.n2) for e in circuit.elements] + [(d.n1, d.n2)]
                    + [p for lv in circuit.levers for p in ((lv.p1, lv.p2), (lv.s1, lv.s2))])
    referenced = reachable(adj, FRAME if FRAME in adj else d.n1)
    lever_nodes = {n for lv in circuit.levers for n in lv.terminals}
    # Islands without levers are merely unloaded (they carry no force); ones
    # reached through a lever are singular.
    floating: set[str] = set()
    for n in lever_nodes - referenced:
        if n not in floating:
            floating |= reachable(adj, n)
    if floating:
        via = [lv.name for lv in circuit.levers if set(lv.terminals) & floating]
        first = next(lv for lv in circuit.levers if lv.name in via)     # via names one at least
        where = f"{circuit.source}:{first.line}:{first.col or 1}"     # FILE:LINE:COL for the CLI
        raise TopologyError(
            f"node(s) {', '.join(sorted(floating)[:12])} have no path to the frame "
            f"(reached only through lever(s) {', '.join(via) or '—'}"
            f"{f', line {first.line}' if first.line else ''}); the network is singular: "
            "join the lever's secondary side to node 0", nodes=sorted(floating), elements=via,
            location=where if first.line and circuit.source != "<string>" else None)
