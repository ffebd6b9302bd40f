"""Small defects found by a new user's pass (each test failed before its fix).

* ``cam --json`` of an oscillating flat face that turns back: marked, no profile.
* the scene resonance JSON has ``omega_d`` (and ``error``) as the circuit JSON has.
* ``mechcirc.sley.linear``'s AttributeError names that module, the package its own name.
* the Python copy of the series–parallel kernel gives what the compiled one gives
  (no ZeroDivisionError where a node's |sum| is 0 in float64).
"""

import importlib
import importlib.util
import json
import math
import sys
import warnings

import numpy as np
import pytest
from cli_helpers import run

import mechcirc.sley.linear
from reference.sp_corpus import random_tree, to_circuit

TURNS_BACK = ["cam", "--law", "cycloidal", "--rise", "60", "--dwell", "120", "--return", "60",
              "--stroke", "50", "--base-radius", "40", "--follower", "oscillating_flat",
              "--pivot", "100"]


def test_cam_json_marks_a_face_that_turns_back_and_gives_no_profile(capsys):
    """A 50° swing returned in 60° turns back at 180° + 60°·acos(1 − 60/50)/(2π)
    (the cycloidal return written out): the JSON says so and lists no profile
    (it listed points 330 base radii out)."""
    status, out, _ = run(TURNS_BACK + ["--json"], capsys)
    doc = json.loads(out)
    assert status == 0 and doc["turned_back"] is True and doc["profile"] is None
    theta = 180.0 + 60.0 * math.acos(1.0 - 60.0 / 50.0) / (2 * math.pi)
    assert doc["checks"]["undercut"]["theta_deg"] == pytest.approx(theta, abs=1e-9)
    # a cam that exists still lists its profile, all of it within its largest radius
    ok = TURNS_BACK[:TURNS_BACK.index("--stroke")] + ["--stroke", "10", "--base-radius", "40",
                                                      "--follower", "oscillating_flat",
                                                      "--pivot", "100"]
    ok[ok.index("--return") + 1] = "120"
    ok[ok.index("--dwell") + 1] = "60"
    status, out, _ = run(ok + ["--json"], capsys)
    doc = json.loads(out)
    assert status == 0 and doc["turned_back"] is False
    r = np.hypot(doc["profile"]["x"], doc["profile"]["y"])
    assert len(r) > 100 and r.max() < 100.0      # inside the pivot circle D = 100 mm


RESONANCE_KEYS = {"kind", "omega", "f_hz", "omega_d", "zeta", "error"}


def _check_rows(rows):
    assert rows
    for r in rows:
        assert set(r) == RESONANCE_KEYS
        # s = −ζωₙ + jω_d with |s| = ωₙ: ω_d = ωₙ√(1 − ζ²) for an underdamped root
        if r["zeta"] < 1:
            assert r["omega_d"] == pytest.approx(r["omega"] * math.sqrt(1 - r["zeta"] ** 2),
                                                 rel=1e-12)
        assert r["f_hz"] == pytest.approx(r["omega"] / (2 * math.pi), rel=1e-15)


def test_scene_resonance_json_has_the_circuit_json_fields(capsys):
    status, out, _ = run(["resonances", "netlists/heald_damped.mcir", "--json"], capsys)
    assert status == 0
    circuit_rows = json.loads(out)["resonances"]
    assert set(circuit_rows[0]) == RESONANCE_KEYS
    status, out, _ = run(["scene", "examples/heald_scene.toml", "--theta", "40", "--json"],
                         capsys)
    assert status == 0
    _check_rows(json.loads(out)["resonances"])
    status, out, _ = run(["scene", "examples/heald_scene.toml", "--cycle", "--points", "2",
                          "--harmonics", "1", "--json"], capsys)
    assert status == 0
    point = json.loads(out)["points"][0]
    _check_rows(point["resonances"])
    _check_rows(point["antiresonances"])


def test_sley_attribute_errors_name_the_module_looked_in():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(AttributeError, match=r"^module 'mechcirc\.sley\.linear' has no "
                                                 r"attribute 'Modes'$"):
            mechcirc.sley.linear.Modes              # noqa: B018
        with pytest.raises(AttributeError, match=r"^module 'mechcirc\.sley' has no "
                                                 r"attribute 'Modes'$"):
            mechcirc.sley.Modes                     # noqa: B018


def _python_copy():
    """A fresh copy of mechcirc._sp_kernel loaded as if numba were not installed."""
    saved = sys.modules.get("numba")
    sys.modules["numba"] = None                      # makes `import numba` fail
    try:
        spec = importlib.util.find_spec("mechcirc._sp_kernel")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        if saved is None:
            del sys.modules["numba"]
        else:
            sys.modules["numba"] = saved
    assert not module.HAVE_NUMBA
    return module


def test_python_copy_of_the_sp_kernel_is_the_compiled_kernel():
    """Bit for bit, K and its error bound, on random trees (half with values powers of 2, so
    sums cancel exactly) at ω = 0, ∞, the roots of those sums and magnitudes where
    √(a² + b²) underflows: the Python copy raised ZeroDivisionError at 1/|S| = 1/0."""
    pytest.importorskip("numba")
    from mechcirc import _sp_kernel, _tree_eval

    py = _python_copy()
    rng = np.random.default_rng(1)
    omega = np.array([[0.0, 5e-324, 1e-300, 0.5, 1.0, 2.0, 4.0, 1e300, np.inf]])

    def powers_of_two(e):
        if e[0] == "leaf":
            return ("leaf", e[1], float(2.0 ** int(rng.integers(-2, 3))))
        if e[0] == "lever":
            return ("lever", float(2.0 ** int(rng.integers(-1, 2))), powers_of_two(e[2]))
        return (e[0], [powers_of_two(c) for c in e[1]])

    for t in range(120):
        e = random_tree(rng, int(rng.integers(1, 9)), damped=0.15)
        p = _tree_eval.plan(to_circuit(powers_of_two(e) if t % 2 else e).tree)
        for error in (False, True):
            with np.errstate(all="ignore"):
                K, rho = _tree_eval.evaluate_designs(p, omega, error, _sp_kernel.evaluate_plan)
                K_py, rho_py = _tree_eval.evaluate_designs(p, omega, error, py.evaluate_plan)
            assert np.array_equal(K.view(float), K_py.view(float), equal_nan=True)
            assert (rho is None) == (rho_py is None)
            if error:
                assert np.array_equal(rho, rho_py, equal_nan=True)
