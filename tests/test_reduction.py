"""Series–parallel reduction against independent evaluators."""

import warnings

import mpmath
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import mechcirc
from mechcirc import reduction
from mechcirc.errors import TopologyError, UnloadedElementWarning

from reference import stb_eq7
from strategies import count_leaves, networks, reference_K_and_cancellation, to_netlist
from reference.inputs import STB


def _random_stb_params(rng):
    p = {f"m{i}": 10 ** rng.uniform(-1, 1) for i in range(1, 13)}
    p.update(k0=10 ** rng.uniform(3, 6), k4=10 ** rng.uniform(5, 8), k5=10 ** rng.uniform(5, 8),
             eta1=10 ** rng.uniform(-0.5, 0.5), eta2=10 ** rng.uniform(-0.5, 0.5),
             eta3=10 ** rng.uniform(-0.5, 0.5), eta4=1.0)
    return p


def test_stb_tree_has_the_structure_of_eq_1():
    c = mechcirc.load(STB)
    assert str(c.tree) == ("m1 + m2 + m3 + m4 + (k4 | (m5 + k5) | "
                           "(m6 + m7 + m8 + m9 + m10 + m11 + m12 + k0))")


def test_stb_reduction_matches_eq_7_at_random_parameters():
    rng = np.random.default_rng(20021)
    worst = 0.0
    for _ in range(200):
        p = _random_stb_params(rng)
        omega = 10 ** rng.uniform(0, 4, size=50)
        K = mechcirc.parse(stb_eq7.netlist(p)).sweep(omega).K
        ref = stb_eq7.full_K(omega, p)
        err = np.abs(K - ref) / np.abs(ref)
        worst = max(worst, err.max())
    assert worst <= 1e-12, worst


def test_stb_eq_7_in_high_precision_agrees():
    """Where eq. (7) in float64 loses digits near a pole, the mpmath value decides."""
    rng = np.random.default_rng(7)
    p = _random_stb_params(rng)
    omega = 10 ** rng.uniform(0, 4, size=50)
    K = mechcirc.parse(stb_eq7.netlist(p)).sweep(omega).K
    with mpmath.workdps(50):
        mp_p = {k: mpmath.mpf(v) for k, v in p.items()}
        ref = [complex(stb_eq7.full_K(mpmath.mpf(w), mp_p).__complex__()) for w in omega]
    np.testing.assert_allclose(K, ref, rtol=1e-13)


@settings(max_examples=150, deadline=None)
@given(net=networks(max_leaves=14), log_omega=st.floats(-2, 3))
def test_random_series_parallel_networks(net, log_omega):
    """Full accuracy wherever no sub-network sits within 1e-3 of its own pole or zero.

    (Closer than that, float64 cannot hold 12 digits of the result at all; such
    points are the flagged singular points of the sweep, tested elsewhere.)
    """
    omega = 10.0 ** log_omega
    ref, cancellation = _mp_reference(net, omega)
    assume(cancellation < 1e3)
    c = mechcirc.parse(to_netlist(net))
    K = c.sweep([omega]).K[0]
    assert abs(K - ref) <= 1e-12 * abs(ref)
    assert len(c.elements) == count_leaves(net)


def _mp_reference(net, omega):
    with mpmath.workdps(60):
        K, cancellation = reference_K_and_cancellation(
            net, mpmath.mpf(omega), j=mpmath.mpc(0, 1), convert=mpmath.mpf)
        return complex(K), cancellation


@settings(max_examples=25, deadline=None)
@given(net=networks(max_leaves=160, min_exp=-6, max_exp=6),
       log_omega=st.floats(-1, 3))
def test_ill_conditioned_networks_against_mpmath(net, log_omega):
    """Values over 12 decades, up to 160 elements, lightly damped (dampers are ~1/3 of the leaves)."""
    omega = 10.0 ** log_omega
    ref, cancellation = _mp_reference(net, omega)
    assume(cancellation < 1e3)
    K = mechcirc.parse(to_netlist(net)).sweep([omega]).K[0]
    assert abs(K - ref) <= 1e-12 * abs(ref)


