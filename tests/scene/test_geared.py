"""Geared cranks in scenes: the FNF six-bar (examples/fnf_sixbar_scene.toml) against an
independent Lagrange derivation in SymPy.

The reference knows nothing of mechcirc's linkage solver, circuits or kernels: the
six-bar's loop-closure equations are written in SymPy in the rotations (φ3, φ4, φ5, φ6)
of links 3–6 from the pose, with crank 1 at ψ and crank 2 at r·ψ; positions come from
Newton on them, velocity and acceleration ratios from differentiating them (SymPy),
and the equations of motion from Lagrange II applied in SymPy to

    T = ½ J_red(ψ) ψ̇² + ½ J_o φ̇_o²,   J_red = J1 + J2 r² + m_K |dK/dψ|²,
    U = ½ C1 (θ_s − ψ)² + ½ C6 (φ_o − φ6(ψ))²,  R = the same with d1, d6 and rates,

θ_s = Ω t the main shaft (prescribed).  Integrated by DOP853 at rtol 1e-10.
"""

import math
import tomllib

import numpy as np
import pytest

from mechcirc.errors import NetlistError
from mechcirc.scene import build, load_scene, parse_scene
from mechcirc.scene.simulation import simulate_scene

sp = pytest.importorskip("sympy")

FILE = "examples/fnf_sixbar_scene.toml"


