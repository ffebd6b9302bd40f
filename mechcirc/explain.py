"""The series–parallel reduction written out step by step, for people.

:func:`explain` turns a circuit's reduction tree (:mod:`mechcirc.reduction`)
into numbered steps, innermost first: which elements combine in series
(same force Q; their K add), which in parallel (same velocity v; their 1/K
add), and each lever reflection written out: a sub-network of characteristic
K behind a lever of ratio r is seen on the primary as K / r², so a mass m
behind it acts as m·r² and a stiffness k as k·r².  Element values are shown
with their reflection factor η (Grigoriev et al. 2002): an element enters as value·η.
"""

from __future__ import annotations

from dataclasses import dataclass

from .circuit import LAWS, Circuit, element_unit
from .reduction import Leaf, Node, Parallel, Reflect, Series, leaves, postorder

__all__ = ["Step", "explain", "explain_lines"]


@dataclass(frozen=True)
class Step:
    """One reduction step: ``label = text`` with a sentence saying why."""

    label: str
    kind: str        # "series", "parallel" or "lever"
    operands: tuple[str, ...]
    text: str
    reason: str


def _leaf_formula(e) -> str:
    """K = (jω)^p / (value·η) of :data:`mechcirc.circuit.LAWS`, written for people."""
    s, power = f"{e.value * e.eta:.6g}", LAWS[e.kind].power
    if power == 0:
        return f"K = 1/{s}"
    if power == 1:
        return f"K = jω/{s}"
    return f"K = -j/({s}·ω)"          # (jω)^-1 / s


def explain(circuit: Circuit) -> tuple[list[Step], str]:
    """The reduction steps of ``circuit``, innermost first, and the root's label.

    Raises :class:`~mechcirc.errors.NotSeriesParallelError` when the network
    has no series–parallel tree (nodal analysis has no steps to show).

    Parameters
    ----------
    circuit : Circuit
        The circuit to explain; its network must be series–parallel.

    Returns
    -------
    tuple of (list of Step, str)
    """
    tree = circuit.tree
    labels: dict[int, str] = {}
    counts = {"series": 0, "parallel": 0, "lever": 0}
    prefix = {"series": "S", "parallel": "P", "lever": "R"}
    kinds = {Series: "series", Parallel: "parallel", Reflect: "lever"}
    steps: list[Step] = []

    def name(node: Node) -> str:
        return node.element.name if isinstance(node, Leaf) else labels[id(node)]

    for node in postorder(tree):
        if isinstance(node, Leaf):
            continue
        kind = kinds[type(node)]
        counts[kind] += 1
        label = f"{prefix[kind]}{counts[kind]}"
        labels[id(node)] = label
        operands: tuple[str, ...]
        if isinstance(node, Reflect):
            r, child = node.lever.ratio, name(node.child)
            text = f"{node.lever.name}[{child}]"
            reason = (f"lever {node.lever.name} (line {node.lever.line}), r = {r:.6g}: "
                      f"K = K({child}) / r² = K({child}) / {r * r:.6g}; behind it a mass m "
                      f"acts as m·r² = {r * r:.6g}·m and a stiffness k as {r * r:.6g}·k")
            operands = (child,)
        else:
            operands = tuple(name(c) for c in node.children)
            sep = " + " if kind == "series" else " | "
            text = sep.join(operands)
            reason = ("series: the same force Q through each; K adds" if kind == "series"
                      else "parallel: the same velocity v across each; 1/K adds")
        steps.append(Step(label, kind, operands, text, reason))
    return steps, name(tree)


def explain_lines(circuit: Circuit) -> list[str]:
    """:func:`explain` as printable lines (what ``mechcirc check --explain`` shows).

    Parameters
    ----------
    circuit : Circuit
        The circuit whose reduction is written out; its network must be series–parallel.

    Returns
    -------
    list of str
        A header naming the drive, each loaded element with its value·η and formula,
        each step with its reason, and last ``K = `` the root's label.
    """
    steps, root = explain(circuit)
    d = circuit.require_drive()
    lines = [f"K seen by drive {d.name} between {d.n1} and {d.n2}, "
             f"reduced in {len(steps)} step(s)"]
    loaded = {e.name for e in leaves(circuit.tree)}
    lines.append("elements (an element enters as value·η):")
    width = max((len(e.name) for e in circuit.elements), default=4)
    for e in circuit.elements:
        if e.name not in loaded:
            continue
        unit = element_unit(e.kind, d)
        value = f"{e.value:.6g} {unit}"
        if e.eta != 1:
            value += f" · η {e.eta:.6g} = {e.value * e.eta:.6g} {unit}"
        lines.append(f"  {e.name:<{width}}  {e.kind:<6}  {value:<42} {_leaf_formula(e)}")
    lwidth = max((len(s.label) for s in steps), default=2)
    for i, s in enumerate(steps, 1):
        lines.append(f"step {i}: {s.label:<{lwidth}} = {s.text}")
        lines.append(f"        {'':<{lwidth}}   {s.reason}")
    lines.append(f"K = {root}")
    return lines
