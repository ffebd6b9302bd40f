"""Mode shapes, energy per element and sensitivities against independent references:
mpmath eigen-solves of hand-built M, C, K, closed forms, and central finite
differences of find_resonances."""

import dataclasses
import math

import mpmath
import numpy as np
import pytest

import mechcirc
from mechcirc.modes import modes

CHAIN = """drive V a 0 velocity=1
spring k1 a n1 1000
mass m1 n1 0 1.0
spring k2 n1 n2 2000
mass m2 n2 0 2.0
spring k3 n2 n3 1500
mass m3 n3 0 0.5
spring k4 n3 0 800
"""
VALUES = {"k1": 1000, "m1": 1.0, "k2": 2000, "m2": 2.0, "k3": 1500, "m3": 0.5, "k4": 800,
          "c2": 3.0}


def _chain_matrices(v, held: bool, damped: bool):
    """M, C, K (mpmath) of the chain n1-n2-n3, written by hand: node a held at rest
    (resonances) or released (k1 carries no force: anti-resonances)."""
    k1 = v["k1"] if held else 0
    M = mpmath.diag([v["m1"], v["m2"], v["m3"]])
    K = mpmath.matrix([[k1 + v["k2"], -v["k2"], 0],
                       [-v["k2"], v["k2"] + v["k3"], -v["k3"]],
                       [0, -v["k3"], v["k3"] + v["k4"]]])
    C = mpmath.diag([0, v["c2"] if damped else 0, 0])
    return M, C, K


def _mp_roots(M, C, K):
    """(s, x) of (s²M + sC + K) x = 0 with Im s ≥ 0, by mpmath's eig of the first-order form."""
    n = M.rows
    Minv = M ** -1
    A = mpmath.zeros(2 * n, 2 * n)
    for i in range(n):
        A[i, n + i] = 1
    A[n:, :n] = -Minv * K
    A[n:, n:] = -Minv * C
    E, ER = mpmath.eig(A)
    return [(complex(E[j]), np.array([complex(ER[i, j]) for i in range(n)]))
            for j in range(2 * n) if mpmath.im(E[j]) >= 0]


def _mac(a, b):
    return abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)


@pytest.mark.parametrize("damped", [False, True])
def test_mode_shapes_and_energies_against_an_mpmath_eigen_solve(damped):
    text = CHAIN + ("damper c2 n2 0 3.0\n" if damped else "")
    found = modes(mechcirc.parse(text))
    plain = mechcirc.parse(text).resonances()
    assert [m.resonance.kind for m in found] == [r.kind for r in plain]
    assert len(found) == 6
    with mpmath.workdps(30):
        for m, r in zip(found, plain):
            held = r.kind == "resonance"
            ref = _mp_roots(*_chain_matrices(VALUES, held, damped))
            s_ref, x = min(ref, key=lambda sx: abs(sx[0] - m.s))
            # modes() takes the roots from the eigen-solve that gives the vectors, not to
            # the bit those of resonances(): both within eps·λ_max/λ of mpmath's (achieved
            # 0.87 of it; asserted 2×).
            bound = 2 * np.finfo(float).eps * max(abs(s) for s, _ in ref) ** 2 / abs(s_ref) ** 2
            for s in (m.s, complex(-r.zeta * r.omega, r.omega_d)):
                assert abs(s_ref - s) <= bound * abs(s_ref)
            # Node a: at rest when held; released, it follows n1 through the unloaded k1.
            want = np.concatenate([[0 if held else x[0]], x])
            got = np.array([m.shape[n] for n in ("a", "n1", "n2", "n3")])
            assert 1 - _mac(got, want) <= 1e-12
            assert max(abs(z) for z in m.shape.values()) == 1
            # Energies from the reference vector (velocity = s·x), written out by hand.
            vel = s_ref * x
            wn2 = abs(s_ref) ** 2
            d = {"k1": vel[0] if held else 0, "k2": vel[0] - vel[1], "k3": vel[1] - vel[2],
                 "k4": vel[2]}
            E = {f"m{i + 1}": 0.5 * VALUES[f"m{i + 1}"] * abs(vel[i]) ** 2 for i in range(3)}
            E |= {k: 0.5 * VALUES[k] * abs(dv) ** 2 / wn2 for k, dv in d.items()}
            total = sum(E.values())
            for name, value in E.items():
                assert m.energy[name] == pytest.approx(value / total, abs=1e-12)
            assert abs(sum(m.energy.values()) - 1) <= 1e-12
            if damped:
                assert m.dissipation["c2"] == pytest.approx(
                    VALUES["c2"] * abs(vel[1]) ** 2 / (2 * math.sqrt(wn2) * total), rel=1e-12)
            # Element velocities and forces Q = S(s)·Δv from the reference vector, scaled as
            # the shape (complex: real vectors of an undamped root are reported complex too);
            # achieved 4.1e-15, asserted 2e-14.
            scale = got @ want.conj() / (want @ want.conj())
            at = dict(zip(("a", "n1", "n2", "n3", "0"), list(scale * want) + [0]))
            law = {"k": 1 / s_ref, "m": s_ref, "c": 1}       # S(s) per unit value
            for line in text.splitlines()[1:]:
                _, name, n1, n2, value = line.split()
                dv, S = at[n1] - at[n2], float(value) * law[name[0]]
                assert type(m.velocity[name]) is complex and type(m.force[name]) is complex
                assert abs(m.velocity[name] - dv) <= 2e-14
                assert abs(m.force[name] - S * dv) <= 2e-14 * max(abs(S), 1)


