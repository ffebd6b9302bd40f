"""The heald-drive design decision (examples/heald_design.py, docs/design.md) against
independent computations: the network's K(s) written out by hand from the element
laws (series–parallel, evaluated in mpmath and numpy), its zeros found by
mpmath.findroot, and the periodic steady state by harmonic superposition of an FFT
of the modified-sine cam law written out here."""

import importlib.util
import math
from pathlib import Path

import mpmath
import numpy as np
import pytest

import mechcirc

REPO = Path(__file__).resolve().parents[1]
NETLIST = REPO / "netlists" / "heald_damped.mcir"

# netlists/heald_damped.mcir in SI, by hand: .param eta1=0.8 eta2=1.25 eta3=0.9 eta4=1.
ETA_B = 0.8 ** 2 * 1.25
ETA_C = ETA_B * 0.9 ** 2
SERIES = [(2.0, 1.0), (1.5, 0.64), (1.2, ETA_B), (0.9, ETA_C)]       # m1..m4 (m, eta)
M5, K5, C5 = 0.8, 1.5e6, 100.0                                        # link DEF
CHAIN = [0.6, 0.5, 0.7, 0.4, 0.3, 0.5, 3.0]                           # m6..m12
K0, C0 = 4.0e4, 20.0                                                  # warp
C4 = 80.0                                                             # the rod's damping
STROKE, RISE, DWELL, RETURN = 0.08, 100.0, 80.0, 120.0


def parts(s, k4, lib=np, eta1=None):
    """(K, K_par, K_chain) at complex frequency s: K seen by the drive, K of the three
    parallel branches below node D, and of the branch m6..m12 + (k0 | c0); ``eta1``
    another value of that lever ratio (the netlist's etaB and etaC follow it)."""
    series, eta_c = SERIES, ETA_C
    if eta1 is not None:
        eta_b = eta1 ** 2 * 1.25
        eta_c = eta_b * 0.9 ** 2
        series = [(2.0, 1.0), (1.5, eta1 ** 2), (1.2, eta_b), (0.9, eta_c)]
    K = sum(1 / (s * m * eta) for m, eta in series)
    S5 = eta_c * (k4 / s + C4)
    K67 = 1 / (s * M5) + 1 / (K5 / s + C5)
    Kchain = sum(1 / (s * m) for m in CHAIN) + 1 / (K0 / s + C0)
    Kpar = 1 / (S5 + 1 / K67 + 1 / Kchain)
    return K + Kpar, Kpar, Kchain