class Reference:
    """The FNF scene's kinematics and dynamics, derived independently (see the module doc)."""

    def __init__(self, path=FILE):
        with open(path, "rb") as fh:
            doc = tomllib.load(fh)
        L = 1e-3
        P = {k: np.array(v, float) * L for k, v in doc["points"].items()}
        self.r = doc["gears"][0]["ratio"]
        self.omega = doc["cranks"][0]["omega"]
        tors = {t["name"]: t for t in doc["torsion"]}
        mass = {m["name"]: m for m in doc["masses"]}
        self.C1, self.d1 = tors["C1"]["stiffness"], tors["C1"]["damping"]
        self.C6, self.d6 = tors["C6"]["stiffness"], tors["C6"]["damping"]
        self.J1, self.J2 = mass["J1"]["inertia"], mass["J2"]["inertia"]
        self.mK, self.Jo = mass["mK"]["mass"], mass["Jorgan"]["inertia"]

        th = sp.Symbol("theta")
        x = sp.symbols("x3 x4 x5 x6")
        xd = sp.symbols("xd3 xd4 xd5 xd6")
        xdd = sp.symbols("xdd3 xdd4 xdd5 xdd6")

        def rot(a, v):
            return sp.Matrix([sp.cos(a) * v[0] - sp.sin(a) * v[1],
                              sp.sin(a) * v[0] + sp.cos(a) * v[1]])

        def M(p):
            return sp.Matrix([sp.Float(P[p][0], 30), sp.Float(P[p][1], 30)])

        A = M("O1") + rot(th, M("A") - M("O1"))
        B = M("O2") + rot(self.r * th, M("B") - M("O2"))
        C = A + rot(x[0], M("C") - M("A"))
        E4 = C + rot(x[1], M("E") - M("C"))
        K4 = C + rot(x[1], M("K") - M("C"))
        E5 = B + rot(x[2], M("E") - M("B"))
        K6 = M("O6") + rot(x[3], M("K") - M("O6"))
        F = sp.Matrix([*(E4 - E5), *(K4 - K6)])

        def D(e):           # total derivative along the motion, x = x(θ)
            if isinstance(e, sp.MatrixBase):
                return e.applyfunc(D)
            return (sp.diff(e, th) + sum(sp.diff(e, a) * b for a, b in zip(x, xd))
                    + sum(sp.diff(e, a) * b for a, b in zip(xd, xdd)))

        Fx = F.jacobian(x)
        self._F = sp.lambdify((th, x), F, "numpy")
        self._Fx = sp.lambdify((th, x), Fx, "numpy")
        self._Fth = sp.lambdify((th, x), F.diff(th), "numpy")
        self._F2 = sp.lambdify((th, x, xd), D(D(F)).subs(dict.fromkeys(xdd, 0)), "numpy")
        Kd = sp.Matrix([D(K6[0]), D(K6[1])])
        Jred = self.J1 + self.J2 * self.r ** 2 + self.mK * (Kd[0] ** 2 + Kd[1] ** 2)
        self._Jred = sp.lambdify((th, x, xd), Jred, "numpy")
        self._dJred = sp.lambdify((th, x, xd, xdd), D(Jred), "numpy")
        self._x = np.zeros(4)

        # Lagrange II in SymPy on T, U, R with J_red(ψ), φ6(ψ) as functions of ψ
        t = sp.Symbol("t")
        psi, psid, po, pod, psidd, podd = sp.symbols("psi psid po pod psidd podd")
        Jf, f6 = sp.Function("Jred"), sp.Function("phi6")
        Om = sp.Symbol("Omega")
        ths = Om * t
        q, qd, qdd = (psi, po), (psid, pod), (psidd, podd)
        T = Jf(psi) * psid ** 2 / 2 + self.Jo * pod ** 2 / 2
        U = self.C1 * (ths - psi) ** 2 / 2 + self.C6 * (po - f6(psi)) ** 2 / 2
        rate6 = pod - sp.diff(f6(psi), psi) * psid
        R = self.d1 * (Om - psid) ** 2 / 2 + self.d6 * rate6 ** 2 / 2
        eqs = []
        for i in range(2):
            dTdqd = sp.diff(T, qd[i])
            ddt = (sum(sp.diff(dTdqd, q[j]) * qd[j] + sp.diff(dTdqd, qd[j]) * qdd[j]
                       for j in range(2)))
            eqs.append(ddt - sp.diff(T, q[i]) + sp.diff(U, q[i]) + sp.diff(R, qd[i]))
        sol = sp.solve(eqs, qdd, dict=True)[0]
        jv, j1, f1 = sp.symbols("jv j1 f1")
        f0 = sp.Symbol("f0")
        rep = {sp.Derivative(Jf(psi), psi): j1, sp.Derivative(f6(psi), psi): f1}
        acc = [sol[a].subs(rep).subs({Jf(psi): jv, f6(psi): f0}) for a in qdd]
        self._acc = sp.lambdify((t, psi, psid, po, pod, jv, j1, f0, f1, Om), acc, "numpy")
        # the linearisation at rest about the rigid state (drive held): M, D, K
        self._lin = (U, R, q, qd, Jf, f6, psi, t, Om, rep, jv, f0, f1)

    def kin(self, theta):
        """(x, x', x'') at crank-1 rotation θ: Newton on the closure, then the derivatives."""
        x = self._x.copy()
        for _ in range(50):
            r = np.asarray(self._F(theta, x), float).ravel()
            dx = np.linalg.solve(np.asarray(self._Fx(theta, x), float), r)
            x = x - dx
            if np.max(np.abs(dx)) < 1e-15:
                break
        self._x = x
        Fx = np.asarray(self._Fx(theta, x), float)
        xd = np.linalg.solve(Fx, -np.asarray(self._Fth(theta, x), float).ravel())
        xdd = np.linalg.solve(Fx, -np.asarray(self._F2(theta, x, xd), float).ravel())
        return x, xd, xdd

    def continue_to(self, theta, steps=60):
        """Follow the branch from the pose to θ in small steps (the Newton start)."""
        self._x = np.zeros(4)
        for s in np.linspace(0.0, theta, steps + 1)[1:]:
            self.kin(s)
        return self.kin(theta)

    def rhs(self, t, y):
        psi, psid, po, pod = y
        x, xd, xdd = self.kin(psi)
        jv, j1 = self._Jred(psi, x, xd), self._dJred(psi, x, xd, xdd)
        a = self._acc(t, psi, psid, po, pod, jv, j1, x[3], xd[3], self.omega)
        return [psid, a[0], pod, a[1]]

    def matrices(self, theta):
        """M, D, K of the free coordinates (ψ, φ_o) at the rigid state at θ, shaft held."""
        U, R, q, qd, Jf, f6, psi, t, Om, rep, jv, f0, f1 = self._lin
        x, xd, _ = self.continue_to(theta)
        rest = {q[0]: theta, q[1]: x[3], t: theta / 1.0, Om: 1.0, qd[0]: 0, qd[1]: 0}
        K = sp.hessian(U, q)
        Dm = sp.hessian(R, qd)
        vals = {f6(psi): x[3]}
        num = []
        for Mx in (K, Dm):
            Mx = Mx.subs(rep).subs(vals).subs({f1: xd[3]}).subs(rest)
            num.append(np.array(Mx.evalf(), dtype=float))
        Mm = np.diag([self._Jred(theta, x, xd), self.Jo])
        return Mm, num[1], num[0]