def test_single_degree_of_freedom_closed_forms():
    """m, k, c from one node to the frame, force-driven: the anti-resonance is the
    free oscillator; its damper's part of ζ is ζ = c / (2√(km)), the energies are
    ½ each, and the forces are S·v of each law at s."""
    m, k, c = 2.0, 800.0, 4.0
    (mode,) = modes(mechcirc.parse(f"drive F a 0 force=1\nmass m a 0 {m}\n"
                                   f"spring k a 0 {k}\ndamper c a 0 {c}\n"))
    zeta = c / (2 * math.sqrt(k * m))
    assert mode.resonance.kind == "antiresonance"
    assert mode.resonance.zeta == pytest.approx(zeta, rel=1e-13)
    assert mode.dissipation["c"] == pytest.approx(zeta, rel=1e-12)
    assert mode.energy == pytest.approx({"m": 0.5, "k": 0.5}, abs=1e-12)
    s = complex(-zeta, math.sqrt(1 - zeta ** 2)) * math.sqrt(k / m)
    assert mode.shape == {"a": 1}
    assert mode.force["m"] == pytest.approx(m * s, rel=1e-12)
    assert mode.force["k"] == pytest.approx(k / s, rel=1e-12)
    assert mode.force["c"] == pytest.approx(c, rel=1e-12)
    # Free oscillation: no net force on the node.
    assert abs(sum(mode.force.values())) <= 1e-12 * abs(mode.force["k"])
    assert mode.sensitivity == pytest.approx({"m": -0.5, "k": 0.5, "c": 0.0}, abs=1e-12)
    # ζ = c/(2√(km)): p·∂ζ/∂p = ζ·(exponent of p).
    assert mode.zeta_sensitivity == pytest.approx({"m": -zeta / 2, "k": -zeta / 2, "c": zeta},
                                                  abs=1e-12)


def test_an_unknown_name_in_a_modes_dictionaries_is_answered_with_did_you_mean():
    """energy['k44'] says which names there are (UnknownNameError, still a KeyError), as
    every other look-up by name does; the dictionaries stay plain picklable data."""
    import pickle

    from mechcirc.errors import UnknownNameError

    (mode,) = modes(mechcirc.parse("drive F a 0 force=1\nmass m a 0 2\n"
                                   "spring k4 a 0 800\ndamper c a 0 4\n"))
    for table, wrong, right in ((mode.energy, "k44", "k4"), (mode.shape, "aa", "a"),
                                (mode.dissipation, "cc", "c"), (mode.force, "mm", "m"),
                                (mode.velocity, "k44", "k4"), (mode.sensitivity, "k44", "k4"),
                                (mode.zeta_sensitivity, "k44", "k4")):
        with pytest.raises(UnknownNameError, match=f"did you mean '{right}'") as err:
            table[wrong]
        assert isinstance(err.value, KeyError)
        back = pickle.loads(pickle.dumps(table))
        assert isinstance(back, dict) and back == table
        with pytest.raises(UnknownNameError):
            back[wrong]
    assert "k4" in mode.energy and "c" not in mode.energy and mode.energy.get("c") is None


