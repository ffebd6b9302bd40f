"""Nodal analysis, levers and force excitation against closed forms and the reduction."""

import functools

import mpmath
import numpy as np
import pytest
import scipy.linalg
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import mechcirc
import mechcirc._jit  # noqa: F401  (used as mechcirc.<module>; not imported by `import mechcirc`)
import mechcirc._nodal_residual  # noqa: F401
import mechcirc._nodal_solvers  # noqa: F401
import mechcirc.nodal  # noqa: F401
from mechcirc.errors import NotSeriesParallelError, TopologyError
from reference import mp_nodal
from reference.networks import OVERDAMPED_CLOSE_PAIR, grid_text
from strategies import networks_with_levers, reference_K_and_cancellation, to_netlist_with_levers

BRIDGE = """drive V a 0 velocity=0.5
spring k1 a b 1e4
damper c2 a c 30
mass   m3 b c 2
spring k4 b 0 3e4
mass   m5 c 0 5
"""


def _bridge_reference(w):
    """Δ–Y transform of the triangle (a, b, c), then series–parallel (independent closed form)."""
    Z1, Z2, Z3 = 1j * w / 1e4, 1 / 30, -1j / (w * 2)
    Z4, Z5 = 1j * w / 3e4, -1j / (w * 5)
    total = Z1 + Z2 + Z3
    Za, Zb, Zc = Z1 * Z2 / total, Z1 * Z3 / total, Z2 * Z3 / total
    left, right = Zb + Z4, Zc + Z5
    return Za + left * right / (left + right)


def test_bridge_is_solved_by_nodal_analysis_and_matches_its_closed_form():
    c = mechcirc.parse(BRIDGE)
    omega = np.geomspace(1, 1e4, 300)
    with pytest.raises(NotSeriesParallelError):
        c.sweep(omega, method="sp")
    s = c.sweep(omega)                      # auto falls back to nodal
    assert s.method == "nodal"
    np.testing.assert_allclose(s.K, _bridge_reference(omega), rtol=1e-12)
    np.testing.assert_allclose(s.Q0, 0.5 / s.K, rtol=1e-14)


def test_bridge_element_forces_balance_at_every_node():
    s = mechcirc.parse(BRIDGE).sweep(np.geomspace(1, 1e4, 50))
    # KCL: force into a = through k1 and c2; node b: k1 = m3 + k4; node c: c2 + m3 = m5.
    np.testing.assert_allclose(s.force("k1") + s.force("c2"), s.Q0, rtol=1e-9)
    np.testing.assert_allclose(s.force("k1"), s.force("m3") + s.force("k4"), rtol=1e-9)
    np.testing.assert_allclose(s.force("c2") + s.force("m3"), s.force("m5"), rtol=1e-9)
    # KVL around a-b-c: v(k1) + v(m3) = v(c2).
    np.testing.assert_allclose(s.velocity("k1") + s.velocity("m3"), s.velocity("c2"),
                               rtol=1e-9)


def test_lever_chain_reflects_as_product_of_ratios_squared():
    text = """drive V p 0 velocity=1
lever L1 p 0 q 0 ratio=2
lever L2 q 0 r 0 ratio=0.5
lever L3 r 0 t 0 ratio=3
mass m t 0 1.5
"""
    c = mechcirc.parse(text)
    omega = np.array([0.3, 7.0, 500.0])
    expected = -1j / (omega * 1.5) / (2 * 0.5 * 3) ** 2      # mass m·r² on the primary
    for method in ("sp", "nodal"):
        np.testing.assert_allclose(c.sweep(omega, method=method).K, expected, rtol=1e-13)
    assert str(c.tree) == "L1[L2[L3[m]]]"
    s = c.sweep(omega)
    # The secondary moves r times faster and carries 1/r of the force.
    np.testing.assert_allclose(s.velocity("m"), 3.0 * s.v0, rtol=1e-13)
    np.testing.assert_allclose(s.force("m"), s.Q0 / 3.0, rtol=1e-13)


@settings(max_examples=120, deadline=None)
@given(net=networks_with_levers(), log_omega=st.floats(-1, 2))
def test_random_networks_with_levers_same_K_by_both_methods(net, log_omega):
    omega = 10.0 ** log_omega
    with mpmath.workdps(60):
        ref, cancellation = reference_K_and_cancellation(
            net, mpmath.mpf(omega), j=mpmath.mpc(0, 1), convert=mpmath.mpf)
        ref = complex(ref)
    # Compare where no sub-network sits within 1e-3 of its own pole or zero
    # (there float64 cannot hold 12 digits by either method).
    assume(cancellation < 1e3)
    c = mechcirc.parse(to_netlist_with_levers(net))
    K_sp = c.sweep([omega], method="sp").K[0]
    K_nodal = c.sweep([omega], method="nodal").K[0]
    assert abs(K_sp - ref) <= 1e-12 * abs(ref)
    # Back to 1e-12 (it was 1e-10 while the refinement's residual was summed in
    # 80-bit long double, which left 1.05e-12 on a series chain; see
    # test_series_chain_of_disparate_values_is_exact below).
    assert abs(K_nodal - ref) <= 1e-12 * abs(ref)


@pytest.mark.parametrize("order", [("m1", "m1000", "s"), ("m1000", "s", "m1"),
                                   ("m1000", "m1", "s")])
@pytest.mark.parametrize("omega", [10.0, 31.6227766])
def test_series_chain_of_disparate_values_is_exact(order, omega):
    """1 kg and 1000 kg masses in series with a 0.01 N/m spring (found by hypothesis in CI).

    With the refinement's residual in 80-bit long double nodal K was off by
    up to 3.5e-12 here (|x|·|y| ~ 1e7·|K|); in double-double it is K
    rounded to float64.  Reference: the series sum of mobilities in mpmath.
    """
    values = {"m1": ("mass", 1.0), "m1000": ("mass", 1000.0), "s": ("spring", 0.01)}
    lines = ["drive V n0 0 velocity=1"]
    ref = mpmath.mpf(0)
    w = mpmath.mpf(omega)
    with mpmath.workdps(40):
        for i, name in enumerate(order):
            kind, v = values[name]
            lines.append(f"{kind} e{i} n{i} {f'n{i + 1}' if i < 2 else '0'} {v!r}")
            ref += 1 / (1j * w * v) if kind == "mass" else 1j * w / v
        ref = complex(ref)
    K = mechcirc.parse("\n".join(lines)).sweep([omega], method="nodal").K[0]
    # Achieved: 0 at these six points; 4e-16 allows K's own rounding twice over.
    assert abs(K - ref) <= 4e-16 * abs(ref)