def test_large_ill_conditioned_ladder_against_mpmath():
    rng = np.random.default_rng(3)
    net = ("leaf", "damper", 1e3)
    for i in range(60):
        kind = ["mass", "spring", "damper"][i % 3]
        rung = ("leaf", kind, 10 ** rng.uniform(-6, 6))
        other = ("leaf", ["spring", "mass"][i % 2], 10 ** rng.uniform(-6, 6))
        net = ("s", [other, ("p", [rung, net])])
    assert count_leaves(net) == 121
    for omega in (0.37, 12.5, 980.0):
        K = mechcirc.parse(to_netlist(net)).sweep([omega]).K[0]
        ref, _ = _mp_reference(net, omega)
        assert abs(K - ref) <= 1e-12 * abs(ref)


def test_unloaded_elements_warn_and_are_named():
    text = """drive V a 0 velocity=1
mass m1 a 0 1
spring dangling a x 10
mass island1 p q 1
spring island2 q p 5
"""
    with pytest.warns(UnloadedElementWarning, match="dangling, island1, island2"):
        c = mechcirc.parse(text)
        assert str(c.tree) == "m1"
    assert c.unloaded == ("dangling", "island1", "island2")


def test_unloaded_of_a_network_that_is_not_series_parallel():
    """``Circuit.unloaded`` is a question of topology: a lever across meshes makes the
    network nodal-only, and the property raised NotSeriesParallelError (found by a
    fuzz of mode sensitivities).  Now the nodal system's loaded part answers, the same
    as a series-parallel network's reduction where both apply."""
    text = """drive V n1 0 velocity=1
mass e0 n1 0 0.33
spring e1 n2 n1 7.0
mass e2 n3 n1 1.34
mass e3 n4 n1 4.5
spring e4 0 n4 5.5
spring e5 0 n1 0.11
lever L0 n4 0 n2 0 ratio=0.0166
"""
    c = mechcirc.parse(text)
    with pytest.raises(mechcirc.errors.NotSeriesParallelError):
        c.tree
    assert c.unloaded == ("e2",)
    # With a spring for the lever the network reduces, and the reduction says the same.
    with pytest.warns(UnloadedElementWarning, match=": e2$"):
        sp = mechcirc.parse(text.replace("lever L0 n4 0 n2 0 ratio=0.0166", "spring e6 n2 0 3"))
        assert str(sp.tree) and sp.unloaded == ("e2",) == sp.nodal.unloaded


def test_bridge_is_not_series_parallel_and_names_the_culprits():
    text = """drive V a 0 velocity=1
spring k1 a b 1
spring k2 a c 2
spring k3 b c 3
spring k4 b 0 4
spring k5 c 0 5
"""
    c = mechcirc.parse(text)
    with pytest.raises(TopologyError) as info:
        c.tree
    assert set(info.value.nodes) == {"b", "c"}
    assert set(info.value.elements) == {"k1", "k2", "k3", "k4", "k5"}


def test_disconnected_drive_is_an_error():
    c = mechcirc.parse("drive V a b velocity=1\nmass m a 0 1\nmass n b 0 1\n".replace(
        "mass n b 0 1", "mass n c 0 1"))
    with pytest.raises(TopologyError, match="not connected"):
        c.tree


def test_force_and_velocity_pushed_down_obey_the_element_laws():
    c = mechcirc.load(STB)
    omega = np.geomspace(5, 5e3, 40)
    s = c.sweep(omega)
    for e in c.elements:
        np.testing.assert_allclose(s.velocity(e.name), e.mobility(omega) * s.force(e.name),
                                   rtol=1e-12)
    # Series chain m1..m4 carries the drive force; the parallel block splits it.
    np.testing.assert_allclose(s.force("m1"), s.Q0, rtol=1e-12)
    np.testing.assert_allclose(s.force("k4") + s.force("k5") + s.force("k0"), s.Q0, rtol=1e-9)
    # Parallel branches share the velocity difference across the block D–0.
    v_block = s.velocity("k4")
    np.testing.assert_allclose(s.velocity("m5") + s.velocity("k5"), v_block, rtol=1e-9)
    # Around the loop T-A-B-C-D-0 the velocity differences add up to V0.
    total = sum(s.velocity(n) for n in ("m1", "m2", "m3", "m4", "k4"))
    np.testing.assert_allclose(total, s.v0, rtol=1e-9)