def test_overdamped_root_has_no_mode():
    found = modes(mechcirc.load("docs/examples/drive.mcir"))
    over = [m for m in found if m.resonance.omega_d == 0]
    assert len(over) == 1
    assert over[0].shape == {} and over[0].energy == {}
    assert "overdamped" in over[0].note
    assert all(m.shape and not m.note for m in found if m.resonance.omega_d > 0)


def _rebuilt(circuit, name, factor):
    """``circuit`` with the value (or lever ratio) of ``name`` multiplied by ``factor``."""
    els = tuple(dataclasses.replace(e, value=e.value * factor) if e.name == name else e
                for e in circuit.elements)
    levers = tuple(dataclasses.replace(lv, ratio=lv.ratio * factor) if lv.name == name else lv
                   for lv in circuit.levers)
    return dataclasses.replace(circuit, elements=els, levers=levers)


H = 1e-5


def _fd(make, n_roots):
    """Central differences of (ln ωₙ, ζ) of every root against ln p, step H."""
    up, down = make(1 + H).resonances(), make(1 - H).resonances()
    assert len(up) == len(down) == n_roots
    return ([(math.log(a.omega) - math.log(b.omega)) / (math.log1p(H) - math.log1p(-H))
             for a, b in zip(up, down)],
            [(a.zeta - b.zeta) / (math.log1p(H) - math.log1p(-H)) for a, b in zip(up, down)])


@pytest.mark.parametrize("path", ["docs/examples/drive.mcir", "netlists/stb_heald.mcir",
                                  "docs/examples/lever.mcir"])
def test_sensitivities_against_central_differences(path):
    circuit = mechcirc.load(path)
    found = modes(circuit)
    n = len(found)
    names = list(found[0].sensitivity)
    assert set(names) == {e.name for e in circuit.elements} | {lv.name for lv in circuit.levers}
    for name in names:
        rel, zeta = _fd(lambda f, name=name: _rebuilt(circuit, name, f), n)
        for m, r, z in zip(found, rel, zeta):
            scale = max(abs(x) for x in m.sensitivity.values())
            assert abs(m.sensitivity[name] - r) <= 1e-6 * scale, (name, m.resonance)
            assert abs(m.zeta_sensitivity[name] - z) <= 1e-6 * max(scale * m.resonance.zeta,
                                                                   1e-12), (name, m.resonance)
    # Scaling every mass, spring and damper together moves no root: the element
    # sensitivities sum to 0 (levers excluded).
    elements = {e.name for e in circuit.elements}
    for m in found:
        assert abs(sum(x for k, x in m.sensitivity.items() if k in elements)) <= 1e-12
    assert set(found[0].param_sensitivity) == set(circuit.params)
    for p, value in circuit.params.items():
        rel, zeta = _fd(lambda f, p=p, v=value: mechcirc.load(path, params={p: v * f}), n)
        for m, r, z in zip(found, rel, zeta):
            scale = max(abs(x) for x in m.sensitivity.values())
            assert abs(m.param_sensitivity[p] - r) <= 1e-6 * scale, (p, m.resonance)
            assert abs(m.param_zeta_sensitivity[p] - z) <= 1e-6 * max(
                scale * m.resonance.zeta, 1e-12), (p, m.resonance)


TWO_DOF = """.param kk=3000 cc=2.5
drive V a 0 velocity=1
spring k1 a n1 {kk}
mass m1 n1 0 1.5
damper c1 n1 0 {cc}
spring k2 n1 n2 {2*kk - 1000}
mass m2 n2 0 0.7 eta={sqrt(cc)}
spring k3 n2 0 900
"""