def test_force_excitation_gives_velocity_and_force_characteristic():
    c = mechcirc.parse("drive F a 0 force=20\nmass m a 0 4\nspring k a 0 1e4\n")
    omega = np.array([10.0, 40.0, 100.0])
    s = c.sweep(omega)
    K = 1 / (1j * omega * 4 + 1e4 / (1j * omega))
    np.testing.assert_allclose(s.K, K, rtol=1e-14)
    np.testing.assert_allclose(s.v0, 20 * K, rtol=1e-14)
    np.testing.assert_allclose(s.S, 1 / K, rtol=1e-14)
    np.testing.assert_allclose(s.Q0, 20.0)
    np.testing.assert_allclose(s.force("m") + s.force("k"), 20.0, rtol=1e-12)


def test_floating_lever_side_is_an_error():
    c = mechcirc.parse("drive V a 0 velocity=1\nmass m a 0 1\nlever L a 0 s1 s2 ratio=2\n")
    with pytest.raises(TopologyError, match="no path to the frame"):
        c.sweep([1.0])


def test_node_reached_only_through_a_lever_is_an_error():
    text = "drive V a 0 velocity=1\nmass m a 0 1\nlever L a 0 s1 s2 ratio=2\nmass n s1 s2 3\n"
    c = mechcirc.parse(text)
    for method in ("sp", "nodal"):
        with pytest.raises(TopologyError, match=r"s1, s2 have no path to the frame.*L.*line 3"):
            c.sweep([1.0], method=method)


def test_secondary_side_left_open_is_an_error():
    text = "drive V a 0 velocity=1\nmass m a 0 1\nlever L a 0 s1 0 ratio=2\n"
    with pytest.raises(TopologyError, match="left floating"):
        mechcirc.parse(text).sweep([1.0], method="sp")


def test_network_singular_at_every_frequency_is_an_error_naming_the_levers():
    text = """drive V a 0 velocity=1
mass m a 0 1
lever L1 a 0 s 0 ratio=2
lever L2 a 0 s 0 ratio=2
spring k s 0 5
"""
    c = mechcirc.parse(text)
    with pytest.raises(TopologyError, match="singular at every frequency") as info:
        c.sweep([1.0])
    assert set(info.value.elements) == {"L1", "L2"}


def test_lever_free_network_is_checked_unless_every_value_is_positive():
    """Without levers only positive values make A(ω) regular without a trial: a spring of
    −k beside +k (built in code; the parser refuses it) leaves A(ω) = 0 at every ω."""
    from mechcirc.circuit import Circuit, Drive, Element

    springs = (Element("spring", "k1", "a", "0", 1e4), Element("spring", "k2", "a", "0", -1e4))
    c = Circuit(springs, Drive("V", "a", "0", "velocity", 1.0))
    with pytest.raises(TopologyError, match="singular at every frequency"):
        c.sweep([1.0], method="nodal")


def test_large_networks_use_sparse_solves_and_agree_with_the_tree():
    # A ladder with 400 nodes is reducible: compare the sparse nodal path with the tree.
    lines = ["drive V n0 0 velocity=1"]
    for i in range(400):
        lines.append(f"mass m{i} n{i} n{i + 1} {1 + i % 7}")
        lines.append(f"spring k{i} n{i + 1} 0 {1e4 * (1 + i % 5)}")
        lines.append(f"damper c{i} n{i + 1} 0 {0.5 + i % 3}")
    c = mechcirc.parse("\n".join(lines))
    omega = np.geomspace(1, 1e3, 20)
    np.testing.assert_allclose(c.sweep(omega, method="nodal").K, c.sweep(omega, method="sp").K,
                               rtol=1e-10)


# ----------------------------------------------------------- one assembly, honest errors
def _grid_K_reference(n, w, k=1e4, m=1.0):
    """K at the corner of the grid from its own Laplacian (numpy, no mechcirc)."""
    P = np.diag(np.r_[1.0, 2 * np.ones(n - 2), 1.0]) - np.eye(n, k=1) - np.eye(n, k=-1)
    L = np.kron(P, np.eye(n)) + np.kron(np.eye(n), P)
    A = 1j * (w * m * np.eye(n * n) - k * (np.eye(n * n) + L) / w)
    e = np.zeros(n * n)
    e[0] = 1.0
    return complex(np.linalg.solve(A, e)[0])


def test_grid_lowest_mode_is_flagged_on_the_sparse_path():
    """Issue 11 §2: the 30×30 grid's mode at exactly ω = 100 used to return −5.6e12j, flag 0."""
    c = mechcirc.parse(grid_text(30))
    assert c.nodal.size > mechcirc.nodal.DENSE_LIMIT            # the sparse path
    omega = np.array([99.0, 100.0, 101.0])
    s = c.sweep(omega, method="nodal")
    assert s.flags[1] == 1 and np.isinf(s.K[1].imag) and s.K[1].real == 0
    assert not np.isnan(s.error).any()
    for i in (0, 2):
        assert s.flags[i] == 0
        # The reference's own error is about eps·cond ≈ 1e-13 here.
        assert s.K[i] == pytest.approx(_grid_K_reference(30, omega[i]), rel=1e-11)


def test_spring_parallel_mass_singular_point_is_the_same_from_both_methods():
    """Issue 11 §3: −inf·j from the tree, nan from nodal; now both give the same value, flag 1."""
    c = mechcirc.parse("drive V a 0 velocity=1\nspring k a 0 1e4\nmass m a 0 1\n")
    sp, nd = c.sweep([99.0, 100.0, 101.0], method="sp"), c.sweep([99.0, 100.0, 101.0],
                                                                    method="nodal")
    assert nd.K[1] == sp.K[1] and np.isinf(nd.K[1].imag)
    np.testing.assert_array_equal(nd.flags, sp.flags)
    np.testing.assert_array_equal(nd.flags, [0, 1, 0])
    assert not np.isnan(nd.error).any()


