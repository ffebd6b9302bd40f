"""``mechcirc forces`` (how the force splits) and ``mechcirc check --explain``."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from mechcirc.circuit import element_mobility
from mechcirc.explain import explain
from mechcirc.forces import element_forces
from reference.stb_eq7 import full_K
from mechcirc.errors import InputError
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]
STB_PARAMS = {"m1": 2.0, "m2": 1.5, "m3": 1.2, "m4": 0.9, "m5": 0.8, "m6": 0.6, "m7": 0.5,
              "m8": 0.7, "m9": 0.4, "m10": 0.3, "m11": 0.5, "m12": 3.0, "k0": 4.0e4,
              "k4": 2.0e6, "k5": 1.5e6, "eta1": 0.8, "eta2": 1.25, "eta3": 0.9, "eta4": 1.0}


def run(argv, capsys):
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def test_series_mass_spring_by_hand():
    m, k, V0, w = 2.0, 800.0, 0.1, 10.0
    c = mechcirc.parse(f"mass m a b {m}\nspring k b 0 {k}\ndrive V a 0 velocity={V0}\n")
    rows, K, Q0, flag = element_forces(c, w)
    Q = V0 / (-1j / (w * m) + 1j * w / k)       # 0.1 / (-0.05j + 0.0125j)
    assert Q0 == pytest.approx(Q, rel=1e-14) and flag == 0
    byname = {r.name: r for r in rows}
    assert byname["m"].Q == pytest.approx(Q, rel=1e-14)
    assert byname["m"].v == pytest.approx(Q * -1j / (w * m), rel=1e-14)
    assert byname["k"].v == pytest.approx(Q * 1j * w / k, rel=1e-14)
    assert byname["m"].Q_phase_deg == pytest.approx(90.0)        # Q = +2.67j
    assert byname["m"].share == pytest.approx(1.0)


@pytest.mark.parametrize("omega", [50.0, 300.0, 800.0, 2000.0])
def test_stb_forces_obey_kirchhoff_and_eq7(omega):
    rows, K, Q0, _ = element_forces(mechcirc.load(STB), omega)
    Q = {r.name: r.Q for r in rows}
    v = {r.name: r.v for r in rows}
    # The drive's force is V0 / K with K from eq. (7), written without mechcirc.
    assert Q0 == pytest.approx(0.1 / full_K(omega, STB_PARAMS), rel=1e-10)
    # Node D: what comes in through m4 leaves through k4, m5 and m6.
    assert Q["k4"] + Q["m5"] + Q["m6"] == pytest.approx(Q["m4"], rel=1e-12)
    # Loop D-E-0: v(k4) = v(m5) + v(k5); loop D-F-...-M-0 likewise.
    assert v["m5"] + v["k5"] == pytest.approx(v["k4"], rel=1e-10)
    chain = ["m6", "m7", "m8", "m9", "m10", "m11", "m12", "k0"]
    assert sum(v[n] for n in chain) == pytest.approx(v["k4"], rel=1e-10)
    for r in rows:        # each element's own law Q = v / K
        e = mechcirc.load(STB).element(r.name)
        K_e = element_mobility(e.kind, e.value * e.eta, np.array([omega]))[0]
        assert r.Q == pytest.approx(r.v / K_e, rel=1e-12)


def test_forces_cli_text_json_and_plot(tmp_path, capsys):
    status, out, err = run(["forces", STB, "--omega", "50Hz", "--plot", tmp_path / "f.svg"],
                           capsys)
    assert status == 0, err
    assert "omega = 314.159 rad/s (50 Hz)" in out
    assert re.search(r"^  m1 +mass +7\.4516 +90\.00 +1\.0000", out, re.M)
    assert "-0.00" not in out
    assert (tmp_path / "f.svg").read_text().lstrip().startswith("<?xml")
    status, out, _ = run(["forces", STB, "--omega", 300, "--json"], capsys)
    doc = json.loads(out)
    assert status == 0 and len(doc["elements"]) == 15
    k4 = next(e for e in doc["elements"] if e["name"] == "k4")
    assert k4["Q_abs"] == pytest.approx(math.hypot(k4["Q"]["re"], k4["Q"]["im"]))


def test_forces_bad_omega_is_a_usage_error(capsys):
    status, _, err = run(["forces", STB, "--omega", "fast"], capsys)
    assert status == 2 and "not a frequency" in err


def _evaluate_steps(circuit, steps, omega):
    """K at ``omega`` computed only from the written-out steps (an independent reading)."""
    val = {e.name: complex(element_mobility(e.kind, e.value * e.eta, np.array([omega]))[0])
           for e in circuit.elements}
    for s in steps:
        if s.kind == "series":
            val[s.label] = sum(val[o] for o in s.operands)
        elif s.kind == "parallel":
            val[s.label] = 1 / sum(1 / val[o] for o in s.operands)
        else:
            r2 = float(re.search(r"/ r² = K\(\w+\) / ([0-9.e+-]+)", s.reason).group(1))
            val[s.label] = val[s.operands[0]] / r2
    return val


def test_explain_stb_steps():
    c = mechcirc.load(STB)
    steps, root = explain(c)
    assert [s.text for s in steps] == [
        "m5 + k5", "m6 + m7 + m8 + m9 + m10 + m11 + m12 + k0", "k4 | S1 | S2",
        "m1 + m2 + m3 + m4 + P1"]
    assert root == "S3"
    for omega in (100.0, 700.0, 3000.0):
        got = _evaluate_steps(c, steps, omega)[root]
        assert got == pytest.approx(full_K(omega, STB_PARAMS), rel=1e-12)


def test_explain_writes_the_lever_reflection_out():
    c = mechcirc.parse("mass m a 0 2\nlever L a 0 b 0 ratio=0.5\nspring k b c 800\n"
                       "mass m2 c 0 1\ndrive V a 0 force=1\n")
    steps, root = explain(c)
    lever = next(s for s in steps if s.kind == "lever")
    assert "r = 0.5: K = K(S1) / r² = K(S1) / 0.25" in lever.reason
    assert "m·r² = 0.25·m" in lever.reason
    for omega in (5.0, 50.0):
        got = _evaluate_steps(c, steps, omega)[root]
        assert got == pytest.approx(complex(c.sweep([omega]).K[0]), rel=1e-12)


def test_check_explain_cli(capsys):
    status, out, err = run(["check", STB, "--explain"], capsys)
    assert status == 0, err
    assert "step 3: P1 = k4 | S1 | S2" in out
    assert "1.5 kg · η 0.64 = 0.96 kg" in out
    assert out.rstrip().endswith("K = S3")
    status, out, _ = run(["check", STB, "--explain", "--json"], capsys)
    doc = json.loads(out)
    assert doc["root"] == "S3" and doc["steps"][0]["operands"] == ["m5", "k5"]


def test_check_explain_bridge_is_a_user_error(capsys):
    bridge = ("spring k1 a b 1\nspring k2 a c 2\nspring k3 b c 3\nspring k4 b 0 4\n"
              "spring k5 c 0 5\nmass m a 0 1\ndrive V a 0 velocity=1\n")
    import tempfile

    with tempfile.NamedTemporaryFile("w", suffix=".mcir", delete=False) as fh:
        fh.write(bridge)
    status, _, err = run(["check", fh.name, "--explain"], capsys)
    Path(fh.name).unlink()
    assert status == 2 and "series–parallel" in err


ROOT = Path(__file__).resolve().parents[1]


def test_forces_api_refuses_bad_omega_with_input_error():
    import mechcirc
    from mechcirc.forces import element_forces

    c = mechcirc.load(STB)
    for w in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(InputError):
            element_forces(c, w)