def test_orientation_signs_reach_the_elements():
    # Element written 0 -> a: its velocity difference is -V0.
    c = mechcirc.parse("drive V a 0 velocity=2\ndamper c1 0 a 4\n")
    s = c.sweep([1.0])
    assert s.velocity("c1")[0] == pytest.approx(-2.0)
    assert s.force("c1")[0] == pytest.approx(-8.0)
    assert s.Q0[0] == pytest.approx(8.0)


def test_singular_points_do_not_crash():
    c = mechcirc.parse("drive V a 0 velocity=1\nmass m a b 1\nspring k b 0 1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")      # no RuntimeWarning from numpy either
        s = c.sweep([0.0, 1.0, 2.0, np.inf])
    assert s.flags.tolist() == [1, 1, 0, 1]
    assert s.K[2] == pytest.approx(-0.5j + 2j)


def test_long_parallel_and_series_runs_flatten_to_one_node_each():
    """Issue 14 §2 / 16 §3: 16,000 elements in parallel took 264 s (quadratic
    flattening); each run of one kind is now gathered once.  Correctness here:
    one flat node, K from the closed form, and orientation signs."""
    import mechcirc
    from mechcirc.reduction import Parallel, Series

    n = 3000
    ks = 1e3 + np.arange(n)
    par = "drive V a 0 velocity=1\n" + "".join(
        f"spring k{i} {'a 0' if i % 2 else '0 a'} {k}\n" for i, k in enumerate(ks))
    c = mechcirc.parse(par)
    tree = c.tree
    assert isinstance(tree, Parallel) and len(tree.children) == n
    assert tree.signs == tuple(1 if i % 2 else -1 for i in range(n))
    w = np.array([2.0, 30.0])
    np.testing.assert_allclose(c.sweep(w).K, 1j * w / ks.sum(), rtol=1e-12)
    # A series chain with every other element written backwards.
    nodes = ["a"] + [f"n{i}" for i in range(1, n)] + ["0"]
    ser = "drive V a 0 velocity=1\n" + "".join(
        f"spring k{i} {nodes[i]} {nodes[i + 1]} {k}\n" if i % 2 == 0 else
        f"spring k{i} {nodes[i + 1]} {nodes[i]} {k}\n" for i, k in enumerate(ks))
    c = mechcirc.parse(ser)
    tree = c.tree
    assert isinstance(tree, Series) and len(tree.children) == n
    assert [leaf.element.name for leaf in tree.children] == [f"k{i}" for i in range(n)]
    s = c.sweep(w)
    np.testing.assert_allclose(s.K, 1j * w * (1 / ks).sum(), rtol=1e-12)
    np.testing.assert_array_equal(s.force("k1"), -s.Q0)
    np.testing.assert_array_equal(s.force("k2"), s.Q0)


# ---------------------------------------------------------------------------
# The one-pass reduction (dangling branches, runs built in place) and the
# compiled evaluation plan
# ---------------------------------------------------------------------------

def test_unloaded_block_that_is_not_series_parallel_is_pruned_not_an_error():
    """A bridge hanging off the drive's block at one node carries no force: the
    fast pass cannot reduce it, the biconnected-block pruning must."""
    bridge = """spring b1 x p 1
spring b2 x q 2
spring b3 p q 3
spring b4 p y 4
spring b5 q y 5
spring b6 y x 6
"""
    c = mechcirc.parse("drive V a 0 velocity=1\nmass m1 a 0 2\nspring k a x 10\n" + bridge)
    with pytest.warns(UnloadedElementWarning):
        assert str(c.tree) == "m1"
    assert c.unloaded == ("k", "b1", "b2", "b3", "b4", "b5", "b6")