def _two_dof_roots(kk, cc, held):
    """The roots (Im s ≥ 0) of the netlist TWO_DOF, in mpmath, from hand-built matrices."""
    k1, k2, k3 = (kk if held else 0), 2 * kk - 1000, 900
    M = mpmath.diag([mpmath.mpf("1.5"), mpmath.mpf("0.7") * mpmath.sqrt(cc)])
    K = mpmath.matrix([[k1 + k2, -k2], [-k2, k2 + k3]])
    C = mpmath.diag([cc, 0])
    n = 2
    A = mpmath.zeros(4, 4)
    A[0, 2] = A[1, 3] = 1
    A[2:, :2] = -(M ** -1) * K
    A[2:, 2:] = -(M ** -1) * C
    E = mpmath.eig(A, right=False)
    return sorted((e for e in E if mpmath.im(e) > 0), key=lambda e: abs(e))[:n]


def test_sensitivities_against_mpmath_40_digits():
    """(p/ωₙ)∂ωₙ/∂p and p∂ζ/∂p of a damped two-degree-of-freedom system, elements
    and .params (through several values and an η), against central differences of
    its roots in 40-digit arithmetic (step 1e-12: error ~1e-24)."""
    found = modes(mechcirc.parse(TWO_DOF))
    assert len(found) == 4
    with mpmath.workdps(40):
        kk, cc, h = mpmath.mpf(3000), mpmath.mpf("2.5"), mpmath.mpf("1e-12")
        for m in found:
            held = m.resonance.kind == "resonance"
            roots = _two_dof_roots(kk, cc, held)
            k = min(range(len(roots)), key=lambda i: abs(complex(roots[i]) - m.s))

            def wz(kk_, cc_, held=held, k=k):
                s = _two_dof_roots(kk_, cc_, held)[k]
                return abs(s), -mpmath.re(s) / abs(s)

            for p, args in (("kk", lambda f: (kk * f, cc)), ("cc", lambda f: (kk, cc * f))):
                (w1, z1), (w0, z0) = wz(*args(1 + h)), wz(*args(1 - h))
                w = wz(kk, cc)[0]
                rel = float((w1 - w0) / (2 * h * w))
                dz = float((z1 - z0) / (2 * h))
                assert abs(m.param_sensitivity[p] - rel) <= 1e-10, (p, m.resonance)
                assert abs(m.param_zeta_sensitivity[p] - dz) <= 1e-10, (p, m.resonance)


@pytest.mark.parametrize("damped", [False, True])
def test_band_solver_roots_get_their_vectors_by_inverse_iteration(monkeypatch, damped):
    """Above the dense limit the band solver gives no vectors: the modes found by
    inverse iteration equal those of the dense solve."""
    import mechcirc.resonances as res

    lines = ["drive V d 0 velocity=1", "spring k0 d n1 100"]
    for i in range(1, 61):
        lines += [f"mass m{i} n{i} 0 {1 + 0.01 * i}",
                  f"spring k{i} n{i} {f'n{i + 1}' if i < 60 else '0'} {100 + i}"]
        lines += [f"damper c{i} n{i} 0 0.05"] if damped else []
    text = "\n".join(lines)
    dense = modes(mechcirc.parse(text), omega_max=5.0)
    monkeypatch.setattr(res, "MAX_UNKNOWNS_DAMPED" if damped else "MAX_UNKNOWNS", 10)
    band = modes(mechcirc.parse(text), omega_max=5.0)
    assert len(band) == len(dense) >= 4
    for a, b in zip(dense, band):
        assert b.resonance.omega == pytest.approx(a.resonance.omega, rel=1e-12)
        va, vb = (np.array(list(m.shape.values())) for m in (a, b))
        assert 1 - _mac(va, vb) <= 1e-12
        for name, x in a.sensitivity.items():
            assert b.sensitivity[name] == pytest.approx(x, abs=1e-9)
            assert b.zeta_sensitivity[name] == pytest.approx(a.zeta_sensitivity[name],
                                                             abs=1e-9)