@pytest.mark.parametrize("ratio", [1e-150, 1e-8, 1e8, 1e150])
def test_extreme_lever_ratios_are_exact_and_not_flagged(ratio):
    """Issue 11 §7: every point was flagged (estimate 2.2 … ∞) while K was exact to 2e-16."""
    text = f"drive V a 0 velocity=1\nlever L a 0 b 0 ratio={ratio!r}\nmass m b 0 2\n"
    omega = np.array([0.1, 1.0, 10.0])
    s = mechcirc.parse(text).sweep(omega, method="nodal")
    exact = -1j / (omega * 2 * ratio * ratio)
    np.testing.assert_allclose(s.K, exact, rtol=4e-16)
    np.testing.assert_array_equal(s.flags, 0)


def test_tiny_damper_is_exact_and_not_flagged():
    s = mechcirc.parse("drive V a 0 velocity=1\ndamper c a 0 1e-300\n").sweep(
        [0.1, 1.0, 10.0], method="nodal")
    np.testing.assert_allclose(s.K, 1 / 1e-300, rtol=2.3e-16)   # 1e-300 is not exact
    np.testing.assert_array_equal(s.flags, 0)


def test_assemble_whole_keeps_every_element():
    text = ("drive V a 0 velocity=1\nmass m a 0 2\nspring k a b 3\n"
            "mass hidden_m c 0 5\nspring hidden_k c 0 7\n")
    c = mechcirc.parse(text)
    loaded = mechcirc.nodal.assemble(c)
    whole = mechcirc.nodal.assemble(c, whole=True)
    assert "hidden_m" in loaded.unloaded and whole.unloaded == ()
    index = {n: i for i, n in enumerate(whole.nodes)}
    assert set(index) == {"a", "b", "c"}
    M, Ks = whole.M.toarray(), whole.Ks.toarray()
    a, b, cc = index["a"], index["b"], index["c"]
    assert M[a, a] == 2 and M[cc, cc] == 5 and M[b, b] == 0
    assert Ks[a, a] == 3 and Ks[a, b] == -3 and Ks[b, b] == 3 and Ks[cc, cc] == 7
    assert whole.a == a and whole.b == -1


@pytest.mark.parametrize("sparse", [False, True])
def test_error_estimate_bounds_the_true_error_on_random_networks(sparse, monkeypatch):
    """A small calibration against mpmath (the full one: benchmarks/calibrate_nodal.py)."""
    import warnings

    from reference import mp_nodal

    if sparse:
        monkeypatch.setattr(mechcirc._nodal_solvers, "DENSE_LIMIT", 0)
    rng = np.random.default_rng(7)
    true_all, est_all = [], []
    for i in range(6):
        text, spec, w_char = mp_nodal.random_network(rng, n_nodes=8 + i, damped=bool(i % 2),
                                                     levers=i % 3)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            system = mechcirc.parse(text).nodal
        omega = w_char * 10 ** rng.uniform(-2, 2, 3)
        s = mechcirc.nodal.solve(system, omega)
        ref = np.array([complex(mp_nodal.K(spec, 1j * w, 30)) for w in omega])
        true_all.extend(np.abs(s.K - ref) / np.abs(ref))
        est_all.extend(s.error)
    true, est = np.array(true_all), np.array(est_all)
    assert np.all(est >= true)
    assert np.all(est < 1e-6)                 # no false alarm: every true error is ≤ 1e-11
    assert np.max(true) < 1e-11
    # Tight: within 1e4 of the true error (floored at 1e-17) at these points.
    assert np.all(est <= 1e4 * np.maximum(true, 1e-17))


# ------------------------------------------- sparse path: deterministic, exact, compiled
def _lever_ladder(n_sections, seed):
    """(netlist, mpmath K(ω)) of a ladder with dampers and levers: an independent continued fraction.

    Springs in series along the chain, masses (some with a damper beside)
    from each node to the frame, and every 97th section a lever into a new
    chain; K is summed from the far end in mpmath: a series element adds its
    mobility, shunts add in admittance, a lever of ratio r divides K by r².
    """
    rng = np.random.default_rng(seed)
    lines = ["drive V n0 0 velocity=1"]
    steps = []                          # from the drive outwards
    node = "n0"
    for i in range(n_sections):
        if i % 97 == 50:
            r = float(rng.choice([0.3, 2.5, 7.0]))
            nxt = f"s{i}"
            lines.append(f"lever L{i} {node} 0 {nxt} 0 ratio={r!r}")
            steps.append(("lever", r))
            node = nxt
        k = float(rng.uniform(1e3, 1e5))
        m = float(rng.uniform(0.1, 3.0))
        nxt = f"n{i + 1}"
        lines.append(f"spring k{i} {node} {nxt} {k!r}")
        lines.append(f"mass m{i} {nxt} 0 {m!r}")
        shunt = [("mass", m)]
        if i % 3 == 0:
            c = float(rng.uniform(0.1, 10.0))
            lines.append(f"damper c{i} {nxt} 0 {c!r}")
            shunt.append(("damper", c))
        steps.append(("section", k, shunt))
        node = nxt

    def K(omega, dps=30):
        with mpmath.workdps(dps):
            w = mpmath.mpf(omega)
            j = mpmath.mpc(0, 1)
            Kr = None                   # K seen looking outwards from the current node
            for step in reversed(steps):
                if step[0] == "lever":
                    Kr = Kr / mpmath.mpf(step[1]) ** 2
                    continue
                _, k, shunt = step
                y = sum(j * w * v if kind == "mass" else mpmath.mpf(v) for kind, v in shunt)
                if Kr is not None:
                    y += 1 / Kr
                Kr = j * w / k + 1 / y
            return complex(Kr)
    return "\n".join(lines), K


_LADDER_OMEGA = np.array([0.37, 3.1, 29.0, 170.0, 1234.5])


