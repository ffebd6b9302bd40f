"""Random mechanical networks and their K(s) and roots in mpmath (never imports mechcirc).

A network is generated as netlist text together with a plain description of
it; the reference builds its own nodal matrices from that description
(mobility analogy: force ↔ current, velocity ↔ voltage; a mass admits s·m,
a spring k/s, a damper c; a lever of ratio r adds one force unknown with
the constraint r(v_p1 − v_p2) = v_s1 − v_s2) and solves them by
``mpmath.lu_solve`` at 30–50 digits.  Values in the netlist are written
with ``repr`` so that both sides see the same binary numbers.
"""

from __future__ import annotations

import mpmath
import numpy as np


def random_network(rng: np.random.Generator, *, n_nodes: int, damped: bool,
                   levers: int = 0, decades: float = 12.0):
    """(netlist text, spec, characteristic ω) of a random network that is not series–parallel in general.

    A random spanning tree to the frame (every node has a path to it), then
    about n/2 extra elements between random nodes (bridges, meshes); kinds
    mass and spring, values log-uniform over ``decades`` decades; with
    ``damped`` a light damper (ζ of order 1e-3…1e-2) beside some elements;
    ``levers`` levers between random nodes and the frame.
    """
    nodes = [f"n{i}" for i in range(1, n_nodes + 1)]
    elements = []

    def value():
        return float(10.0 ** rng.uniform(-decades / 2, decades / 2))

    for i, nd in enumerate(nodes):
        other = rng.choice(["0"] + nodes[:i])
        elements.append([str(rng.choice(["mass", "spring"])), nd, str(other), value()])
    for _ in range(max(1, n_nodes // 2)):
        a, b = rng.choice(["0"] + nodes, size=2, replace=False)
        elements.append([str(rng.choice(["mass", "spring"])), str(a), str(b), value()])
    # Every node needs a mass somewhere near it for a dynamic network, and a
    # spring: make sure both kinds occur.
    elements[0][0], elements[-1][0] = "mass", "spring"
    ms = [v for k, _, _, v in elements if k == "mass"]
    ks = [v for k, _, _, v in elements if k == "spring"]
    w_char = float(np.sqrt(np.median(ks) / np.median(ms)))
    if damped:
        for e in list(elements):
            if rng.random() < 0.5:
                kind, a, b, v = e
                # c ≈ 2ζ·sqrt(k·m) with the element's own scale at w_char.
                scale = v * w_char if kind == "mass" else v / w_char
                elements.append(["damper", a, b, float(scale * 10 ** rng.uniform(-3, -2))])
    lever_list = []
    for j in range(levers):
        a, b = rng.choice(nodes, size=2, replace=False)
        lever_list.append((f"L{j}", str(a), "0", str(b), "0", float(10 ** rng.uniform(-3, 3))))
    lines = ["drive V n1 0 velocity=1"]
    for i, (kind, a, b, v) in enumerate(elements):
        lines.append(f"{kind} e{i} {a} {b} {v!r}")
    for name, p1, p2, s1, s2, r in lever_list:
        lines.append(f"lever {name} {p1} {p2} {s1} {s2} ratio={r!r}")
    spec = {"elements": [tuple(e) for e in elements], "levers": lever_list,
            "drive": ("n1", "0")}
    return "\n".join(lines) + "\n", spec, w_char


def spec_of(text):
    """The spec of a netlist of elements, levers and a drive (numbers, no expressions;
    ``{name}`` already substituted, ``.param`` lines skipped)."""
    spec = {"elements": [], "levers": [], "drive": None}
    for line in text.splitlines():
        words = line.split()
        if not words or words[0] == ".param":
            continue
        if words[0] == "drive":
            spec["drive"] = (words[2], words[3])
        elif words[0] == "lever":
            spec["levers"].append((*words[1:6], float(words[6].split("=")[1])))
        else:
            spec["elements"].append((words[0], words[2], words[3], float(words[4])))
    return spec


def _matrices(spec, dps):
    names = sorted(({n for _, a, b, _ in spec["elements"] for n in (a, b)} |
                    {n for lv in spec["levers"] for n in lv[1:5]}) - {"0"})
    idx = {n: i for i, n in enumerate(names)}
    idx["0"] = -1
    n = len(names) + len(spec["levers"])
    with mpmath.workdps(dps):
        mats = {k: mpmath.zeros(n, n) for k in ("mass", "spring", "damper", "lever")}
        for kind, a, b, v in spec["elements"]:
            y = mpmath.mpf(v)
            i, j = idx[a], idx[b]
            A = mats[kind]
            if i >= 0:
                A[i, i] += y
            if j >= 0:
                A[j, j] += y
            if i >= 0 and j >= 0:
                A[i, j] -= y
                A[j, i] -= y
        for k, (_, p1, p2, s1, s2, r) in enumerate(spec["levers"]):
            col = len(names) + k
            for node, c in ((p1, mpmath.mpf(r)), (p2, -mpmath.mpf(r)), (s1, -1), (s2, 1)):
                i = idx[node]
                if i >= 0:
                    mats["lever"][i, col] += c
                    mats["lever"][col, i] += c
        c = mpmath.zeros(n, 1)
        a, b = (idx[x] for x in spec["drive"])
        if a >= 0:
            c[a] += 1
        if b >= 0:
            c[b] -= 1
    return mats, c


def K(spec, s, dps: int = 40):
    """K at the complex frequency s (s = jω on the axis), in mpmath; inf where A(s) is singular."""
    mats, c = _matrices(spec, dps)
    with mpmath.workdps(dps):
        s = mpmath.mpc(s)
        A = mats["damper"] + mats["lever"] + s * mats["mass"] + mats["spring"] / s
        try:
            x = mpmath.lu_solve(A, c)
        except ZeroDivisionError:
            return mpmath.mpc(mpmath.inf)
        return sum(c[i] * x[i] for i in range(c.rows))


def inverse_K(spec, s, dps: int = 40):
    """1/K from the held system [[A, c], [cᵀ, 0]], regular at the poles of K."""
    mats, c = _matrices(spec, dps)
    n = c.rows
    with mpmath.workdps(dps):
        s = mpmath.mpc(s)
        A = mats["damper"] + mats["lever"] + s * mats["mass"] + mats["spring"] / s
        B = mpmath.zeros(n + 1, n + 1)
        for i in range(n):
            for j in range(n):
                B[i, j] = A[i, j]
            B[i, n] = c[i]
            B[n, i] = c[i]
        e = mpmath.zeros(n + 1, 1)
        e[n] = 1
        return -mpmath.lu_solve(B, e)[n]


def det_root(spec, s0, pole: bool, dps: int = 40) -> complex:
    """The pole of K (``pole``) or its zero nearest the start s0, as a zero of a determinant.

    K = cᵀA⁻¹c is −det B / det A with B = [[A, c], [cᵀ, 0]]: its poles are the zeros of
    det A, its zeros those of det B.  A zero of K and a pole closer than the secant's
    first step (network 280 of seed 3: 1e-11 apart) cancel in K and in 1/K, so
    :func:`root` leaves for another root; each determinant has only its own.  Each is
    scaled by its value at s0·(1 + 1e-6), so that mpmath's check of |f| at the root
    does not depend on the units."""
    mats, c = _matrices(spec, dps)
    n = c.rows
    with mpmath.workdps(dps):
        def det(s):
            A = mats["damper"] + mats["lever"] + s * mats["mass"] + mats["spring"] / s
            if not pole:
                B = mpmath.zeros(n + 1, n + 1)
                for i in range(n):
                    for j in range(n):
                        B[i, j] = A[i, j]
                    B[i, n] = B[n, i] = c[i]
                A = B
            return mpmath.det(A)

        x0 = mpmath.mpc(s0)
        scale = det(x0 * (1 + mpmath.mpf(10) ** -6))
        return complex(mpmath.findroot(lambda s: det(s) / scale,
                                       (x0, x0 * (1 + mpmath.mpf(10) ** -12)),
                                       tol=mpmath.mpf(10) ** (-dps)))


def root(spec, s0, pole: bool, dps: int = 40) -> complex:
    """The zero of K (or of 1/K if ``pole``) nearest the start s0, by mpmath.findroot.

    The secant starts from s0 and s0·(1 + 1e-12), not mpmath's default s0 + 1/4: a
    weakly coupled mode puts a pole of K within 3e-11 of the zero sought (the
    45-element ladder's pair at 516.08 rad/s), and a first step of 1/4 lands past it."""
    with mpmath.workdps(dps):
        f = (lambda s: inverse_K(spec, s, dps)) if pole else (lambda s: K(spec, s, dps))
        x0 = mpmath.mpc(s0)
        return complex(mpmath.findroot(f, (x0, x0 * (1 + mpmath.mpf(10) ** -12)),
                                       tol=mpmath.mpf(10) ** (-dps)))