def test_series_parallel_runs_written_in_every_orientation():
    """Runs grown at either end and flipped: K against the closed form, and each
    element's velocity from the push-down against its own law (signs included)."""
    rng = np.random.default_rng(3)
    lines = ["drive V a 0 velocity=1"]
    ks = []
    # Three parallel bundles of series chains between a–b, b–c, c–0, elements
    # written forwards or backwards at random.
    nodes = ["a", "b", "c", "0"]
    total_K = 0.0
    for seg in range(3):
        Y = 0.0
        for chain in range(int(rng.integers(1, 5))):
            n = int(rng.integers(1, 6))
            inner = [nodes[seg]] + [f"n{seg}_{chain}_{i}" for i in range(n - 1)] + [nodes[seg + 1]]
            Kc = 0.0
            for i in range(n):
                k = float(10 ** rng.uniform(2, 5))
                u, w = inner[i], inner[i + 1]
                if rng.random() < 0.5:
                    u, w = w, u
                lines.append(f"spring s{len(ks)} {u} {w} {k!r}")
                ks.append(k)
                Kc += 1.0 / k
            Y += 1.0 / Kc
        total_K += 1.0 / Y
    c = mechcirc.parse("\n".join(lines))
    omega = np.array([0.5, 7.0, 300.0])
    s = c.sweep(omega)
    np.testing.assert_allclose(s.K, 1j * omega * total_K, rtol=1e-13)
    for e in c.elements:
        np.testing.assert_allclose(s.velocity(e.name), 1j * omega / e.value * s.force(e.name),
                                   rtol=1e-12)
    # Force balance at every inner node: what the elements bring in leaves again.
    scale = np.abs(s.Q0)
    inner = {n for e in c.elements for n in (e.n1, e.n2)} - {"a", "0"}
    assert len(inner) >= 2
    for node in inner:
        net = sum(s.force(e.name) * (1 if e.n2 == node else -1)
                  for e in c.elements if node in (e.n1, e.n2))
        assert np.all(np.abs(net) <= 1e-12 * scale), node


@pytest.fixture
def both_paths():
    """Run a test with the compiled plan forced on, then off; restores the default.

    Yields :mod:`mechcirc._jit`, whose ``COMPILED`` the test sets."""
    from mechcirc import _jit

    saved = _jit.COMPILED
    yield _jit
    _jit.COMPILED = saved


def _trees_for_paths():
    from reference import sp_corpus

    rng = np.random.default_rng(99)
    trees = [sp_corpus.random_tree(rng, int(rng.integers(1, 40)), damped=d)
             for _ in range(40) for d in (0.0, 0.3)]
    trees.append(sp_corpus.ladder(rng, 45))
    # A wide node: many internal children (the compiled plan's value stack is deep).
    trees.append(("p", [("s", [("leaf", "spring", 1e3 + i), ("leaf", "mass", 1.0 + i)])
                        for i in range(50)]))
    trees.append(("leaf", "damper", 3.0))                      # a leaf alone
    trees.append(("lever", 0.3, ("leaf", "mass", 2.0)))       # a lever over one leaf
    return [sp_corpus.to_circuit(t) for t in trees]


def test_compiled_plan_computes_what_the_numpy_path_computes(both_paths):
    pytest.importorskip("numba")
    omega = np.concatenate([[0.0, np.inf], np.geomspace(1e-3, 1e3, 60)])
    for c in _trees_for_paths():
        tree = c.tree
        both_paths.COMPILED = True
        K1, r1 = reduction.evaluate(tree, omega, error=True)
        K1b = reduction.evaluate(tree, omega)
        both_paths.COMPILED = False
        K0, r0 = reduction.evaluate(tree, omega, error=True)
        np.testing.assert_array_equal(K1, K1b)
        ok = np.isfinite(K0) & np.isfinite(K1)
        # The same operations in the same order; a few ulps where a complex
        # reciprocal or |K| is computed differently (measured 3e-15).
        np.testing.assert_allclose(K1[ok], K0[ok], rtol=2e-14, atol=0)
        fin = np.isfinite(r0)
        np.testing.assert_allclose(r1[fin], r0[fin], rtol=1e-12)
        assert np.array_equal(np.isfinite(r1), fin)
        # Where the numpy path gives NaN (inf·0 in a lever's complex division at
        # ω = 0 or ∞) the compiled one may give a value; both flag the point.
        assert not np.isnan(r1).any()