@functools.lru_cache(maxsize=1)
def _LADDER_REFERENCE():
    text, K_ref = _lever_ladder(2000, seed=11)
    return text, np.array([K_ref(w) for w in _LADDER_OMEGA])


@pytest.mark.parametrize("path", ["band", "superlu", "band-numpy", "superlu-numpy",
                                  "superlu-strict"])
def test_large_ladder_with_levers_is_exact_against_mpmath(path, monkeypatch):
    """Issue 14 §3: the sparse paths keep K ≤ 1e-12 from mpmath (2,000 sections, sampled ω).

    ``superlu-strict`` sends every point through the partial-pivoting
    fallback (taken where the symmetric mode's refinement stays above 1e-10).
    """
    if path.startswith("superlu"):
        monkeypatch.setattr(mechcirc._nodal_solvers, "BAND_MAX", -1)
    if path.endswith("strict"):
        monkeypatch.setattr(mechcirc.nodal, "_STRICT_AFTER", -1.0)
    # the numpy path, or compiled even for a sweep this small
    monkeypatch.setattr(mechcirc._jit, "COMPILED", not path.endswith("numpy"))
    text, ref = _LADDER_REFERENCE()
    system = mechcirc.parse(text).nodal
    assert mechcirc._nodal_solvers.solver(system).kind == path.split("-")[0]
    K, err = mechcirc.nodal.mobility_and_error(system, _LADDER_OMEGA)
    true = np.abs(K - ref) / np.abs(ref)
    # Achieved: ≤ 2.3e-16 on every path (K rounded once); 1e-15 leaves a margin of 4.
    assert np.all(true <= 1e-15), true
    assert np.all(err >= true)


def test_sparse_solves_are_bit_identical_between_runs():
    """The solver is chosen from the pattern (not by timing): the same K, bit for bit, every time."""
    ladder, _ = _lever_ladder(400, seed=3)
    for text, kind in ((ladder, "band"), (grid_text(14), "superlu")):
        omega = np.geomspace(3.0, 300.0, 17)
        runs = []
        for _ in range(2):
            system = mechcirc.parse(text).nodal
            assert mechcirc._nodal_solvers.solver(system).kind == kind
            runs.append(mechcirc.nodal.mobility_and_error(system, omega))
        assert runs[0][0].tobytes() == runs[1][0].tobytes()
        assert runs[0][1].tobytes() == runs[1][1].tobytes()


def test_compiled_residual_is_the_numpy_residual_bit_for_bit(monkeypatch):
    """The numba kernel does the numpy code's double-double operations in the same order."""
    pytest.importorskip("numba")
    import warnings

    from reference import mp_nodal

    # Forced: by default a kernel not yet in numba's cache is not compiled here.
    monkeypatch.setattr(mechcirc._jit, "COMPILED", True)
    kern = mechcirc.nodal.kernels(10 ** 9)
    assert kern is not None
    rng = np.random.default_rng(5)
    for t in range(12):
        text, _, w_char = mp_nodal.random_network(rng, n_nodes=6 + t, damped=bool(t % 2),
                                                  levers=t % 3)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            system = mechcirc.parse(text).nodal
        pat = mechcirc._nodal_residual.pattern(system)
        omega = w_char * 10 ** rng.uniform(-2, 2, 4 + 15 * (t % 3))   # 1, 2, 3 blocks of 16
        shape = (omega.size, system.size)
        xh = (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) * 10.0 ** (t - 6)
        xl = xh * 1e-17 * rng.standard_normal(shape)
        rhs = system.injection()
        for low in (xl, None):
            compiled = pat.residual(omega, xh, low, rhs, kern)
            vectorised = pat.residual(omega, xh, low, rhs)
            assert compiled.tobytes() == vectorised.tobytes()


def test_compiled_update_is_the_numpy_two_sum_bit_for_bit(monkeypatch):
    """refine_dd's step x + d = s + e (and xl + e after the first step) by the kernel
    (_nodal_kernels.update: s into x, e into the residual's array) has the bits of
    _dd.two_sum on complex arrays: values over 600 decades, signed zeros, cancellation
    (d = −x), inf and NaN; and the first step's |s|ᵀ|r| (for the first-step bound, formed
    before r is overwritten) is the row's sum in order of (|re| + |im|) products."""
    pytest.importorskip("numba")
    monkeypatch.setattr(mechcirc._jit, "COMPILED", True)
    kern = mechcirc.nodal.kernels(10 ** 9)
    rng = np.random.default_rng(9)
    shape = (37, 11)

    def draw():
        return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) \
            * 10.0 ** rng.uniform(-300, 300, shape)
    x, d, xl, r = draw(), draw(), draw(), draw() * 1e-3
    d[::3] = x[::3] * 1e-17 * rng.standard_normal(shape)[::3]
    d[1::5] = -x[1::5]
    x[2::7, 0], d[3::7, 1], x[4, 2], d[5, 3], x[6, 4] = -0.0, -0.0, np.inf, np.nan, -np.inf
    for lo in (False, True):
        with np.errstate(all="ignore"):
            s, e = mechcirc._dd.two_sum(x, d)
            e = xl + e if lo else e
        s2, e2, rounding = x.copy(), r.copy(), np.empty(shape[0])
        kern.update(s2, d, xl, lo, e2, rounding, True)
        assert s2.tobytes() == s.tobytes() and e2.tobytes() == e.tobytes()
        for k in range(shape[0]):
            want = 0.0
            for a, b in zip(s[k].tolist(), r[k].tolist()):     # (Python floats)
                want += (abs(a.real) + abs(a.imag)) * (abs(b.real) + abs(b.imag))
            assert np.float64(want).tobytes() == rounding[k].tobytes() or \
                (np.isnan(want) and np.isnan(rounding[k]))


