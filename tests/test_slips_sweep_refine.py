"""``sweep(..., refine=False)`` is remembered by the Sweep (plain data, it pickles), and the
follow-up evaluations (peak, the plot's points near the roots, node velocities) solve
unrefined too, bit for bit as ``nodal.solve(refine=False)``."""

import pickle

import matplotlib
import numpy as np
import pytest

from mechcirc import nodal, parse, sweep
from mechcirc.resonances import find_resonances

matplotlib.use("Agg")

NET = """\
drive  V a 0 velocity=1
mass   m1 a 0 1
spring k1 a b 1e4
mass   m2 b 0 2
damper c2 b 0 3
spring k2 b 0 1e3
"""


@pytest.fixture
def spy(monkeypatch):
    calls = []
    real = nodal.solve

    def solve(system, omega, **kw):
        calls.append(kw.get("refine", True))
        return real(system, omega, **kw)

    monkeypatch.setattr(nodal, "solve", solve)
    return calls


@pytest.mark.parametrize("refine", [False, True])
def test_peak_solves_as_the_sweep_did(spy, refine):
    c = parse(NET)
    s = sweep(c, np.geomspace(10, 1000, 50), method="nodal", refine=refine)
    assert s.refine is refine and pickle.loads(pickle.dumps(s)).refine is refine
    assert s.with_notes(("x",)).refine is refine
    spy.clear()
    p = s.peak()
    assert spy and set(spy) == {refine}
    # The peak's value is |V0/K| at its omega as the plain (or refined) solve gives it
    # (to the rounding of V0/K against 1/K, 1 ulp; plain and refined K differ by 2.4e-13).
    K = nodal.solve(c.nodal, [p.omega], refine=refine).K[0]
    assert p.value == pytest.approx(abs(1 / K), rel=4e-16, abs=0)


def test_plot_and_node_velocity_solve_unrefined(spy, monkeypatch):
    c = parse(NET)
    s = sweep(c, np.geomspace(10, 1000, 20), method="nodal", refine=False)
    spy.clear()
    s.plot(resonances=find_resonances(c, omega_max=1000))
    assert spy and set(spy) == {False}
    units = []
    real_unit = nodal.solve_unit
    monkeypatch.setattr(nodal, "solve_unit",
                        lambda sys, w, **kw: units.append(kw.get("refine")) or
                        real_unit(sys, w, **kw))
    v = s.node_velocity("b")
    assert units == [False]
    ref = real_unit(c.nodal, s.omega, refine=False)[:, list(c.nodal.nodes).index("b")]
    assert np.array_equal(v, ref * s.Q0)


@pytest.mark.parametrize("refine", [False, True])
def test_element_force_and_velocity_solve_as_the_sweep_did(monkeypatch, refine):
    c = parse(NET)
    s = sweep(c, np.geomspace(10, 1000, 20), method="nodal", refine=refine)
    units = []
    real_unit = nodal.solve_unit
    monkeypatch.setattr(nodal, "solve_unit",
                        lambda sys, w, **kw: units.append(kw.get("refine", True)) or
                        real_unit(sys, w, **kw))
    Q, v = s.force("k1"), s.velocity("k1")
    assert units == [refine]            # one solve, cached for both, with the sweep's choice
    # k1 runs a -> b: v is the difference of the node velocities of the same solve, and
    # Q = k v / (jω) for a spring of k = 1e4 N/m.
    x = real_unit(c.nodal, s.omega, refine=refine) * s.Q0[:, None]
    nodes = list(c.nodal.nodes)
    ref_v = x[:, nodes.index("a")] - x[:, nodes.index("b")]
    assert np.allclose(v, ref_v, rtol=1e-14, atol=0)
    assert np.allclose(Q, 1e4 * ref_v / (1j * s.omega), rtol=1e-12, atol=0)
