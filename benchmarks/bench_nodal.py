"""Nodal analysis and resonances: speed against scikit-rf and closed forms (issue 3 §6–§7).

Prints, measured in the same run:

(a) a 1,000-element network that is not series–parallel (a chain whose
    nodes are also joined two apart), swept at 1,000 ω points by
    mechcirc's nodal method, against scikit-rf's ``Circuit`` on the same
    network (the same elements as impedances in the mobility analogy,
    K ↔ Z).  scikit-rf is timed on a subset of the frequencies (it is
    too slow for all of them) and its time per point is scaled up; the two
    results are compared at those points.
(b) ``resonances()`` of a 1,000-element spring–mass chain.
(c) adaptive against uniform logarithmic sweeps: points needed to resolve
    every |Q0| peak of a lightly damped chain within 1 %.

Run from the repository root: ``python benchmarks/bench_nodal.py``.
"""

from __future__ import annotations


import numpy as np

import mechcirc
from mechcirc.adaptive import adaptive_sweep
from timing import wall


def cross_chain(n_nodes: int) -> str:
    """Masses to the frame, springs i–i+1 and dampers i–i+2: not series–parallel."""
    lines = ["drive V n0 0 velocity=1"]
    for i in range(n_nodes):
        lines.append(f"mass m{i} n{i} 0 {1 + (i % 5) * 0.3}")
        lines.append(f"spring k{i} n{i} {f'n{i + 1}' if i + 1 < n_nodes else '0'} "
                     f"{1e4 * (1 + (i % 3))}")
        if i + 2 < n_nodes:
            lines.append(f"damper c{i} n{i} n{i + 2} {0.5 + (i % 4) * 0.1}")
    return "\n".join(lines)


def skrf_network(circuit: mechcirc.Circuit, omega: np.ndarray):
    """The same network as a scikit-rf Circuit (impedances in ohms stand for K)."""
    import skrf as rf
    from skrf.circuit import Circuit

    freq = rf.Frequency.from_f(omega / (2 * np.pi), unit="Hz")
    media = rf.media.DefinedGammaZ0(freq, z0=1.0)
    junctions: dict[str, list] = {}
    for e in circuit.elements:
        Z = e.mobility(omega)
        if e.n2 == "0" or e.n1 == "0":
            node = e.n1 if e.n2 == "0" else e.n2
            net = media.load((Z - 1.0) / (Z + 1.0), name=e.name)     # Z to ground, z0 = 1
            junctions.setdefault(node, []).append((net, 0))
        else:
            net = Circuit.SeriesImpedance(freq, Z, name=e.name, z0=1.0)
            junctions.setdefault(e.n1, []).append((net, 0))
            junctions.setdefault(e.n2, []).append((net, 1))
    port = Circuit.Port(freq, name="port", z0=1.0)
    junctions[circuit.drive.n1].append((port, 0))
    return Circuit(list(junctions.values())).network