# ------------------------------------------- the numpy banded LU, vectorised over ω
@pytest.mark.parametrize("kl", [0, 1, 3])
def test_batched_band_lu_solves_as_numpy_dense_solve(kl):
    """band_lu_batch/band_solve_batch against numpy.linalg.solve on the dense matrices.

    Random complex bands, the diagonal scaled down in half of the batch so
    that partial pivoting swaps rows; one matrix with an all-zero column is
    reported singular and the others are unaffected.
    """
    solvers = mechcirc._nodal_solvers
    rng = np.random.default_rng(kl)
    n, B = 17, 9
    A = np.zeros((B, n, n), dtype=complex)
    for i in range(n):
        for c in range(max(0, i - kl), min(n, i + kl + 1)):
            A[:, i, c] = rng.standard_normal(B) + 1j * rng.standard_normal(B)
    A[::2] -= 0.999 * np.einsum("bii->bi", A[::2])[:, :, None] * np.eye(n)   # swaps
    A[4, :, 6] = 0                                                        # singular
    G = np.zeros((n + kl, 3 * kl + 1, B), dtype=complex)
    for i in range(n):
        for c in range(max(0, i - kl), min(n, i + kl + 1)):
            G[i, kl + c - i] = A[:, i, c]
    piv, ok = solvers.band_lu_batch(G, n, kl)
    assert list(np.flatnonzero(~ok)) == [4]
    assert kl == 0 or piv.any()                        # pivoting did happen
    b = rng.standard_normal((n, B)) + 1j * rng.standard_normal((n, B))
    x = np.zeros((n + 2 * kl, B), dtype=complex)
    x[:n] = b
    solvers.band_solve_batch(G, piv, x, n, kl)
    for k in np.flatnonzero(ok):
        ref = np.linalg.solve(A[k], b[:, k])
        # Achieved ≤ 2.5e-15 relative (kl = 3); 1e-13 leaves a margin of 40.
        assert np.max(np.abs(x[:n, k] - ref)) <= 1e-13 * np.max(np.abs(ref))


def test_small_narrow_networks_are_banded_and_exact_against_mpmath(monkeypatch):
    """A 40-section ladder (41 unknowns, ≤ the dense limit) takes the numpy banded LU
    (not a dense inverse per ω) and keeps K within 1e-15 of mpmath."""
    monkeypatch.setattr(mechcirc._jit, "COMPILED", False)
    text, K_ref = _lever_ladder(40, seed=5)
    system = mechcirc.parse(text).nodal
    assert system.size <= mechcirc.nodal.DENSE_LIMIT
    assert mechcirc._nodal_solvers.solver(system).kind == "band"
    K, err = mechcirc.nodal.mobility_and_error(system, _LADDER_OMEGA)
    ref = np.array([K_ref(w) for w in _LADDER_OMEGA])
    true = np.abs(K - ref) / np.abs(ref)
    # Achieved: 0 (K correctly rounded here); 1e-15 as the large ladders' test.
    assert np.all(true <= 1e-15), true
    assert np.all(err >= true)


def test_a_residual_of_more_terms_than_a_chunk_goes_one_point_at_a_time(monkeypatch):
    """Past ``_CHUNK_TERMS`` residual terms (a 99,999-element ladder on the numpy path)
    the residual goes one ω per piece (never a step of zero), the same numbers bit for bit."""
    monkeypatch.setattr(mechcirc._jit, "COMPILED", False)
    text, K_ref = _lever_ladder(100, seed=2)
    system = mechcirc.parse(text).nodal
    K, err = mechcirc.nodal.mobility_and_error(system, _LADDER_OMEGA)
    monkeypatch.setattr(mechcirc.nodal, "_CHUNK_TERMS", 1)
    K1, err1 = mechcirc.nodal.mobility_and_error(system, _LADDER_OMEGA)
    assert K1.tobytes() == K.tobytes() and err1.tobytes() == err.tobytes()
    ref = np.array([K_ref(w) for w in _LADDER_OMEGA])
    assert np.all(np.abs(K1 - ref) <= 1e-15 * np.abs(ref))


def test_each_point_is_the_same_alone_as_in_a_sweep(monkeypatch):
    """A point's refined K, error and flag do not depend on the other points of the sweep:
    the refinement takes its arrays whole while every ω refines and by index once some
    have converged, and both give the point's own bits (numpy path).  (The plain solve's
    estimate is not compared: its last bit can depend on the batch, seen at one of these
    nine points before this refinement's change too.)"""
    monkeypatch.setattr(mechcirc._jit, "COMPILED", False)
    text, _ = _lever_ladder(20, seed=7)
    c = mechcirc.parse(text)
    omega = np.geomspace(1.0, 1e3, 41)
    s = c.sweep(omega, method="nodal")
    for i in range(0, omega.size, 5):
        one = c.sweep(omega[i:i + 1], method="nodal")
        assert one.K.tobytes() == s.K[i:i + 1].tobytes(), i
        assert one.error.tobytes() == s.error[i:i + 1].tobytes(), i
        assert one.flags[0] == s.flags[i]


def test_sensitivity_without_the_data_part_is_the_same():
    """``Pattern.sensitivities(..., data=False)`` (a sweep's) gives S bit for bit as with
    S_data, and S_data against its definition Σ_e |y_e| |x_i − x_j|² + levers, recomputed
    here from the stamps by hand (relative 1e-14; achieved ~1e-16)."""
    rng = np.random.default_rng(3)
    text, _ = _lever_ladder(55, seed=1)          # a lever at its 51st section
    system = mechcirc.parse(text).nodal
    pat = mechcirc._nodal_residual.pattern(system)
    omega = np.array([3.0, 40.0])
    x = rng.standard_normal((2, system.size)) + 1j * rng.standard_normal((2, system.size))
    K = system.difference(x)
    S, Sd = pat.sensitivities(omega, x, K)
    S2, none = pat.sensitivities(omega, x, K, data=False)
    assert none is None and S2.tobytes() == S.tobytes()
    index = {n: i for i, n in enumerate(system.nodes)}
    xe = np.concatenate([x, np.zeros((2, 1))], axis=1)
    ref = np.zeros(2)
    for e in system.elements:
        i, j = index.get(e.n1, system.size), index.get(e.n2, system.size)
        y = abs(e.value * e.eta * {"mass": 1j * omega, "spring": 1 / (1j * omega)}.get(
            e.kind, 1.0 + 0 * omega))
        ref += y * np.abs(xe[:, i] - xe[:, j]) ** 2
    for k, lv in enumerate(system.levers):
        q = xe[:, len(system.nodes) + k]
        p1, p2 = index.get(lv.p1, system.size), index.get(lv.p2, system.size)
        ref += 2 * abs(lv.ratio) * np.abs(xe[:, p1] - xe[:, p2]) * np.abs(q)
    assert np.all(np.abs(Sd * np.abs(K) - ref) <= 1e-14 * ref)