def test_compiled_plan_matches_mpmath_on_a_ladder(both_paths):
    pytest.importorskip("numba")
    from reference import sp_corpus

    rng = np.random.default_rng(45)
    expr = sp_corpus.ladder(rng, 999)
    c = sp_corpus.to_circuit(expr)
    omega = np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, 9)
    both_paths.COMPILED = True
    K, rho = reduction.evaluate(c.tree, omega, error=True)
    true = sp_corpus.true_error(K, sp_corpus.reference(expr, omega))
    assert true.max() < 1e-12          # measured 1.6e-16 … 2e-15
    assert np.all(rho >= true)
    # Shapes: a 0-d ω and an empty one.
    assert reduction.evaluate(c.tree, np.float64(3.0)).shape == ()
    assert reduction.evaluate(c.tree, np.array([])).shape == (0,)


def test_a_long_series_run_grown_at_its_front_keeps_every_spring(monkeypatch):
    """100 springs in series, written in a shuffled order with random orientations (seed
    0): a run of more than 64 operands is grown at its front (_Run.prepend's deque path);
    K = jω Σ 1/k_i + 1/(jω m), the series of the springs' and the mass's mobilities, in
    mpmath."""
    grown = []
    prepend = reduction._Run.prepend

    def spy(self, kids, signs):
        grown.append(len(self.children))
        prepend(self, kids, signs)

    monkeypatch.setattr(reduction._Run, "prepend", spy)
    n, rng = 100, np.random.default_rng(0)
    order, flip = rng.permutation(n), rng.integers(0, 2, n)
    springs = [f"spring s{i} n{i + flip[i]} n{i + 1 - flip[i]} {1000 + i}\n" for i in order]
    c = mechcirc.parse(f"drive V n0 0 velocity=1\nmass m n{n} 0 2.5\n" + "".join(springs))
    omega = np.array([0.3, 10.0, 400.0])
    K = c.sweep(omega).K
    assert max(grown) > 64
    compliance = mpmath.fsum(1 / mpmath.mpf(1000 + i) for i in range(n))
    ref = [complex(1j * mpmath.mpf(w) * compliance + 1 / (1j * mpmath.mpf(w) * 2.5))
           for w in omega]
    np.testing.assert_allclose(K, ref, rtol=1e-14)


def test_fast_node_constructors_make_what_init_makes():
    """reduction builds its nodes without the frozen dataclasses' __init__: the same
    objects, field for field (a new field would make them differ here)."""
    e = mechcirc.parse("mass m a 0 1\ndrive V a 0 velocity=1\n").elements[0]
    leaf = reduction._leaf(e)
    assert type(leaf) is reduction.Leaf and vars(leaf) == vars(reduction.Leaf(e))
    for cls in (reduction.Series, reduction.Parallel):
        made = reduction._branches(cls, (leaf, leaf), (1, -1))
        assert type(made) is cls and vars(made) == vars(cls((leaf, leaf), (1, -1)))


def test_plan_with_values_defaults_to_each_levers_own_ratio_for_many_designs():
    """``Plan.with_values(scaled)`` without ``ratios`` gives every design the levers'
    own ratios (its docstring), for D > 1 as for D = 1: the same plan as with those
    ratios written out (it raised a shape error for D > 1)."""
    from mechcirc import _tree_eval

    c = mechcirc.parse("drive V a 0 velocity=1\nmass m a 0 2\nlever L a 0 b 0 ratio=3\n"
                       "spring k b 0 50\ndamper c b 0 0.5\n")
    p = _tree_eval.plan(c.tree)
    assert len(p.levers) == 1 and len(p.leaves) == 3
    scaled = np.array([[e.value * e.eta] for e in p.leaves]) * np.array([[1.0, 2.0, 0.5]])
    got = p.with_values(scaled)
    want = p.with_values(scaled, np.full((1, 3), 3.0))
    assert got.designs == 3
    for a, b in zip(got.arrays(), want.arrays()):
        np.testing.assert_array_equal(a, b)
