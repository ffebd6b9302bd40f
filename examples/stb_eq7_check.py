"""Reproduce the paper's eq. (7) for the STB heald mechanism with mechcirc.

Grigoriev, Terentiev & Grigoriev (2002) reduce the mechanical circuit of the
STB heald (shedding) motion, Fig. 3, by hand to one closed form, eq. (7)
(Grigoriev et al. 2002).  This script writes eq. (7) out with its own numpy code, not
mechcirc's, and compares it with mechcirc's series–parallel reduction of

1. ``netlists/stb_heald.mcir`` at 20,000 frequencies, ω = 1 … 10⁵ rad/s;
2. 200 random positive parameter sets × 50 random frequencies, each set
   written as a netlist (with ``.param`` lines and ``eta=`` expressions).

It prints the largest relative error |K_mechcirc − K_eq7| / |K_eq7|, and the
same for Q0 = V0/K (eq. 8).

Points near poles.  K is a reactance function: its poles and zeros are real
ω where the numerator or the denominator of eq. (7) vanishes.  Near them the
float64 value of eq. (7) itself loses digits to cancellation (and so would any
evaluation: K is ill-conditioned there), so a comparison says little.  The
script finds every pole and zero exactly enough — the positive real roots of
the numerator and denominator of eq. (7) as polynomials in x = ω² — and
leaves out the points with |ω − ω_r| ≤ 10⁻³ ω_r for some root ω_r.  It also
prints the largest error over all points, with none left out.

Run from the repository root::

    python examples/stb_eq7_check.py

Exit status 0 when the error away from the poles is at most 1e-12, else 1.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import mechcirc

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "stb_heald.mcir"
TOLERANCE = 1e-12
#: Points within this relative distance (in ω) of a pole or zero of K are left out.
NEAR_POLE = 1e-3


# --------------------------------------------------------------------------
# Eq. (2)-(7) of the paper, written out independently of mechcirc
# --------------------------------------------------------------------------

def lumped(p):
    """The paper's lumped quantities: M_I, M_II, M_III (eqs 2, 3, 6) and η_c."""
    m = [None] + [p[f"m{i}"] for i in range(1, 13)]
    eta1, eta2, eta3 = p["eta1"], p["eta2"], p["eta3"]
    eta_c = eta1**2 * eta2 * eta3**2
    eta_B, eta_C = eta1**2 * eta2, eta_c
    M_I = m[10] * m[11] * m[12] / (m[10] * m[12] + m[11] * m[12] + m[10] * m[11])
    M_II = m[6] * m[7] * m[8] * m[9] / (m[7] * m[8] * m[9] + m[6] * m[8] * m[9]
                                        + m[6] * m[7] * m[9] + m[6] * m[7] * m[8])
    M_III = (m[1] * m[2] * m[3] * m[4] * eta1**2 * eta_B * eta_C
             / (m[2] * m[3] * m[4] * eta1**2 * eta_B * eta_C + m[1] * m[3] * m[4] * eta_B * eta_C
                + m[1] * m[2] * m[4] * eta1**2 * eta_C + m[1] * m[2] * m[3] * eta1**2 * eta_B))
    return M_I, M_II, M_III, eta_c


def K_eq7(omega, p):
    """K(ω) [m/(N·s)] by eq. (7); vectorised over ``omega`` [rad/s]."""
    M_I, M_II, M_III, eta_c = lumped(p)
    m5, k0, k4, k5, eta4 = p["m5"], p["k0"], p["k4"], p["k5"], p["eta4"]
    w = np.asarray(omega, dtype=float)
    A = m5 * w**2 - k5
    B = M_I * M_II * w**2 - k0 * (M_I * eta4 + M_II)
    C = m5 * w**2 * (k4 * eta_c + k5) - k4 * k5 * eta_c
    num = w**2 * A * (M_III * B - M_I * M_II * k0 * eta4) - B * C
    den = w * M_III * (A * w**2 * M_I * M_II * k0 * eta4 + B * C)
    return 1j * num / den


def poles_and_zeros(p):
    """Positive ω [rad/s] where eq. (7)'s numerator or denominator is zero (ω = 0 aside)."""
    M_I, M_II, M_III, eta_c = lumped(p)
    m5, k0, k4, k5, eta4 = p["m5"], p["k0"], p["k4"], p["k5"], p["eta4"]
    P = np.polynomial.Polynomial           # polynomials in x = ω²
    x = P([0.0, 1.0])
    A = m5 * x - k5
    B = M_I * M_II * x - k0 * (M_I * eta4 + M_II)
    C = m5 * (k4 * eta_c + k5) * x - k4 * k5 * eta_c
    num = x * A * (M_III * B - M_I * M_II * k0 * eta4) - B * C
    den = A * x * M_I * M_II * k0 * eta4 + B * C
    roots = np.concatenate([num.roots(), den.roots()])
    real = roots[(np.abs(roots.imag) <= 1e-9 * np.abs(roots)) & (roots.real > 0)].real
    return np.sort(np.sqrt(real))


def away_from_poles(omega, roots):
    """Mask of the ω farther than NEAR_POLE (relative) from every root."""
    if roots.size == 0:
        return np.ones(omega.shape, dtype=bool)
    dist = np.abs(omega[:, None] - roots[None, :]) / roots[None, :]
    return dist.min(axis=1) > NEAR_POLE


# --------------------------------------------------------------------------
# Netlists
# --------------------------------------------------------------------------