def test_residual_term_counts_are_counted_from_the_stamps():
    """``Pattern.max_terms`` (terms of a (row, kind) bucket) and ``max_row_terms`` (of a
    row) — the residual-rounding bounds' m — against a count of the terms by hand."""
    from collections import Counter

    for text in (_lever_ladder(55, seed=2)[0], grid_text(4), BRIDGE):
        system = mechcirc.parse(text).nodal
        pat = mechcirc._nodal_residual.pattern(system)
        index = {n: i for i, n in enumerate(system.nodes)}
        bucket, row = Counter(), Counter()
        for e in system.elements:
            for node in (e.n1, e.n2):
                if node in index:
                    bucket[index[node], e.kind] += 1
                    row[index[node]] += 1
        for r in system.stamps["lever"][0]:
            bucket[int(r), "lever"] += 1
            row[int(r)] += 1
        assert pat.max_terms == max(bucket.values())
        assert pat.max_row_terms == max(row.values())


@pytest.mark.parametrize("compiled", [False, True])
def test_second_pass_is_skipped_only_where_the_first_step_bound_holds(compiled, monkeypatch):
    """Where the first correction leaves an estimate above 16 eps, refine_dd skips the
    second residual pass when the bound on the first-corrected K (first_step_bound: the
    banded LU's backward error, the entries' rounding, the residual's rounding to
    float64) is below 16 eps, on numpy's banded LU (band_bound_batch) and on the
    compiled one (mechcirc._nodal_kernels.band_bound).

    The bound must be above the true error of that K in double-double, against a
    50-digit continued fraction (a ladder of 22 sections, 101 ω over 5 decades);
    the skip must happen at most of the points that took a second pass, and K
    (rounded) stays correctly rounded.
    """
    import mpmath

    monkeypatch.setattr(mechcirc._jit, "COMPILED", compiled)
    kern = mechcirc.nodal.kernels(10 ** 9)
    if compiled and kern is None:
        pytest.skip("numba is not installed")
    assert (kern is None) != compiled
    rng = np.random.default_rng(12)
    ks, ms = rng.uniform(1e4, 2e4, 22), rng.uniform(0.2, 1.2, 22)
    nodes = ["a"] + [f"n{i}" for i in range(1, 23)]
    lines = ["drive V a 0 velocity=1"]
    for i in range(22):
        lines += [f"spring k{i} {nodes[i]} {nodes[i + 1]} {float(ks[i])!r}",
                  f"mass m{i} {nodes[i + 1]} 0 {float(ms[i])!r}"]
    system = mechcirc.parse("\n".join([*lines, f"damper r {nodes[-1]} 0 0.001"])).nodal
    band = mechcirc._nodal_solvers.solver(system)
    assert band.kind == "band"
    pat = mechcirc._nodal_residual.pattern(system)
    omega = np.geomspace(0.6, 6e3, 101)
    rhs = system.injection()
    eps = np.finfo(float).eps
    ok, fn = band.factor(omega, kern)
    assert ok.all() and hasattr(fn, "bound")

    def run(steps, bound):                  # refine_dd with and without the bound
        return mechcirc.nodal.refine_dd(
            fn if bound else fn.solve,
            lambda w, xh, xl, rhs, exact=True: pat.residual(w, xh, xl, rhs, kern, exact),
            omega, rhs, system, True, steps)
    _, _, est1, _ = run(1, False)
    _, _, est_loop, _ = run(4, False)
    xh, xl, est, _ = run(4, True)
    second = np.flatnonzero(est1 > 16 * eps)
    skipped = second[est[second] != est_loop[second]]
    # Achieved: all 57 points that took a second pass; the bound 1.5e3x the true
    # error or more.
    assert skipped.size >= 0.8 * second.size
    assert np.all(est[skipped] <= 16 * eps)
    with mpmath.workdps(50):
        for k in second:
            jw = mpmath.mpc(0, float(omega[k]))
            ref = 1 / mpmath.mpf(1e-3)
            for kk, m in zip(ks[::-1], ms[::-1]):
                ref = jw / float(kk) + 1 / (jw * float(m) + 1 / ref)
            Kdd = mpmath.mpc(xh[k, 0]) + mpmath.mpc(xl[k, 0])
            true = float(abs(Kdd / ref - 1))
            assert est[k] >= true, (omega[k], est[k], true)
            assert abs(complex(Kdd) / complex(ref) - 1) <= 1.2e-16      # rounded once


@pytest.mark.parametrize("compiled", [False, True])
def test_band_bound_is_the_dense_product_of_the_factors(compiled, monkeypatch):
    """The banded LU's |x|ᵀP̃|L||U||d| (numpy's band_bound_batch, the compiled band_bound)
    equals the product formed densely from P, L, U (scipy.linalg.lu: the same
    pivots) to rounding: a ladder with a lever, rows swapped at 4 of 7 ω."""
    monkeypatch.setattr(mechcirc._jit, "COMPILED", compiled)
    kern = mechcirc.nodal.kernels(10 ** 9)
    if compiled and kern is None:
        pytest.skip("numba is not installed")
    text, _ = _lever_ladder(22, seed=4)
    system = mechcirc.parse(text).nodal
    band = mechcirc._nodal_solvers.solver(system)
    assert band.kind == "band" and np.all(band.p == np.arange(system.size))
    omega = np.geomspace(1.0, 3e3, 7)
    rng = np.random.default_rng(3)
    x, d = (rng.standard_normal((7, system.size)) + 1j * rng.standard_normal((7, system.size))
            for _ in range(2))
    got = band.factor(omega, kern)[1].bound(x, d, np.arange(7))
    pat = mechcirc._nodal_residual.pattern(system)

    def mag(z):
        return np.abs(z.real) + np.abs(z.imag)
    ref = []
    for k, w in enumerate(omega):
        P, L, U = scipy.linalg.lu(pat.csc(w).toarray())
        ref.append(mag(x[k]) @ P @ mag(L) @ mag(U) @ mag(d[k]))
    # Achieved: 2.6e-15 (the factors' own rounding); 1e-12 is far below the
    # bound's slack (1e3x or more).
    assert np.all(np.abs(got / np.array(ref) - 1) <= 1e-12)
    # At some ω only (refine_dd's active points), x and d read at those rows of every ω's:
    # each ω's sums are the same operations.
    some = np.array([1, 4, 6])
    assert np.array_equal(band.factor(omega, kern)[1].bound(x, d, some), got[some])