def _run(argv, capsys):
    from mechcirc.cli import main

    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_cli_modes_and_sensitivity_json_carry_the_api_values(capsys):
    path = "docs/examples/drive.mcir"
    status, out, err = _run(["resonances", path, "--modes", "--sensitivity", "--json"], capsys)
    assert status == 0, err
    import json

    rows = json.loads(out)["resonances"]
    api = modes(mechcirc.load(path))
    assert len(rows) == len(api) == 4
    for row, m in zip(rows, api):
        assert row["omega"] == m.resonance.omega
        assert row["element_sensitivity"] == m.sensitivity
        assert row["param_sensitivity"] == m.param_sensitivity == {
            "eta1": pytest.approx(m.param_sensitivity["eta1"])}
        if m.shape:
            assert row["mode"] == {n: [v.real, v.imag] for n, v in m.shape.items()}
            assert row["energy"] == m.energy
        else:
            assert row["mode"] is None and "overdamped" in row["note"]
    # Without the flags the document is what it was.
    status, out, err = _run(["resonances", path, "--json"], capsys)
    assert set(json.loads(out)["resonances"][0]) == {"kind", "omega", "f_hz", "omega_d",
                                                     "zeta", "error"}


def test_cli_tables_and_plot(capsys, tmp_path):
    path = "netlists/stb_heald.mcir"
    image = tmp_path / "modes.png"
    status, out, err = _run(["resonances", path, "--modes", "--sensitivity", "--plot", image],
                            capsys)
    assert status == 0, err
    assert image.stat().st_size > 10_000
    assert out.count("to raise omega by 10 % (linear estimate): ") == 5
    # The first resonance is the warp (k0) on the heald frame: its advice names k0 first.
    first = out.split("\n1: resonance")[1].split("\n2: ")[0]
    assert "stiffen k0 by" in first.split("linear estimate): ")[1].split(",")[0]
    assert "energy" in first and "eta4" in first


def test_plot_mode_draws_on_the_axes_given():
    from matplotlib.figure import Figure

    from mechcirc.plotting import plot_mode

    found = modes(mechcirc.load("docs/examples/drive.mcir"))
    ax = Figure().add_subplot()
    assert plot_mode(found[0], ax=ax) is ax
    (line,) = [ln for ln in ax.lines if ln.get_label() == "Re v"]
    assert list(line.get_ydata()) == pytest.approx([v.real for v in found[0].shape.values()])
    assert isinstance(plot_mode(found[-1]), Figure)       # overdamped: the note, no curve


def test_a_repeated_root_says_its_shape_is_one_of_a_family():
    """Three identical branches on the driven node: held, their root is triple (two
    copies cancel in K); the one reported has no unique shape and says so."""
    text = "drive V a 0 velocity=1\nmass ma a 0 1\n" + "".join(
        f"spring k{i} a b{i} 100\nmass m{i} b{i} 0 1\n" for i in range(3))
    found = modes(mechcirc.parse(text))
    assert [(m.resonance.kind, round(m.resonance.omega, 9)) for m in found] == [
        ("resonance", 10.0), ("antiresonance", 20.0)]
    assert "repeated root" in found[0].note and found[1].note == ""


def test_cli_plot_of_many_modes_draws_the_lowest_and_says_so(capsys, tmp_path):
    path = tmp_path / "chain.mcir"
    # 7 masses: 14 modes, 2 beyond the 12 panels (20 masses, 40 modes, took 0.3 s more)
    lines = ["drive V d 0 velocity=1", "spring k0 d n1 100"]
    for i in range(1, 8):
        lines += [f"mass m{i} n{i} 0 1", f"spring k{i} n{i} {f'n{i + 1}' if i < 7 else '0'} 100"]
    path.write_text("\n".join(lines))
    status, _, err = _run(["resonances", path, "--plot", tmp_path / "m.png"], capsys)
    assert status == 0
    assert "draws the lowest 12 of 14 modes" in err
    status, _, err = _run(["resonances", path, "--plot", tmp_path / "no" / "m.png"], capsys)
    assert status == 2 and "does not exist" in err