@pytest.fixture(scope="module")
def ref():
    return Reference()


@pytest.mark.parametrize("deg", [40.0, 200.0, 555.0])
def test_circuit_at_theta_matches_the_sympy_linearisation(ref, deg):
    """The circuit's resonances (drive held) are the eigenvalues of the linearised
    Lagrangian at θ (over the two-revolution cycle: 555° is on the second turn) to 1e-8."""
    scene = load_scene(FILE)
    th = math.radians(deg)
    Mm, Dm, Km = ref.matrices(th)
    n = 2
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -np.linalg.solve(Mm, Km)
    A[n:, n:] = -np.linalg.solve(Mm, Dm)
    s = np.linalg.eigvals(A)
    s = s[s.imag > 0]
    want = sorted((abs(z), -z.real / abs(z)) for z in s)
    got = sorted((r.omega, r.zeta) for r in build(scene, th).circuit.resonances()
                 if r.kind == "resonance")
    assert len(got) == len(want) == 2
    for (w1, z1), (w2, z2) in zip(got, want):
        assert abs(w1 - w2) <= 1e-8 * w2
        assert abs(z1 - z2) <= 1e-8 * max(z2, 1e-3)


@pytest.mark.slow
def test_simulation_matches_the_sympy_equations_over_a_revolution(ref):
    """mechcirc simulate (RK4, 400 steps per period of the fastest mode, one cycle)
    against the SymPy equations integrated by DOP853 (rtol 1e-10): the forces in the rods C1 and C6 and the organ's
    acceleration over the first revolution of crank 1, to 1e-6 of their largest value."""
    from scipy.integrate import solve_ivp

    scene = load_scene(FILE)
    res = simulate_scene(scene, revolutions=1, points=240, steps_per_period=400,
                         error_estimate=False)
    ts = res.time
    keep = ts <= 2 * math.pi / ref.omega            # the first revolution of crank 1
    order = np.argsort(ts[keep])
    ts = ts[keep][order]
    ref.continue_to(0.0)
    _, xd0, _ = ref.kin(0.0)
    y0 = [0.0, ref.omega, 0.0, xd0[3] * ref.omega]
    sol = solve_ivp(ref.rhs, (0.0, ts[-1]), y0, method="DOP853", rtol=1e-10, atol=1e-12,
                    t_eval=ts)
    assert sol.status == 0
    psi, psid, po, pod = sol.y
    m1, m6, acc = [], [], []
    for k, t in enumerate(ts):
        x, xd, _ = ref.kin(psi[k])
        m1.append(ref.C1 * (ref.omega * t - psi[k]) + ref.d1 * (ref.omega - psid[k]))
        m6.append(ref.C6 * (po[k] - x[3]) + ref.d6 * (pod[k] - xd[3] * psid[k]))
        acc.append(ref.rhs(t, sol.y[:, k])[3])
    for name, want in (("C1.force", m1), ("C6.force", m6), ("organ.acceleration", acc)):
        got = res.values[name][keep][order]
        want = np.array(want)
        err = np.max(np.abs(got - want)) / np.max(np.abs(want))
        assert err <= 1e-6, (name, err)


def test_the_cycle_spans_two_turns_of_crank_one():
    scene = load_scene(FILE)
    assert scene.cycle_revolutions == 2
    assert math.isclose(scene.cycle, 4 * math.pi)


