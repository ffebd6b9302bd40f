"""The fast linkage solvers (closed-form dyads, batched Newton) against independent references.

References: the closed-form FourBar (positions, μ, ν to ~1e-12), finite
differences of positions, and scipy.optimize.fsolve on the constraint
equations (a second solver) for the class-III six-bar.
"""

import math
import pickle
from pathlib import Path

import numpy as np
import pytest
from linkage_reference import jac, phi
from scipy.optimize import fsolve

from mechcirc.errors import GeometryError
from mechcirc.kinematics import FourBar, load_linkage, parse_linkage

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(params=["compiled", "numpy"])
def backend(request, monkeypatch):
    """Newton as one compiled loop (numba; plain Python without it) or batched numpy."""
    from mechcirc import _jit

    monkeypatch.setattr(_jit, "COMPILED", request.param == "compiled")
    return request.param

TEMPLATE = """
[points]
A = [0.0, 0.0]
B = [{bx!r}, {by!r}]
C = [{cx!r}, {cy!r}]
D = [{d!r}, 0.0]
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = {omega!r}
"""


def fourbar_linkage(a, b, c, d, branch=1, theta0=0.0, omega=100.0):
    fb = FourBar(a, b, c, d, branch=branch)
    phi4 = fb.rocker_angle(theta0)
    text = TEMPLATE.format(bx=a * math.cos(theta0), by=a * math.sin(theta0),
                           cx=d + c * math.cos(phi4), cy=c * math.sin(phi4), d=d, omega=omega)
    return parse_linkage(text), fb


@pytest.mark.parametrize("dims,branch", [((29.0, 37.0, 188.0, 189.0), 1),
                                         ((29.0, 37.0, 188.0, 189.0), -1),
                                         ((20.0, 70.0, 60.0, 80.0), 1),
                                         ((60.0, 90.0, 80.0, 30.0), 1)])   # double-crank
# the dyads are numpy on either backend (one source since the thirteenth session): once
@pytest.mark.parametrize("method,backend", [("dyads", "numpy"), ("newton", "compiled"),
                                            ("newton", "numpy")], indirect=["backend"])
def test_fourbar_against_the_closed_form(dims, branch, method, backend):
    a, b, c, d = dims
    omega = 100.0
    lk, fb = fourbar_linkage(a, b, c, d, branch, theta0=0.4, omega=omega)
    theta = np.linspace(0.0, 2 * math.pi, 721)
    m = lk.motion(theta, method=method)
    assert m.method == method
    st = fb.evaluate(0.4 + theta)
    i3, i4 = m.link_names.index("coupler"), m.link_names.index("rocker")
    C = m.points[:, m.point_names.index("C")]
    phi4 = np.arctan2(C[:, 1], C[:, 0] - d)
    np.testing.assert_allclose((phi4 - st.phi4 + np.pi) % (2 * np.pi) - np.pi, 0, atol=1e-12)
    # link rates divided by ω (ω²) are μ, μ3 (ν, ν3); relative to each ratio's
    # largest value ≤ 1.4e-14 is achieved on these geometries, 1e-13 asserted
    for got, want in ((m.angular_velocities[:, i4] / omega, st.mu),
                      (m.angular_velocities[:, i3] / omega, st.mu3),
                      (m.angular_accelerations[:, i4] / omega ** 2, st.nu),
                      (m.angular_accelerations[:, i3] / omega ** 2, st.nu3)):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * np.max(np.abs(want)))


def test_dyads_and_newton_agree_on_a_six_bar_of_two_dyads(backend):
    text = (ROOT / "tests" / "kinematics" / "test_linkage.py").read_text()
    block = text.split('def test_structure_of_a_six_bar_of_two_dyads():\n    text = """', 1)[1]
    lk = parse_linkage(block.split('"""', 1)[0])
    assert lk.solver == "dyads"
    th = np.linspace(0.0, 1.0, 50)
    a, b = lk.motion(th), lk.motion(th, method="newton")
    for x, y in ((a.q, b.q), (a.qdot, b.qdot), (a.qddot, b.qddot)):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-13 * np.max(np.abs(y)))  # 2e-15 achieved