UNITS = """.param k=2 N/mm r=0.5
.param m2={k/1000 + 1} g
drive V a 0 velocity=1
spring k1 a b {k} N/m
mass m1 b 0 {m2*1e3} g
lever L b 0 c 0 ratio={r*2}
spring k2 c 0 {3*k} N/mm damping={r} N*s/mm eta={1 + r}
mass m3 c 0 0.2
"""


def test_param_sensitivities_through_units_levers_and_a_spring_damping():
    """A .param in N/mm, one defined from another in g, a lever ratio, a spring's
    damping= companion and its η: against central differences of the roots with the
    parameter overridden (SI)."""
    circuit = mechcirc.parse(UNITS)
    found = modes(circuit)
    assert len(found) >= 2
    for p, value in circuit.params.items():
        rel, zeta = _fd(lambda f, p=p, v=value: mechcirc.parse(UNITS, params={p: v * f}),
                        len(found))
        for m, r, z in zip(found, rel, zeta):
            scale = max(abs(x) for x in m.sensitivity.values())
            assert abs(m.param_sensitivity[p] - r) <= 1e-6 * scale, (p, m.resonance)
            assert abs(m.param_zeta_sensitivity[p] - z) <= 1e-6 * max(
                scale * m.resonance.zeta, 1e-12), (p, m.resonance)


def test_circuit_delegates_give_the_module_functions():
    """Circuit.modes / .periodic / .speed_map are the functions of their modules."""
    from mechcirc import parse
    from mechcirc.modes import modes

    c = parse("drive V a 0 velocity=1\nmass m a b 1\nspring k b 0 100\ndamper c b 0 0.5\n")
    a, b = c.modes(), modes(c)
    assert [m.resonance for m in a] == [m.resonance for m in b]
    assert a[0].shape == b[0].shape


def test_grid_anti_resonances_of_modes_against_the_closed_form():
    """The 30×30 grid of tests/test_resonances.py: modes() takes the released roots from
    the dense eigen-solve that gives the vectors, resonances() from the banded one.
    Against the closed form ω² = (k/m)(1 + λ_i + λ_j), λ_j = 2 − 2cos(πj/n): modes()
    achieved 2.9 eps·λ_max (asserted 8, the bound eps·λ_max/λ of the relative error
    of λ with the factor 4 of its estimate, twice); resonances() 25 (its banded
    reduction; asserted 1e-14·λ_max in test_resonances.py).  The held roots (modes()
    from the secular equation, resonances() from a banded solve): one strictly between
    each two consecutive distinct closed-form anti-resonances (a missed or a doubled
    root fails), and against numpy's dense eigvalsh of the held grid built here."""
    from reference.networks import grid_text

    n, k, m = 30, 1e4, 1.0
    found = modes(mechcirc.parse(grid_text(n, k, m)))
    plain = mechcirc.parse(grid_text(n, k, m)).resonances()
    assert [x.resonance.kind for x in found] == [r.kind for r in plain]
    lam = 2 - 2 * np.cos(np.pi * np.arange(n) / n)
    w2 = np.sort((k / m) * (1 + lam[:, None] + lam[None, :]).ravel())
    w2 = w2[np.r_[True, np.diff(w2) > 1e-9 * w2[1:]]]         # distinct values
    anti = np.sort([x.resonance.omega for x in found if x.resonance.kind == "antiresonance"])
    assert anti.size == w2.size
    assert np.max(np.abs(anti ** 2 - w2)) <= 8 * np.finfo(float).eps * w2[-1]
    res = [x.resonance for x in found if x.resonance.kind == "resonance"]
    held = np.array([r.omega for r in res])
    assert held.size == w2.size - 1 and np.all(np.diff(held) > 0)
    assert np.all((w2[:-1] < held ** 2) & (held ** 2 < w2[1:]))
    lap = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    lap[0, 0] = lap[-1, -1] = 1
    K = k * (np.eye(n * n) + np.kron(lap, np.eye(n)) + np.kron(np.eye(n), lap))
    ref = np.linalg.eigvalsh(K[1:, 1:] / m)        # g0_0 (row 0) held at rest
    near = ref[np.abs(ref[:, None] - held[None, :] ** 2).argmin(axis=0)]
    # Achieved 10.2 eps·λ_max (resonances()' banded roots 13.1: the reference's own
    # rounding is in both), asserted 20; and within 0.16 of each root's reported error
    # (resonances()' 0.23), asserted 1.
    assert np.max(np.abs(near - held ** 2)) <= 20 * np.finfo(float).eps * ref[-1]
    assert np.all(np.abs(np.sqrt(near) - held) <= held * np.array([r.error for r in res]))