@pytest.mark.parametrize("kl", [1, 2])
def test_band_bound_of_a_band_is_the_factored_product(kl):
    """band_bound_batch is |x|ᵀP₀|L₀|P₁|L₁|…|U||d| formed densely, factor by factor: 200 random banded batches of 1-39 unknowns, entries over 6 decades
    (thousands of row swaps)."""
    rng = np.random.default_rng(1)
    swaps, worst = 0, 0.0
    for _ in range(200):
        n, B = int(rng.integers(1, 40)), int(rng.integers(1, 6))
        G = np.zeros((n + kl, 3 * kl + 1, B), dtype=complex)
        for i in range(n):
            for c in range(max(0, i - kl), min(n, i + kl + 1)):
                G[i, kl + c - i] = (rng.standard_normal(B) + 1j * rng.standard_normal(B)) \
                    * 10.0 ** rng.uniform(-3, 3, B)
        piv, _ = mechcirc._nodal_solvers.band_lu_batch(G, n, kl)
        swaps += int(np.count_nonzero(piv))
        x, d = (rng.standard_normal((n, B)) + 1j * rng.standard_normal((n, B)) for _ in range(2))
        got = mechcirc._nodal_solvers.band_bound_batch(G, piv, x, d, n, kl)
        mag = np.abs(G.real) + np.abs(G.imag)
        for b in range(B):
            M = np.zeros((n, n))
            for j in range(n):
                for t in range(min(2 * kl + 1, n - j)):
                    M[j, j + t] = mag[j, kl + t, b]
            for j in range(n - 2, -1, -1):
                for s in range(1, min(kl, n - 1 - j) + 1):
                    M[j + s] += mag[j + s, kl - s, b] * M[j]
                p = int(piv[j, b])
                if p:
                    M[[j, j + p]] = M[[j + p, j]]
            ref = (np.abs(x[:, b].real) + np.abs(x[:, b].imag)) @ M \
                @ (np.abs(d[:, b].real) + np.abs(d[:, b].imag))
            worst = max(worst, abs(got[b] / ref - 1))
    # Achieved: 6.7e-16 (kl 1, 5,803 swaps), 7.8e-16 (kl 2, 7,597 swaps).
    assert swaps > 1000 and worst <= 1e-14