def main() -> None:
    import platform

    print(f"python {platform.python_version()}, numpy {np.__version__}")
    # (a) nodal against scikit-rf
    n_nodes = 334
    circuit = mechcirc.parse(cross_chain(n_nodes))
    n_el = len(circuit.elements)
    omega = np.geomspace(10, 1e3, 1000)
    t_nodal, s = wall(lambda: circuit.sweep(omega, method="nodal"), repeat=3, best=True)
    t_fast, s_fast = wall(
        lambda: mechcirc.nodal.mobility_unrefined(circuit.nodal, omega), repeat=3, best=True)
    subset = omega[::125]
    try:
        t_skrf_half, _ = wall(lambda: skrf_network(circuit, subset[::2]), repeat=1, best=True)
        t_skrf, net = wall(lambda: skrf_network(circuit, subset), repeat=1, best=True)
    except ImportError:
        print("(a) scikit-rf not installed: pip install scikit-rf")
    else:
        Z = net.z[:, 0, 0]
        K = circuit.sweep(subset, method="nodal").K
        # Marginal cost per point (the difference of two runs), so that scikit-rf's
        # set-up time is not counted against it.
        per_point_skrf = (t_skrf - t_skrf_half) / (subset.size - subset[::2].size)
        print(f"(a) {n_el}-element non-series-parallel network, {omega.size} points, "
              f"{circuit.nodal.size} unknowns")
        print(f"    mechcirc nodal (refined, default) {t_nodal * 1e3:9.1f} ms "
              f"({t_nodal / omega.size * 1e6:.0f} µs/point)")
        print(f"    mechcirc nodal (no refinement)    {t_fast * 1e3:9.1f} ms "
              f"({t_fast / omega.size * 1e6:.0f} µs/point)")
        print(f"    scikit-rf Circuit, {subset[::2].size} and {subset.size} points: "
              f"{t_skrf_half * 1e3:.0f} and {t_skrf * 1e3:.0f} ms, marginal "
              f"{per_point_skrf * 1e6:.0f} µs/point -> about "
              f"{t_skrf + per_point_skrf * (omega.size - subset.size):.0f} s for {omega.size} points")
        print(f"    ratio scikit-rf / mechcirc per point: "
              f"{per_point_skrf / (t_nodal / omega.size):.0f}x (goal >= 20x)")
        print(f"    max relative difference of K at the shared points: "
              f"{np.max(np.abs(Z - K) / np.abs(K)):.1e}")
    # (b) resonances of a 1,000-element chain
    N = 500
    lines = ["drive V d 0 velocity=1", "spring k0 d n1 100"]
    for i in range(1, N + 1):
        lines.append(f"mass m{i} n{i} 0 1")
        lines.append(f"spring k{i} n{i} {f'n{i + 1}' if i < N else '0'} 100")
    chain = mechcirc.parse("\n".join(lines))
    chain.tree
    t_res, found = wall(lambda: mechcirc.parse("\n".join(lines)).resonances(), repeat=3, best=True)
    j = np.arange(1, N + 1)
    held = 20 * np.sin(j * np.pi / (2 * (N + 1)))
    res = np.array([r.omega for r in found if r.kind == "resonance"])
    print(f"(b) resonances of a {len(chain.elements)}-element chain: {len(found)} found in "
          f"{t_res:.2f} s (goal <= 1 s, parse included); worst relative error against the "
          f"closed form {np.max(np.abs(res / held - 1)):.1e}")
    # (c) adaptive against uniform
    text = ["drive V a 0 velocity=1"]
    prev = "a"
    for i in range(4):
        text += [f"spring k{i} {prev} n{i} {2e4 * (i + 1)}", f"damper c{i} {prev} n{i} {0.3}",
                 f"mass m{i} n{i} 0 {1.0 / (i + 1)}"]
        prev = f"n{i}"
    c = mechcirc.parse("\n".join(text))
    peaks = [r for r in c.resonances() if r.kind == "resonance"]
    # The peak of each resonance: the largest |Q0| within five half-power
    # bandwidths of its damped frequency, on a grid 10^5 times finer than the band.
    windows = [(r.omega_d - 5 * r.zeta * r.omega, r.omega_d + 5 * r.zeta * r.omega)
               for r in peaks]
    dense = [np.abs(c.sweep(np.linspace(lo, hi, 100001)).Q0).max() for lo, hi in windows]

    def resolved(result):
        q = np.abs(result.Q0)
        return all(q[(result.omega >= lo) & (result.omega <= hi)].max(initial=0) >= 0.99 * p
                   for (lo, hi), p in zip(windows, dense))

    t_ad, ad = wall(lambda: adaptive_sweep(c, 10, 1e4), repeat=1, best=True)
    n_uniform = None
    for n in np.unique(np.geomspace(100, 400000, 60).astype(int)):
        if all(resolved(c.sweep(np.geomspace(10, 1e4, m))) for m in range(n, n + 5)):
            n_uniform = n
            break
    print(f"(c) {len(peaks)} damped peaks (ζ = {', '.join(f'{r.zeta:.1e}' for r in peaks)}): "
          f"adaptive grid {len(ad.omega)} points ({t_ad * 1e3:.0f} ms), every peak within "
          f"1 %: {resolved(ad)}; a uniform log grid needs about {n_uniform} points")


if __name__ == "__main__":
    main()