@pytest.mark.parametrize("frame", [True, False])
def test_held_vectors_from_the_released_ones_against_mpmath(monkeypatch, frame):
    """A network with a mass at every node and no lever: the held (resonance) vectors
    come from the released eigenvectors by the secular equation.  Against an mpmath
    eigen-solve (30 digits) of the held problem written by hand: the drive to the
    frame (node a at rest) and between two nodes (v_a = v_b)."""
    import mechcirc.resonances as res

    rng = np.random.default_rng(11)
    rows, cols = 3, 4
    nodes = [f"g{i}_{j}" for i in range(rows) for j in range(cols)]
    mass, ground = rng.uniform(0.5, 2.0, len(nodes)).tolist(), rng.uniform(1e3, 3e3, 12).tolist()
    links = [(i * cols + j, i * cols + j + dj * cols + dj2, float(rng.uniform(1e3, 3e3)))
             for i in range(rows) for j in range(cols)
             for dj, dj2 in ((1, 0), (0, 1)) if i + dj < rows and j + dj2 < cols]
    other = 0 if frame else 5
    lines = [f"drive V g0_0 {'0' if frame else nodes[other]} velocity=1"]
    lines += [f"mass m{k} {nd} 0 {mass[k]!r}\nspring f{k} {nd} 0 {ground[k]!r}"
              for k, nd in enumerate(nodes)]
    lines += [f"spring l{k} {nodes[a]} {nodes[b]} {kv!r}" for k, (a, b, kv) in enumerate(links)]
    used = []
    real = res._secular_held
    monkeypatch.setattr(res, "_secular_held", lambda *a: used.append(real(*a)) or used[-1])
    found = [m for m in modes(mechcirc.parse("\n".join(lines))) if m.resonance.kind == "resonance"]
    assert len(used) == 1 and used[0] is not None and len(found) == len(nodes) - 1
    with mpmath.workdps(30):
        K = mpmath.zeros(len(nodes))
        for k in range(len(nodes)):
            K[k, k] += ground[k]
        for a, b, kv in links:
            K[a, a] += kv
            K[b, b] += kv
            K[a, b] -= kv
            K[b, a] -= kv
        # Held: node 0 at rest (row and column out), or merged into node ``other``.
        Z = mpmath.zeros(len(nodes), len(nodes) - 1)
        for k in range(1, len(nodes)):
            Z[k, k - 1] = 1
        if not frame:
            Z[0, other - 1] = 1
        Mh = Z.T * mpmath.diag(list(mass)) * Z
        d = [1 / mpmath.sqrt(Mh[k, k]) for k in range(Mh.rows)]
        D = mpmath.diag(d)
        lam, Q = mpmath.eigsy(D * Z.T * K * Z * D)
        worst = 0.0
        for m in found:
            k = min(range(lam.rows), key=lambda k: abs(lam[k] - m.resonance.omega ** 2))
            assert abs(mpmath.sqrt(lam[k]) - m.resonance.omega) <= 1e-12 * m.resonance.omega
            want = np.array([complex(x) for x in Z * D * Q[:, k]])
            want /= want[np.argmax(np.abs(want))]
            got = np.array([m.shape[nd] for nd in nodes])
            worst = max(worst, np.abs(got - want).max())
    # Achieved 4.7e-15 (drive to the frame) and 7.1e-15 (between two nodes); the dense
    # eigen-solve of the held problem, the route before, 3.9e-15 and 4.8e-15.  Asserted 2e-14.
    assert worst <= 2e-14