@pytest.mark.parametrize("compiled", [False, True])
def test_lu_division_is_pythons_complex_division(compiled):
    """The compiled banded LU's complex division (_nodal_kernels._cdiv: both of CPython's
    cases formed, one selected, so that its loops over ω vectorise) has the bits of
    Python's own division, for the pivot's reciprocal 1 / z and for a quotient w / z:
    20,000 random z and w over 600 decades, |re| = |im|, signed zeros, and the extremes
    (subnormals, 1.7e308)."""
    if compiled:
        pytest.importorskip("numba")
        from mechcirc import _nodal_kernels as k
    else:
        k = mechcirc._jit.load("mechcirc._nodal_kernels", _FORCE_PYTHON=True)
    rng = np.random.default_rng(5)
    re, im, wr, wi = (rng.standard_normal(20_000) * 10.0 ** rng.uniform(-300, 300, 20_000)
                      for _ in range(4))
    im[::7] = re[::7] * rng.choice([-1.0, 1.0], re[::7].size)
    re[::11], im[1::13], re[2::17], wi[::5] = 0.0, -0.0, -0.0, 0.0
    ext = [5e-324, -5e-324, 2.2e-308, 1.0, -1.0, 1.7e308, -1.7e308]
    pairs = [(a, b, c, d) for a, b, c, d in zip(re, im, wr, wi) if a or b] \
        + [(a, b, 1.0, 0.0) for a in ext for b in ext]
    want, got = [], []
    with np.errstate(all="ignore"):                # (as Python, numpy scalars overflow aloud)
        for a, b, c, d in pairs:
            for num in ((1.0, 0.0), (c, d)):
                z = complex(*num) / complex(a, b)
                want.append((z.real, z.imag))
                got.append(k._cdiv(*num, a, b, True))
    # The bits compared all at once (float64 holds each value as it is, NaNs' too).
    differ = np.flatnonzero(np.any(np.array(got, dtype=np.float64).view(np.uint64)
                                   != np.array(want, dtype=np.float64).view(np.uint64), axis=1))
    assert differ.size == 0, [(got[i], want[i], pairs[i // 2], i % 2) for i in differ[:5]]


@pytest.mark.parametrize("compiled", [False, True])
def test_estimate_max_modulus_is_numpys(compiled):
    """The compiled estimate's max |x| over a row (folded by _nodal_kernels._max_step, |z|
    formed only where |re| + |im| reaches the largest so far) is numpy's np.abs(x).max() to
    rtol 1e-15: rows with an entry of |re| = |im| whose |re| + |im| is just below 1.5×
    the first entry's |z| (a skip rule of 1.5·max instead of max returned 1.0 for 1.0465,
    4.5e-2 off), 1,000 random rows over 60 decades, a NaN.  Python's and numba's hypot
    differ from numpy's by up to 2.5e-16 (1.1 ulp; worst of 5 seeds): the limit is 4×
    that."""
    if compiled:
        pytest.importorskip("numba")
        from mechcirc import _nodal_kernels as k
    else:
        k = mechcirc._jit.load("mechcirc._nodal_kernels", _FORCE_PYTHON=True)
    rng = np.random.default_rng(8)
    x = (rng.standard_normal((1000, 7)) + 1j * rng.standard_normal((1000, 7))) \
        * 10.0 ** rng.uniform(-30, 30, (1000, 1))
    x[::3, 1] = x[::3, 0] * 0.7 * (1 + 1j)              # |re| = |im|, |z| up to 0.99·|x0|·√2
    x[1::3, 1] = abs(x[1::3, 0]) * 0.74 * (1 + 1j)      # |z| = 1.0465·|x0|
    x[5, 3] = complex(np.nan, 0.0)
    for row in range(x.shape[0]):
        want = np.abs(x[row]).max()
        got = 0.0
        for z in x[row]:
            got = k._max_step(got, z)
        assert abs(got - want) <= 1e-15 * want or (np.isnan(got) and np.isnan(want)), \
            (row, got, want)


def test_warm_kernels_calls_every_nodal_kernel(warm_up_run):
    """warm_kernels (what the detached process runs before a sweep takes the kernels)
    calls every compiled kernel of _nodal_kernels, so each lands in numba's cache: a
    kernel it never calls (the first-step bound, asked only where a first correction is
    not yet at rounding) would be compiled in the sweep's own process, seconds of the
    wait that mechcirc._jit's rule avoids.  The calls are recorded in a process with
    numba's JIT off (the kernels run as Python: nothing is compiled; the process of
    every warm-up statement, tests/conftest.py, warm_up_run, where each function of the
    module is recorded); the kernels are the module's compiled dispatchers, read here
    with numba on."""
    pytest.importorskip("numba")
    from numba.core.registry import CPUDispatcher

    from mechcirc import _nodal_kernels as k

    kernels = sorted(name for name, v in vars(k).items() if isinstance(v, CPUDispatcher)
                     and v.targetoptions.get("inline") != "always")
    assert kernels == ["_solve_blocks", "band_assemble_factor", "band_bound", "band_solve_perm",
                       "estimate", "residual", "sensitivities", "step_bound",
                       "update"]
    done = warm_up_run["nodal.warm_kernels, its kernel calls recorded"]
    assert done["error"] is None, done
    assert set(kernels) <= set(done["result"]), done["result"]


def test_k_off_the_axis_between_a_close_pair_from_the_double_double_lu():
    """Between the two roots of a pair 8.5e-10 apart on the negative real axis A(s) is
    within rounding of singular: from float64 factors K had no digit there (off by 1e5
    and 0.6, estimates infinite); the double-double LU's retry at complex s gives K to its
    bound (2e-6, pessimistic: K is exact here), against a 50-digit solve (mpmath)."""
    system = mechcirc.parse(OVERDAMPED_CLOSE_PAIR).nodal
    s = np.array([-7617.7683055, -7617.76830])
    with mpmath.workdps(50):
        ref = np.array([complex(mp_nodal.K(mp_nodal.spec_of(OVERDAMPED_CLOSE_PAIR),
                                           mpmath.mpf(x), 50)) for x in s])
    K, dK = mechcirc.nodal.evaluate_complex(system, s)
    assert np.all(np.abs(K - ref) <= dK) and np.all(dK <= 1e-5 * np.abs(ref))


#: Random network 32 of tests/fuzz/numeric_run.py's peak campaign (seed 2): levers L0 and
#: L1 join n1 and n2 both ways at ratios whose product is 0.28, so v1 = v2 = 0.
HELD_BY_TWO_LEVERS = """drive V n1 0 velocity=1
mass e0 n1 0 0.819016511074705
spring e1 n2 0 0.016588137500111094
spring e2 n3 n1 67.31315891088488
spring e3 n3 n1 0.2840930325175765
damper e4 n3 n1 0.004016295703249738
lever L0 n1 0 n2 0 ratio=24.868034660382293
lever L1 n2 0 n1 0 ratio=0.011161166144608235
"""


@pytest.mark.filterwarnings("ignore::mechcirc.errors.UnloadedElementWarning")
@pytest.mark.parametrize("text, levers, line", [
    (HELD_BY_TWO_LEVERS, ("L0", "L1"), 7),
    # Levers in parallel at ratios 2 and 3: v_b = 2 v_a = 3 v_a.  Before, the sweep
    # found an undamped resonance at 4.33 rad/s that is not there.
    ("drive V a 0 velocity=1\nmass m a 0 1\nspring k a b 10\nlever L1 a 0 b 0 ratio=2\n"
     "lever L2 a 0 b 0 ratio=3\n", ("L1", "L2"), 4),
])
def test_levers_that_hold_the_drive_are_named(text, levers, line):
    """K = 0 at every ω (mpmath, 50 digits: exactly 0 at two ω); the sweep gave |Q0| of
    1e50–1e67 N flagged "no digit", and a peak of 1.06e67 N "located".  Now nodal
    analysis refuses such a network, naming the levers at the first one's line."""
    spec = mp_nodal.spec_of(text)
    assert [mp_nodal.K(spec, 1j * w, 50) for w in (0.37, 5.3)] == [0, 0]
    c = mechcirc.parse(text, source="held.mcir")
    with pytest.raises(TopologyError, match="hold the drive's two nodes together") as exc:
        c.sweep([1.0])
    assert exc.value.elements == levers and exc.value.location == f"held.mcir:{line}:1"
    with pytest.raises(TopologyError, match="hold the drive's two nodes"):
        c.resonances()


@pytest.mark.parametrize("ratio", [1e-150, 1e-8, 1.0, 1e8, 1e150])
def test_levers_that_agree_do_not_hold_the_drive(ratio):
    """Two levers a→b at r and b→a at 1/r (the product rounded to 1 or not) state one
    constraint, and a lever of ratio 1e±150 does not hold its primary however far
    the balance of its row: not refused as a held drive (lever forces left
    undetermined by the pair are the other refusal, "singular at every frequency")."""
    one = f"drive V a 0 velocity=1\nlever L a 0 b 0 ratio={ratio!r}\nmass m b 0 2\n"
    assert np.isfinite(mechcirc.parse(one).sweep([1.0], method="nodal").K).all()
    pair = one + f"lever L2 b 0 a 0 ratio={1 / ratio!r}\n"
    with pytest.raises(TopologyError) as exc:
        mechcirc.parse(pair).sweep([1.0], method="nodal")
    assert "hold the drive" not in str(exc.value)
