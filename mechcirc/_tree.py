"""The series–parallel tree of a circuit: its nodes, and walks over it.

:class:`Leaf`, :class:`Series`, :class:`Parallel` and :class:`Reflect` nodes
(plain frozen data), built by :func:`mechcirc.reduction.reduce_circuit` and
evaluated by :mod:`mechcirc._tree_eval` (both re-exported by
:mod:`mechcirc.reduction`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union

from .circuit import Element, Lever

__all__ = ["Leaf", "Series", "Parallel", "Reflect", "Node", "Reduction", "leaves", "depth",
           "postorder"]


class _Printed:
    """What every tree node shares: it prints as its nested expression (:func:`_format`)."""

    __slots__ = ()

    def __str__(self) -> str:
        return _format(self)


@dataclass(frozen=True, eq=False)
class Leaf(_Printed):
    """One element of the circuit."""

    element: Element


@dataclass(frozen=True, eq=False)
class _Branches(_Printed):
    """The fields :class:`Series` and :class:`Parallel` share (``signs``: see Series)."""

    children: tuple["Node", ...]
    signs: tuple[int, ...]


@dataclass(frozen=True, eq=False)
class Series(_Branches):
    """Children carrying the same force; ``signs[i]`` is +1 where child i's
    orientation (n1 → n2) agrees with this node's, −1 where it is reversed."""


@dataclass(frozen=True, eq=False)
class Parallel(_Branches):
    """Children sharing the same velocity difference; ``signs`` as in :class:`Series`."""


@dataclass(frozen=True, eq=False)
class Reflect(_Printed):
    """A sub-network seen through a lever: K_primary = K_child / ratio².

    ``sign`` is −1 when the child's orientation runs from the lever's ``s2``
    to ``s1``.
    """

    child: "Node"
    lever: Lever
    sign: int = 1


Node = Union[Leaf, Series, Parallel, Reflect]


@dataclass(frozen=True)
class Reduction:
    """Result of :func:`reduce_circuit`: the tree and the unloaded elements' names."""

    tree: Node
    unloaded: tuple[str, ...]


def _format(root: _Printed) -> str:
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
        wrap = parent is not None       # a nested series or parallel run: in parentheses
        stack.append((")" if wrap else "", None))
        for i in range(len(item.children) - 1, -1, -1):     # pushed last to first
            stack.append((item.children[i], item))
            stack.append((sep if i else "(" if wrap else "", None))
    return "".join(out)


def leaves(root: Node) -> list[Element]:
    """The elements under ``root``, left to right (the leaves of :func:`postorder`).

    Parameters
    ----------
    root : Node
        The tree whose elements are listed.

    Returns
    -------
    list of Element
    """
    return [node.element for node in postorder(root) if isinstance(node, Leaf)]


def depth(root: Node) -> int:
    """Number of levels of the tree (a leaf alone: 1).

    Parameters
    ----------
    root : Node
        The tree measured.

    Returns
    -------
    int
    """
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
    """Every node of the tree, children before their parent (iterative).

    Parameters
    ----------
    root : Node
        The tree walked.

    Returns
    -------
    list of Node
    """
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
