"""Sweep sensitivities (mechcirc.modes.sweep_sensitivity, sweep --sensitivity) against
independent references: central finite differences of the sweep itself and
40-digit mpmath derivatives of a closed-form K."""

import csv
import dataclasses
import json

import mpmath
import numpy as np
import pytest
from cli_helpers import assert_user_error, run

import mechcirc
from mechcirc.modes import sweep_sensitivity

H = 1e-5


def _rebuilt(circuit, name, factor):
    """``circuit`` with the value (or lever ratio) of ``name`` multiplied by ``factor``."""
    els = tuple(dataclasses.replace(e, value=e.value * factor) if e.name == name else e
                for e in circuit.elements)
    levers = tuple(dataclasses.replace(lv, ratio=lv.ratio * factor) if lv.name == name else lv
                   for lv in circuit.levers)
    return dataclasses.replace(circuit, elements=els, levers=levers)


@pytest.mark.parametrize("path", ["docs/examples/drive.mcir", "netlists/stb_heald.mcir",
                                  "docs/examples/lever.mcir", "netlists/heald_damped.mcir"])
def test_against_central_differences(path):
    """(p/|q|)∂|q|/∂p and (p/|K|)∂|K|/∂p of every element, lever and .param against
    central differences of ln|q| in ln p (step 1e-5: truncation ~1e-10, rounding
    ~1e-11 of |q|), within 1e-6 of the largest sensitivity at that ω."""
    circuit = mechcirc.load(path)
    omega = np.geomspace(20, 4000, 23)
    s = sweep_sensitivity(circuit, omega)
    names = [e.name for e in circuit.elements] + [lv.name for lv in circuit.levers] + \
        list(circuit.params)
    assert list(s.dK) == names
    q = s.quantity
    rel = {n: s.relative(n) for n in names}
    scale = np.max(np.abs([rel[n] for n in names] + [s.relative(n, "K") for n in names]),
                   axis=0)
    step = np.log1p(H) - np.log1p(-H)
    for name in names:
        if name in circuit.params:
            v = circuit.params[name]
            up = mechcirc.load(path, params={name: v * (1 + H)})
            down = mechcirc.load(path, params={name: v * (1 - H)})
        else:
            up, down = _rebuilt(circuit, name, 1 + H), _rebuilt(circuit, name, 1 - H)
        su, sd = up.sweep(omega), down.sweep(omega)
        for quantity in {q, "K"}:
            fd = (np.log(np.abs(getattr(su, quantity))) -
                  np.log(np.abs(getattr(sd, quantity)))) / step
            got = s.relative(name, quantity)
            assert np.all(np.abs(got - fd) <= 1e-6 * scale), (name, quantity)
        # The absolute derivative is the relative one times |q|/p.
        mag = np.abs(getattr(circuit.sweep(omega), q))
        np.testing.assert_allclose(s.derivative(name) * s.value[name], rel[name] * mag,
                                   rtol=1e-12, atol=0)


LEVER = """.param r0=0.5 kk=800
drive  V  a 0 velocity=0.1
mass   m1 a 0 2
lever  L  a 0 b 0 ratio=r0
spring k  b c {kk}
mass   m2 c 0 1.5
damper c2 c 0 3 eta={2*r0}
"""


def _mp_Q0(p, w):
    """|Q0| = V0/|K| of LEVER in closed form: 1/K = jωm1 + r²/K_s,
    K_s = jω/k + 1/(jωm2 + c2·η)."""
    jw = mpmath.mpc(0, w)
    Ks = jw / p["k"] + 1 / (jw * p["m2"] + p["c2"] * p["eta"])
    return abs(mpmath.mpf("0.1") * (jw * p["m1"] + p["r"] ** 2 / Ks))