def test_six_bar_against_fsolve_and_finite_differences(backend):
    lk = load_linkage(ROOT / "examples" / "fnf_sixbar.toml")
    assert lk.solver == "newton"
    th = np.radians(np.arange(0.0, 360.0, 0.25))
    m = lk.motion(th)
    local, idx, rows = lk.local_offsets(), lk.link_index(), lk.constraint_rows()
    for k in (0, 97, 400, 1000, 1439):
        angles = [c.omega * m.t[k] for c in lk.cranks]
        guess = m.q[k] + 1e-3                   # fsolve from a perturbed start
        ref = fsolve(lambda x: phi(lk, x, angles, local, idx, rows), guess,
                     fprime=lambda x: jac(lk, x, local, idx, rows), xtol=1e-13)
        np.testing.assert_allclose(m.q[k], ref, rtol=0, atol=3e-13)   # 2.8e-14 achieved
    # 4th-order central differences in time of q and q̇ (0.25° spacing): their
    # truncation leaves 2.4e-10 (q̇) and 6.2e-10 (q̈) of the largest value; 3e-9 asserted
    dt = m.t[1] - m.t[0]
    fd_v = (m.q[:-4] - 8 * m.q[1:-3] + 8 * m.q[3:-1] - m.q[4:]) / (12 * dt)
    fd_a = (m.qdot[:-4] - 8 * m.qdot[1:-3] + 8 * m.qdot[3:-1] - m.qdot[4:]) / (12 * dt)
    np.testing.assert_allclose(m.qdot[2:-2], fd_v, rtol=0, atol=3e-9 * np.max(np.abs(m.qdot)))
    np.testing.assert_allclose(m.qddot[2:-2], fd_a, rtol=0, atol=3e-9 * np.max(np.abs(m.qddot)))


def test_targets_far_apart_still_continue_along_the_branch(backend):
    lk = load_linkage(ROOT / "examples" / "fnf_sixbar.toml")
    dense = lk.motion(np.radians(np.arange(0.0, 300.0, 1.0)))
    sparse = lk.motion(np.radians([299.0, 100.0, 7.0]))
    for k, deg in enumerate((299, 100, 7)):
        np.testing.assert_allclose(sparse.q[k], dense.q[deg], atol=1e-12)  # 1.4e-14 achieved


def test_lock_is_located_by_the_dyad_path():
    fb = FourBar(30.0, 10.0, 30.0, 25.0)            # double-rocker written as a crank
    lo, hi = fb.crank_range()
    th0 = 0.5 * (lo + hi)
    lk, _ = fourbar_linkage(30.0, 10.0, 30.0, 25.0, theta0=th0, omega=1.0)
    with pytest.raises(GeometryError, match=r"locks near θ = ([\d.]+)°") as info:
        lk.motion(np.array([0.1, math.pi]))
    import re
    got = float(re.search(r"θ = ([\d.]+)°", str(info.value)).group(1))
    assert got == pytest.approx(math.degrees(hi - th0), abs=1e-4)   # 6 digits printed


def test_motion_pickles_and_states_match(backend):
    lk = load_linkage(ROOT / "examples" / "fnf_sixbar.toml")
    m = lk.motion(np.radians([10.0, 20.0]))
    m2 = pickle.loads(pickle.dumps(m))
    np.testing.assert_array_equal(m2.points, m.points)
    s = lk.solve(math.radians(20.0))
    for p, x in s.points.items():
        np.testing.assert_allclose(x, m.points[1, m.point_names.index(p)], atol=1e-12)


def test_lock_is_located_by_the_newton_path(backend):
    fb = FourBar(30.0, 10.0, 30.0, 25.0)
    lo, hi = fb.crank_range()
    th0 = 0.5 * (lo + hi)
    lk, _ = fourbar_linkage(30.0, 10.0, 30.0, 25.0, theta0=th0, omega=1.0)
    with pytest.raises(GeometryError, match=r"locks near θ = ([\d.]+)°") as info:
        lk.motion(np.array([0.1, math.pi]), method="newton")
    import re
    got = float(re.search(r"θ = ([\d.]+)°", str(info.value)).group(1))
    assert got == pytest.approx(math.degrees(hi - th0), abs=1e-3)


def test_states_fill_their_dicts_on_access_and_pickle_as_plain_data():
    lk = load_linkage(ROOT / "examples" / "fnf_sixbar.toml")
    th = np.radians([10.0, 20.0, 30.0])
    states, m = lk.solve(th), lk.motion(th)
    s1 = states[1]
    data = pickle.dumps(s1)
    assert b"_rows" not in data                 # not the rows of the other positions
    back = pickle.loads(data)
    ref = m.state(1)
    for s in (s1, back):
        assert set(s.points) == set(lk.pose)
        for name in ("points", "velocities", "accelerations"):
            for p, x in getattr(ref, name).items():
                np.testing.assert_array_equal(getattr(s, name)[p], x)
        assert s.angular_velocities == ref.angular_velocities
        for c, d in ref.contributions.items():
            for p, x in d.items():
                np.testing.assert_array_equal(s.contributions[c][p], x)
    assert "velocities=" in repr(states[2])
    with pytest.raises(AttributeError):
        s1.no_such_field