@pytest.mark.parametrize("other", ["0", "g2_3"])
def test_secular_held_roots_against_mpmath(other):
    """Every root of the held problem from the secular equation (before _cancel and any
    polish) on a uniform 6×6 grid, whose repeated released roots (ω² = (k/m)(1 + λ_i +
    λ_j) = … with i ≠ j) and modes the drive does not see give held roots at released
    ones, driven to the frame and between two nodes: all 35 against a 30-digit mpmath
    eigen-solve, one by one in ascending order (a missed or a doubled root fails)."""
    import mechcirc.resonances as res
    from reference.networks import grid_text

    n, k, m = 6, 1e4, 1.0
    system = mechcirc.parse(grid_text(n, k, m).replace("g0_0 0", f"g0_0 {other}", 1)).nodal
    M, D, Ks, G_released, G_held, damped = res.pencil(system, dense=True)
    released, V = res._modes(M, D, Ks, G_released, damped, None, True)
    found = res._secular_held(V, released, G_held[-1])
    assert found is not None
    got = np.abs(found[0][:, 0]) ** 2
    with mpmath.workdps(30):
        K = mpmath.zeros(n * n)
        for i in range(n * n):
            K[i, i] += k
            for j in (i + 1, i + n):        # right and down neighbours
                if j < n * n and (j == i + n or j % n):
                    K[i, i] += k
                    K[j, j] += k
                    K[i, j] -= k
                    K[j, i] -= k
        Z = mpmath.zeros(n * n, n * n - 1)      # node g0_0 out, or merged into g2_3
        for i in range(1, n * n):
            Z[i, i - 1] = 1
        if other != "0":
            Z[0, 2 * n + 3 - 1] = 1
        # The eigenvalues of (ZᵀZ)⁻¹ZᵀKZ/m: ZᵀZ is diagonal (each column of Z holds the
        # nodes merged into one), so they are those of the symmetric S = G ZᵀKZ G / m,
        # G = (ZᵀZ)^(-1/2), by mpmath's symmetric eigen-solve (eigsy: 0.14 s of CPU
        # against 0.74-0.80 s for eig of the unsymmetric product; the same doubles).
        G = Z.T * Z
        assert all(G[i, j] == 0 for i in range(G.rows) for j in range(G.cols) if i != j)
        g = [1 / mpmath.sqrt(G[i, i]) for i in range(G.rows)]
        A = Z.T * K * Z
        S = mpmath.matrix(A.rows)
        for i in range(A.rows):
            for j in range(A.cols):
                S[i, j] = g[i] * A[i, j] * g[j] / m
        want = np.sort([float(x) for x in mpmath.eigsy(S, eigvals_only=True)])
    assert got.size == want.size == n * n - 1
    # Achieved 3.5 and 3.6 eps·λ_max (the dense eigen-solve of the held problem: 3.1
    # and 5.5); asserted 8.
    assert np.max(np.abs(got - want)) <= 8 * np.finfo(float).eps * want[-1]


def test_secular_route_falls_back_to_the_held_eigen_solve(monkeypatch):
    """Where dlasd4 does not converge (info ≠ 0) the held problem is solved densely, as for
    every other network: the same resonances within their errors, with their shapes."""
    import scipy.linalg.lapack as lapack

    import mechcirc.resonances as res
    from reference.networks import grid_text

    text = grid_text(6).replace("g0_0 0", "g0_0 g2_3", 1)
    want = [m for m in modes(mechcirc.parse(text)) if m.resonance.kind == "resonance"]
    real, secular, used = lapack.dlasd4, res._secular_held, []
    monkeypatch.setattr(lapack, "dlasd4", lambda *a, **k: (*real(*a, **k)[:3], 1))
    monkeypatch.setattr(res, "_secular_held", lambda *a: used.append(secular(*a)) or used[-1])
    got = [m for m in modes(mechcirc.parse(text)) if m.resonance.kind == "resonance"]
    assert used == [None] and len(got) == len(want) > 0
    for g, w in zip(got, want):
        assert abs(g.resonance.omega - w.resonance.omega) <= \
            (g.resonance.error + w.resonance.error) * w.resonance.omega
        assert g.shape.keys() == w.shape.keys()