def mp_root(k4, s0):
    """The zero of the closed-form K(s) near s0, 30 digits."""
    with mpmath.workdps(30):
        return complex(mpmath.findroot(lambda s: parts(s, mpmath.mpf(k4), mpmath)[0],
                                       mpmath.mpc(s0)))


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("heald_design",
                                                  REPO / "examples" / "heald_design.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module, module.study()


def test_the_closed_form_is_the_netlist():
    """The hand-written K(jω) is the netlist's (units mm, kN, g read right) to 1e-12."""
    c = mechcirc.load(NETLIST)
    w = np.geomspace(10, 1e4, 61)
    np.testing.assert_allclose(c.sweep(w).K, parts(1j * w, 5e5)[0], rtol=1e-12)


def test_first_resonance_before_and_after(example):
    _, r = example
    for k4, omega in ((5e5, r["omega1"]), (r["chosen"], r["omega1_after"])):
        c = mechcirc.load(NETLIST)
        found = example[0].first_resonance(example[0].with_rod(c, k4))
        s0 = complex(-found.zeta * found.omega, found.omega_d)
        s = mp_root(k4, s0)
        assert abs(abs(s) - omega) <= 1e-10 * omega
        assert abs(-s.real / abs(s) - found.zeta) <= 1e-10
    W = 2 * math.pi * 600 / 60
    assert 7.9 < r["omega1"] / W < 8.0                  # on the 8th harmonic
    assert 8.5 < r["omega1_after"] / W < 8.7            # between the 8th and 9th


def test_rod_sensitivity_and_the_stiffening(example):
    """(k/ω)∂ω/∂k of the rod against 40-digit central differences of the closed-form
    root; the exact stiffening by bisection on that root; the linear estimate
    within 1.1 percentage points of it (it undershoots: ω grows slower than
    linearly in k), and the chosen 0.6 kN/mm meets the target."""
    _, r = example
    s0 = mp_root(5e5, complex(-r["zeta1"] * r["omega1"], r["omega1"]))
    with mpmath.workdps(40):
        h = mpmath.mpf("1e-12")

        def ln_wn(k):
            return mpmath.log(abs(mpmath.findroot(lambda s: parts(s, k, mpmath)[0],
                                                  mpmath.mpc(s0))))

        ref = float((ln_wn(5e5 * (1 + h)) - ln_wn(5e5 * (1 - h))) / (2 * h))
    assert abs(r["S_rod"] - ref) <= 1e-10
    target = 8.5 * 2 * math.pi * 600 / 60
    # Bisection on [0.5, 0.6] kN/mm, each root started from the straight line between
    # the roots at the ends (the same branch: |s| stays between them).
    lo, hi = 5e5, 6e5
    s_lo, s_hi = s0, mp_root(6e5, s0 * 1.08)
    assert abs(s_lo) < target < abs(s_hi) < 550
    for _ in range(50):
        mid = (lo + hi) / 2
        s = mp_root(mid, s_lo + (s_hi - s_lo) * (mid - lo) / (hi - lo))
        assert abs(s_lo) <= abs(s) <= abs(s_hi)
        lo, hi, s_lo, s_hi = (mid, hi, s, s_hi) if abs(s) < target else (lo, mid, s_lo, s)
    exact = (lo + hi) / 2 / 5e5 - 1
    assert abs(r["exact"] - exact) <= 1e-8
    assert r["linear"] < r["exact"] and r["exact"] - r["linear"] <= 0.011
    assert r["chosen"] >= 5e5 * (1 + exact)


def _modified_sine(u):
    """ds/du of the modified-sine law on 0 ≤ u ≤ 1 (rise 1), written out."""
    mid = (u > 1 / 8) & (u < 7 / 8)
    return np.where(mid, math.pi - 3 * math.pi * np.cos(math.pi / 3 + 4 * math.pi * u / 3),
                    math.pi - math.pi * np.cos(4 * math.pi * u)) / (math.pi + 4)


def _periodic_forces(k4, rpm=600, n=3600 * 20):
    """Peak |Q| of the drive (over all n angles) and of the rod's and the warp's
    springs (over every 0.1°, as the example samples them) over one cycle: an FFT
    of the drive velocity (n samples, harmonics to n/2: its |V_k| ~ k⁻³), each
    harmonic through the closed-form K, back by inverse FFT."""
    W = 2 * math.pi * rpm / 60
    theta = np.arange(n) * 360.0 / n
    dx = np.zeros(n)
    up = theta < RISE
    dx[up] = STROKE * _modified_sine(theta[up] / RISE) / math.radians(RISE)
    down = (theta >= RISE + DWELL) & (theta < RISE + DWELL + RETURN)
    dx[down] = -STROKE * _modified_sine((theta[down] - RISE - DWELL) / RETURN) \
        / math.radians(RETURN)
    V = np.fft.rfft(W * dx)
    k = np.arange(V.size)
    s = 1j * k[1:] * W
    K, Kpar, Kchain = parts(s, k4)
    Q = np.zeros_like(V)
    Q[1:] = V[1:] / K
    vD = Q[1:] * Kpar
    rod = np.zeros_like(V)
    rod[1:] = ETA_C * k4 / s * vD
    warp = np.zeros_like(V)
    warp[1:] = K0 / s * (vD / Kchain) / (K0 / s + C0)
    for a in (Q, rod, warp):
        a[-1] = 0
    return [float(np.abs(np.fft.irfft(a, n)[::step]).max())
            for a, step in ((Q, 1), (rod, n // 3600), (warp, n // 3600))]


def test_peak_forces_before_and_after(example):
    """The periodic steady state at 600 rpm against harmonic superposition with the
    closed-form K: within 1e-4 of the drive's peak force (periodic's tolerance;
    its tail bound covers every element's force the same way)."""
    _, r = example
    for k4, keys in ((5e5, ("peak_before", "rod_before", "warp_before")),
                     (r["chosen"], ("peak_after", "rod_after", "warp_after"))):
        ref = _periodic_forces(k4)
        for key, value in zip(keys, ref):
            assert abs(r[key] - value) <= 1e-4 * ref[0], (key, r[key], value)
    assert r["rod_after"] < 0.85 * r["rod_before"]
    assert r["warp_after"] < 0.75 * r["warp_before"]


def test_a_stiffer_rod_still_is_worse():
    """docs/design.md: at 0.7 kN/mm the first resonance is at 9.14 Ω (near the 9th
    harmonic) and the rod's peak force is 239.4 N, more than at 0.6 kN/mm (217.9 N):
    both from the closed form alone."""
    W = 2 * math.pi * 600 / 60
    s = mp_root(7e5, complex(-0.046 * 9.1 * W, 9.1 * W))
    assert round(abs(s) / W, 2) == 9.14
    rod = _periodic_forces(7e5)[1]
    assert round(rod, 1) == 239.4 and rod > _periodic_forces(6e5)[1] + 20


def test_sweep_sensitivity_at_the_harmonics(example):
    """(k/|Q0|)∂|Q0|/∂k of the rod at 7Ω, 8Ω, 9Ω against central differences of the
    closed form (step 1e-6)."""
    _, r = example
    W = 2 * math.pi * 600 / 60
    s = 1j * W * np.array([7.0, 8.0, 9.0])
    h = 1e-6
    fd = (np.log(np.abs(1 / parts(s, 5e5 * (1 + h))[0]))
          - np.log(np.abs(1 / parts(s, 5e5 * (1 - h))[0]))) / (2 * h)
    np.testing.assert_allclose(r["dQ0_rel"], fd, rtol=1e-6)


def test_the_example_runs(capsys, monkeypatch):
    from cli_helpers import run_script

    status, out, err = run_script(REPO / "examples" / "heald_design.py", [], capsys, monkeypatch)
    assert status == 0, out + err
    assert "exact re-solve: 16.88%" in out


def _band_min_abs_K(eta1=None, lo=470.0, hi=560.0, k4=5e5):
    """min |K(jω)| over [lo, hi] of the closed form: a 20,001-point grid, then a
    golden-section search in mpmath (30 digits) between the grid's neighbours."""
    w = np.linspace(lo, hi, 20001)
    i = int(np.argmin(np.abs(parts(1j * w, k4, eta1=eta1)[0])))
    with mpmath.workdps(30):
        def f(x):
            return abs(parts(mpmath.mpc(0, x), mpmath.mpf(k4), mpmath, eta1)[0])

        a, b = mpmath.mpf(w[max(i - 1, 0)]), mpmath.mpf(w[min(i + 1, w.size - 1)])
        g = (3 - mpmath.sqrt(5)) / 2
        for _ in range(150):
            x1, x2 = a + g * (b - a), b - g * (b - a)
            a, b = (a, x2) if f(x1) <= f(x2) else (x1, b)
        return float(f((a + b) / 2))


def test_the_lever_variant_against_the_closed_form():
    """docs/design.md §5: the batch's first resonance at eta1 = 0.8 and 0.879 is the
    closed form's zero, and its least |K| over 470 … 560 rad/s (the drive force's
    peak, |Q0| = |V0|/|K|) the closed form's."""
    from mechcirc.batch import designs

    etas = (0.8, 0.879)
    ds = designs(NETLIST.read_text(), {"eta1": np.array(etas)})
    res = ds.resonances(omega_max=600)
    ex = ds.extremes([470.0, 560.0], resonances=res)
    for d, eta1 in enumerate(etas):
        r = min((x for x in res.list(d) if x.kind == "resonance"), key=lambda x: x.omega)
        with mpmath.workdps(30):
            s = complex(mpmath.findroot(lambda z: parts(z, mpmath.mpf(5e5), mpmath, eta1)[0],
                                        mpmath.mpc(complex(-r.zeta * r.omega, r.omega_d))))
        assert abs(abs(s) - r.omega) <= 1e-12 * r.omega
        assert ex.K_min[d] == pytest.approx(_band_min_abs_K(eta1), rel=1e-14)   # 4.4e-16
    assert 534.07 < res.list(1)[0].omega < 534.5          # just past 8.5 Ω: 534.27
    assert ex.Q0_max[1] / ex.Q0_max[0] == pytest.approx(ex.K_min[0] / ex.K_min[1], rel=1e-14)
    assert 1.24 < ex.Q0_max[1] / ex.Q0_max[0] < 1.26            # "by a quarter"
    # The stiffer rod instead (0.6 kN/mm): 263.0 N against 251.6 N, +4.5 %.
    stiff = mechcirc.parse(NETLIST.read_text().replace("0.5 kN/mm", "0.6 kN/mm"))
    rise = mechcirc.peak(stiff, 470.0, 560.0).value / ex.Q0_max[0]
    assert rise == pytest.approx(_band_min_abs_K() / _band_min_abs_K(k4=6e5), rel=1e-14)
    assert 1.04 < rise < 1.05