def test_against_mpmath_40_digits():
    """A lever, a damper whose η and the lever's ratio share a .param, and a .param
    spring: every relative sensitivity of |Q0| and |K| against 40-digit derivatives
    of the closed form (mpmath.diff), within 1e-10 absolute."""
    circuit = mechcirc.parse(LEVER)
    omega = [3.0, 17.0, 25.0, 40.0, 250.0]
    s = sweep_sensitivity(circuit, omega)
    with mpmath.workdps(40):
        base = {"m1": mpmath.mpf(2), "r": mpmath.mpf("0.5"), "k": mpmath.mpf(800),
                "m2": mpmath.mpf("1.5"), "c2": mpmath.mpf(3), "eta": mpmath.mpf(1)}
        # name -> how the closed form's inputs depend on x = p / p0
        moves = {"m1": lambda x: {"m1": 2 * x}, "k": lambda x: {"k": 800 * x},
                 "kk": lambda x: {"k": 800 * x}, "m2": lambda x: {"m2": mpmath.mpf("1.5") * x},
                 "c2": lambda x: {"c2": 3 * x}, "L": lambda x: {"r": x / 2},
                 "r0": lambda x: {"r": x / 2, "eta": x}}
        for k, w in enumerate(omega):
            for name, move in moves.items():
                def lnQ(x, move=move, w=w):
                    return mpmath.log(_mp_Q0(base | move(x), w))

                ref = float(mpmath.diff(lnQ, 1))      # d ln|Q0| / d ln p at p0
                assert abs(s.relative(name)[k] - ref) <= 1e-10, (name, w)
                assert abs(s.relative(name, "K")[k] + ref) <= 1e-10, (name, w)


def test_force_drive_and_unloaded_names():
    """Under a force drive Q0 is prescribed (0) and v0 = F0·K moves as K; an element
    that carries no force has 0."""
    c = mechcirc.parse("drive F a 0 force=2\nmass m a 0 1\nspring k a 0 100\n"
                       "mass x b 0 1\nspring y b 0 5\n")
    s = sweep_sensitivity(c, [5.0, 20.0])
    assert s.quantity == "v0"
    assert np.all(s.relative("m", "Q0") == 0)
    np.testing.assert_array_equal(s.relative("m"), s.relative("m", "K"))
    # |K| = 1/|k/ω − mω|: (m/|K|)∂|K|/∂m = mω/(k/ω − mω)·sign → closed form.
    w = np.array([5.0, 20.0])
    ref = 1 * w / (100 / w - 1 * w)
    np.testing.assert_allclose(s.relative("m"), ref, rtol=1e-13)
    assert np.all(s.dK["x"] == 0)
    with pytest.raises(mechcirc.MechcircError, match="there are: m, k, x, y"):
        sweep_sensitivity(c, [1.0], ["z"])


def test_chunks_of_omega_give_the_same_values():
    """Long sweeps are solved in chunks of ω (memory): the values across a chunk's
    boundary are those of the points solved alone."""
    c = mechcirc.load("netlists/heald_damped.mcir")
    w = np.linspace(10, 3000, 70_000)
    s = sweep_sensitivity(c, w, ["k4", "eta1"])
    pick = np.r_[0:3, 32_760:32_780, 65_530:65_540, 69_997:70_000]   # chunks of 32,768
    alone = sweep_sensitivity(c, w[pick], ["k4", "eta1"])
    for name in ("k4", "eta1"):
        np.testing.assert_array_equal(s.dK[name][pick], alone.dK[name])


def test_cli_columns_json_and_summary(capsys, tmp_path):
    path = "netlists/heald_damped.mcir"
    out_csv = tmp_path / "s.csv"
    argv = ["sweep", path, "--omega-min", "50", "--omega-max", "3000", "--points", "30",
            "--sensitivity", "k4", "--sensitivity", "eta1"]
    status, out, err = run(argv + ["-o", out_csv], capsys)
    assert status == 0, err
    assert "(p/|Q0|) d|Q0|/dp" in out and "k4" in out and "eta1" in out
    rows = list(csv.DictReader(out_csv.open()))
    s = sweep_sensitivity(mechcirc.load(path), np.linspace(50, 3000, 30), ["k4", "eta1"])
    for name in ("k4", "eta1"):
        np.testing.assert_array_equal([float(r[f"dQ0_d{name}"]) for r in rows],
                                      s.derivative(name))
        np.testing.assert_array_equal([float(r[f"relQ0_{name}"]) for r in rows],
                                      s.relative(name))
    status, out, _ = run(argv + ["--json"], capsys)
    doc = json.loads(out)
    assert doc["sensitivity"]["k4"]["value"] == s.value["k4"]
    np.testing.assert_array_equal(doc["sensitivity"]["eta1"]["relative"], s.relative("eta1"))
    assert_user_error(["sweep", path, "--omega-min", "1", "--omega-max", "2",
                       "--sensitivity", "k9"], capsys, "'k9'", "there are:", "k4", "eta1")
    assert_user_error(["sweep", path, "--omega-min", "1", "--omega-max", "2", "--points",
                       "100001", "--sensitivity", "k4"], capsys, "--sensitivity",
                      "100000 points")