def test_targets_newton_misses_are_redone_by_single_steps(monkeypatch):
    """numpy path: when the batched Newton from the interpolated guess fails for a target,
    the target is reached by single continuation steps from the kept node before it
    (here every batched solve is made to report failure, so blocks shrink to single
    steps and every target takes that path); the positions equal the ones of the normal
    path within the residual a single step converges to, 1e-12 of the linkage's size
    (8.8e-11 of 1.6e-10 achieved), and the velocities to 1e-11 of their largest (8.1e-13
    achieved); the removed fallback of its own (_continue) gave the same numbers."""
    from mechcirc import _jit
    from mechcirc.kinematics import linkage_solver

    monkeypatch.setattr(_jit, "COMPILED", False)
    lk = load_linkage(ROOT / "examples" / "fnf_sixbar.toml")
    theta = np.radians([299.0, 100.0, 7.0, 7.5])
    ref = lk.motion(theta, method="newton")
    solve = linkage_solver.Newton.newton

    def failing(self, q, angles, *args, **kwargs):
        q, ok = solve(self, q, angles, *args, **kwargs)
        return q, np.zeros_like(ok)

    monkeypatch.setattr(linkage_solver.Newton, "newton", failing)
    got = lk.motion(theta, method="newton")
    np.testing.assert_allclose(got.q, ref.q, rtol=0, atol=1e-12 * lk.length_scale())
    np.testing.assert_allclose(got.qdot, ref.qdot, rtol=0,
                               atol=1e-11 * np.max(np.abs(ref.qdot)))



def _from_targets():
    import sys

    return sys._getframe(2).f_code.co_name == "_targets"


@pytest.mark.parametrize("fault", ["singular", "mirror"])
def test_a_target_solved_singular_or_on_the_other_assembly_is_refused_at_its_angle(
        monkeypatch, fault):
    """numpy path, targets 1° apart (between the kept nodes, solved in one batch by
    _targets), the first of that batch made to go wrong: its q̇ not finite (a singular
    Jacobian) → 'singular position at θ' of that target; its Newton started on the
    other assembly (C from the closed-form FourBar's branch −1), converged there, from
    an interpolated guess that was not close (its residual patched up by 1) → 'branch
    jump near θ' of that target (det J changed sign)."""
    from mechcirc import _jit
    from mechcirc.kinematics import linkage_solver

    monkeypatch.setattr(_jit, "COMPILED", False)
    th0, dims = 0.4, (20.0, 70.0, 60.0, 80.0)
    lk, _ = fourbar_linkage(*dims, theta0=th0, omega=10.0)
    theta = np.radians(np.arange(0.0, 40.0, 1.0))
    solve, derive = linkage_solver.Newton.newton, linkage_solver.Newton.derivatives
    real_residual = linkage_solver.Newton.residual
    seen = []

    def derivatives(self, q):
        J, qd, qdd, parts = derive(self, q)
        if _from_targets():
            seen.append(q[0, 2])
            qd[0] = np.nan
        return J, qd, qdd, parts

    def newton(self, q, angles, *args, **kwargs):
        if not _from_targets():
            return solve(self, q, angles, *args, **kwargs)
        th = th0 + angles[0, 0]
        seen.append(angles[0, 0])
        B = dims[0] * np.array([math.cos(th), math.sin(th)])
        phi4 = FourBar(*dims, branch=-1).rocker_angle(th)
        C = np.array([dims[3], 0.0]) + dims[2] * np.array([math.cos(phi4), math.sin(phi4)])
        pose = lk.pose
        q = q.copy()
        q[0, 5] = math.atan2(*(C - B)[::-1]) - math.atan2(*(pose["C"] - pose["B"])[::-1])
        q[0, 8] = math.atan2(*(C - pose["D"])[::-1]) \
            - math.atan2(*(pose["C"] - pose["D"])[::-1])
        q, ok = solve(self, q, angles, *args, **kwargs)
        assert ok[0] and np.linalg.norm(q[0, 3:5] - B) < 1e-9    # converged, mirrored
        return q, ok

    def residual(self, q, angles, *args):
        r = real_residual(self, q, angles, *args)
        if _from_targets():
            r[0] += 1.0                 # the interpolated guess of that target was not close
        return r

    if fault == "singular":
        monkeypatch.setattr(linkage_solver.Newton, "derivatives", derivatives)
        message = "singular position at θ = {:.6g}° (constraint Jacobian not invertible)"
    else:
        monkeypatch.setattr(linkage_solver.Newton, "newton", newton)
        monkeypatch.setattr(linkage_solver.Newton, "residual", residual)
        message = "branch jump near θ = {:.6g}°: the position passed a singular configuration"
    with pytest.raises(GeometryError) as info:
        lk.motion(theta, method="newton")
    assert len(seen) == 1 and np.min(np.abs(theta - seen[0])) < 1e-12
    assert message.format(math.degrees(seen[0])) in str(info.value)