GEARED = """
units = "mm"
[points]
O1 = [0.0, 0.0]
A = [20.0, 0.0]
O2 = [200.0, 0.0]
B = [230.0, 0.0]
C = [260.0, 90.0]
D = [320.0, 0.0]
[ground]
points = ["O1", "O2", "D"]
[links]
crank1 = ["O1", "A"]
crank2 = ["O2", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank1"
omega = 10.0
[[cranks]]
link = "crank2"
omega = 20.0
[[masses]]
link = "rocker"
inertia = 0.02
[[masses]]
link = "crank2"
inertia = 0.001
[drive]
link = "crank1"
velocity = 1.0
"""


def test_mesh_stiffness_is_a_torsion_rod_at_the_geared_crank():
    """crank 2 geared 2:1 to crank 1 through a mesh of stiffness k drives a four-bar: with
    crank 1 held the circuit rings at √(k / (J2 + J_rocker (μ/2)²)), μ = ω_rocker/ω_crank1;
    the simulation of the separate part follows its rigid motion to within the mesh twist."""
    text = GEARED + "[[gears]]\ncrank = \"crank2\"\nratio = 2\nstiffness = 3000.0\ndamping = 0.3\n"
    scene = parse_scene(text)
    assert [set(p) for p in scene.parts] == [{"crank1", "gear_crank2"},
                                            {"crank2", "coupler", "rocker"}]
    model = build(scene, math.radians(30))
    mu = model.ratios["J_rocker"]
    want = math.sqrt(3000.0 / (0.001 + 0.02 * (mu / 2) ** 2))
    got = [r.omega for r in model.circuit.resonances() if r.kind == "resonance"]
    assert len(got) == 1 and abs(got[0] - want) <= 1e-12 * want
    res = simulate_scene(scene, revolutions=3, points=360, steps_per_period=100)
    twist = res.extrema["mesh_crank2.deformation"]
    assert 0 < max(map(abs, twist)) < 1e-3          # the crank follows 2θ within the mesh twist
    assert res.periodicity < 1e-6


@pytest.mark.parametrize("gear, message", [
    ("ratio = 0", "gear ratio 0 would stop crank 'crank2'"),
    ("ratio = 3", "has omega = 20 rad/s in [[cranks]] but the gear ratio 3 makes it 30"),
    ("ratio = 1.41421356237", "is not a ratio of whole numbers"),
])
def test_bad_gear_ratios_are_located(gear, message):
    with pytest.raises(NetlistError, match=message.replace("[", r"\[").replace("]", r"\]")):
        parse_scene(GEARED + f"[[gears]]\ncrank = \"crank2\"\n{gear}\n")


def test_cranks_at_different_speeds_need_a_gear():
    with pytest.raises(NetlistError, match="needs a \\[\\[gears\\]\\] entry") as exc:
        parse_scene(GEARED)
    assert 'ratio = 2' in str(exc.value)


def test_cycle_map_spans_the_cycle_and_equals_the_circuit_at_each_angle():
    from mechcirc.scene.cycle import cycle_map

    scene = load_scene(FILE)
    cmap = cycle_map(scene, points=8, harmonics=2)
    assert np.allclose(cmap.theta, np.arange(8) * math.pi / 2)        # 0 … 4π, end excluded
    assert cmap.omega_shaft == 10.0                                    # |Ω| / 2 revolutions
    for k in (3, 6):                                                   # 270°, 540°
        want = [r.omega for r in build(scene, cmap.theta[k]).circuit.resonances()
                if r.kind == "resonance"]
        got = [r.omega for r in cmap.resonances[k]]
        assert np.allclose(got, want, rtol=1e-12, atol=0)


def test_an_elastic_mesh_inside_the_closed_loop_is_refused():
    from mechcirc.errors import GeometryError

    text = open(FILE, encoding="utf-8").read().replace(
        "ratio = -1.5\n", "ratio = -1.5\nstiffness = 1.0e4\n")
    with pytest.raises(GeometryError, match=r"has W = 3·7 − 2·9 − 1 = 2 degrees of freedom "
                                            r"\(a rigid gear mesh counts 1\).*an elastic gear "
                                            r"mesh inside a loop through both cranks"):
        parse_scene(text, FILE)
