"""Random series–parallel networks for property tests, with their own evaluator.

A network is a nested tuple: ``("leaf", kind, value)``, ``("s", [children])``
or ``("p", [children])``.  :func:`to_netlist` writes it as a netlist with
fresh internal nodes; :func:`reference_K` evaluates it directly from the
structure (plain complex arithmetic or mpmath), independently of mechcirc.
"""

from hypothesis import strategies as st

KINDS = ("mass", "spring", "damper")


def leaf(min_exp=-3, max_exp=3):
    return st.tuples(st.just("leaf"), st.sampled_from(KINDS),
                     st.floats(min_exp, max_exp).map(lambda x: 10.0 ** x))


def networks(max_leaves=12, min_exp=-3, max_exp=3):
    return st.recursive(
        leaf(min_exp, max_exp),
        lambda children: st.tuples(st.sampled_from(["s", "p"]),
                                   st.lists(children, min_size=2, max_size=4)),
        max_leaves=max_leaves)


def count_leaves(net):
    return 1 if net[0] == "leaf" else sum(count_leaves(c) for c in net[1])


def to_netlist(net, V0=1.0):
    lines = [f"drive V a 0 velocity={V0!r}"]
    counter = {"n": 0, "e": 0}

    def fresh():
        counter["n"] += 1
        return f"n{counter['n']}"

    def emit(node, n1, n2):
        if node[0] == "leaf":
            counter["e"] += 1
            lines.append(f"{node[1]} e{counter['e']} {n1} {n2} {node[2]!r}")
        elif node[0] == "p":
            for c in node[1]:
                emit(c, n1, n2)
        else:
            nodes = [n1] + [fresh() for _ in node[1][:-1]] + [n2]
            for c, u, w in zip(node[1], nodes, nodes[1:]):
                emit(c, u, w)

    emit(net, "a", "0")
    return "\n".join(lines) + "\n"


def reference_K(net, omega, j=1j, convert=float):
    """K of ``net`` at one ω, by the connection rules applied to the structure."""
    return reference_K_and_cancellation(net, omega, j, convert)[0]


def reference_K_and_cancellation(net, omega, j=1j, convert=float):
    """``(K, c)``: K of ``net`` at ω and the worst cancellation ratio met on the way.

    ``c`` is the largest Σ|x_i| / |Σ x_i| over every sum the connection rules
    form (K of series parts, 1/K of parallel parts); ``c = inf`` at an exact
    pole or zero of a sub-network.  A float evaluation can lose about
    log10(c) digits, so tests only demand full accuracy where ``c`` is modest.
    """
    if net[0] == "lever":           # a reflection scales K and adds no sum
        K, worst = reference_K_and_cancellation(net[2], omega, j, convert)
        return K / convert(net[1]) ** 2, worst
    if net[0] == "leaf":
        kind, value = net[1], convert(net[2])
        if kind == "mass":
            return -j / (omega * value), 1.0
        if kind == "spring":
            return j * omega / value, 1.0
        return 1 / value, 1.0
    results = [reference_K_and_cancellation(c, omega, j, convert) for c in net[1]]
    worst = max(c for _, c in results)
    terms = [K for K, _ in results]
    if net[0] == "p":
        if any(abs(t) == 0 for t in terms):
            return 0 * terms[0], float("inf")
        terms = [1 / t for t in terms]
    total = terms[0]
    for x in terms[1:]:
        total = total + x
    size = sum(abs(x) for x in terms)
    if abs(total) == 0:
        return total, float("inf")
    worst = max(worst, float(size / abs(total)))
    return (total if net[0] == "s" else 1 / total), worst


def networks_with_levers(max_leaves=10):
    """Like :func:`networks`, but a sub-network may sit behind a lever:
    ``("lever", ratio, child)`` has K = K_child / ratio²."""
    ratio = st.floats(-1, 1).map(lambda x: 10.0 ** x)
    return st.recursive(
        leaf(),
        lambda children: st.one_of(
            st.tuples(st.sampled_from(["s", "p"]), st.lists(children, min_size=2, max_size=3)),
            st.tuples(st.just("lever"), ratio, children)),
        max_leaves=max_leaves)


def to_netlist_with_levers(net, V0=1.0, drive="velocity"):
    """Netlist of a network that may hold levers (secondaries close to the frame)."""
    lines = [f"drive V a 0 {drive}={V0!r}"]
    counter = {"n": 0, "e": 0}

    def fresh():
        counter["n"] += 1
        return f"n{counter['n']}"

    def emit(node, n1, n2):
        counter["e"] += 1
        if node[0] == "leaf":
            lines.append(f"{node[1]} e{counter['e']} {n1} {n2} {node[2]!r}")
        elif node[0] == "lever":
            s1 = fresh()
            lines.append(f"lever L{counter['e']} {n1} {n2} {s1} 0 ratio={node[1]!r}")
            emit(node[2], s1, "0")
        elif node[0] == "p":
            for c in node[1]:
                emit(c, n1, n2)
        else:
            nodes = [n1] + [fresh() for _ in node[1][:-1]] + [n2]
            for c, u, w in zip(node[1], nodes, nodes[1:]):
                emit(c, u, w)

    emit(net, "a", "0")
    return "\n".join(lines) + "\n"