def params_of(circuit):
    """m1..m12, k0, k4, k5 from the elements and eta1..eta4 from the .param lines."""
    p = {name: circuit.element(name).value
         for name in [f"m{i}" for i in range(1, 13)] + ["k0", "k4", "k5"]}
    p.update({k: circuit.params[k] for k in ("eta1", "eta2", "eta3", "eta4")})
    return p


def netlist_text(p, V0):
    """Fig. 3 as a netlist, with the paper's reflection factors as expressions."""
    r = {k: repr(float(v)) for k, v in p.items()}
    return f"""\
.param eta1={r['eta1']} eta2={r['eta2']} eta3={r['eta3']} eta4={r['eta4']}
.param etaB={{eta1^2 * eta2}} etaC={{eta1^2 * eta2 * eta3^2}}
drive  V  T 0 velocity={V0!r}
mass   m1  T A {r['m1']}
mass   m2  A B {r['m2']} eta={{eta1^2}}
mass   m3  B C {r['m3']} eta=etaB
mass   m4  C D {r['m4']} eta=etaC
spring k4  D 0 {r['k4']} eta=etaC
mass   m5  D E {r['m5']}
spring k5  E 0 {r['k5']}
mass   m6  D F {r['m6']}
mass   m7  F G {r['m7']}
mass   m8  G H {r['m8']}
mass   m9  H I {r['m9']} eta=eta4
mass   m10 I J {r['m10']} eta=eta4
mass   m11 J L {r['m11']}
mass   m12 L M {r['m12']} eta=eta4
spring k0  M 0 {r['k0']} eta=eta4
"""


def random_params(rng):
    """Positive parameters spread over decades; η4 = 1 as the paper requires."""
    p = {f"m{i}": 10 ** rng.uniform(-1, 1) for i in range(1, 13)}           # 0.1 … 10 kg
    p.update(k0=10 ** rng.uniform(3, 6), k4=10 ** rng.uniform(5, 8),       # N/m
             k5=10 ** rng.uniform(5, 8),
             eta1=10 ** rng.uniform(-0.5, 0.5), eta2=10 ** rng.uniform(-0.5, 0.5),
             eta3=10 ** rng.uniform(-0.5, 0.5), eta4=1.0)
    return p


def relative_error(a, b):
    return np.abs(a - b) / np.abs(b)


# --------------------------------------------------------------------------

def main() -> int:
    t0 = time.perf_counter()
    print("eq. (7) of Grigoriev et al. (2002) against mechcirc's reduction")
    print(f"(points with |ω − ω_r| ≤ {NEAR_POLE:g}·ω_r for a pole or zero ω_r of K are "
          "left out; 'all' includes them)\n")

    # 1. The file's own parameters, a dense sweep.
    circuit = mechcirc.load(NETLIST)
    p = params_of(circuit)
    V0 = circuit.drive.amplitude
    omega = np.geomspace(1.0, 1e5, 20_000)
    s = circuit.sweep(omega)
    ref = K_eq7(omega, p)
    roots = poles_and_zeros(p)
    keep = away_from_poles(omega, roots)
    err_K = relative_error(s.K, ref)
    err_Q = relative_error(s.Q0, V0 / ref)
    print(f"1. {NETLIST.name}: {omega.size} points, ω = {omega[0]:g} … {omega[-1]:g} rad/s")
    print(f"   tree: K = {circuit.tree}")
    print("   poles and zeros of K [rad/s]: " + ", ".join(f"{r:.6g}" for r in roots))
    print(f"   left out near them: {np.count_nonzero(~keep)} points")
    print(f"   max relative error of K : {err_K[keep].max():.3e}   (all points: "
          f"{err_K.max():.3e})")
    print(f"   max relative error of Q0: {err_Q[keep].max():.3e}   (all points: "
          f"{err_Q.max():.3e})")
    worst_file = max(err_K[keep].max(), err_Q[keep].max())

    # 2. Random parameter sets, each as a netlist of its own.
    rng = np.random.default_rng(2002)
    n_sets, n_omega = 200, 50
    worst, worst_all, left_out = 0.0, 0.0, 0
    for _ in range(n_sets):
        p = random_params(rng)
        omega = 10 ** rng.uniform(0, 4, size=n_omega)
        s = mechcirc.parse(netlist_text(p, V0=0.1)).sweep(omega)
        ref = K_eq7(omega, p)
        keep = away_from_poles(omega, poles_and_zeros(p))
        err = np.maximum(relative_error(s.K, ref), relative_error(s.Q0, 0.1 / ref))
        left_out += np.count_nonzero(~keep)
        worst_all = max(worst_all, err.max())
        if keep.any():
            worst = max(worst, err[keep].max())
    print(f"\n2. {n_sets} random parameter sets × {n_omega} random ω in [1, 1e4] rad/s "
          f"(masses 0.1…10 kg, stiffnesses 1e3…1e8 N/m, η1..η3 in [0.32, 3.2], η4 = 1)")
    print(f"   left out near poles or zeros: {left_out} of {n_sets * n_omega} points")
    print(f"   max relative error of K and Q0: {worst:.3e}   (all points: {worst_all:.3e})")

    overall = max(worst_file, worst)
    verdict = "agree" if overall <= TOLERANCE else "DISAGREE"
    print(f"\nmax relative error away from poles: {overall:.3e} (tolerance {TOLERANCE:g}): "
          f"mechcirc and eq. (7) {verdict}")
    print(f"({time.perf_counter() - t0:.1f} s)")
    return 0 if overall <= TOLERANCE else 1


if __name__ == "__main__":
    sys.exit(main())
