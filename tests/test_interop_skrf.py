"""scikit-rf networks and Touchstone files: round trips, two-ports, comparisons."""

import math
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from mechcirc.errors import MechcircError, TopologyError
from mechcirc.interop.skrf import reference_mobility, two_port_z, write_touchstone
from reference.stb_eq7 import full_K
from reference.inputs import STB

skrf = pytest.importorskip("skrf")

REPO = Path(__file__).resolve().parents[1]
STB_PARAMS = {"m1": 2.0, "m2": 1.5, "m3": 1.2, "m4": 0.9, "m5": 0.8, "m6": 0.6, "m7": 0.5,
              "m8": 0.7, "m9": 0.4, "m10": 0.3, "m11": 0.5, "m12": 3.0, "k0": 4.0e4,
              "k4": 2.0e6, "k5": 1.5e6, "eta1": 0.8, "eta2": 1.25, "eta3": 0.9, "eta4": 1.0}
PNG = b"\x89PNG\r\n\x1a\n"


def run(argv, capsys):
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def test_to_skrf_carries_K_and_says_it_is_not_ohms():
    omega = np.geomspace(10, 1e4, 300)
    result = mechcirc.load(STB).sweep(omega)
    net = result.to_skrf()
    assert net.nports == 1
    np.testing.assert_allclose(net.f, omega / (2 * math.pi), rtol=1e-15)
    err = np.abs(net.z[:, 0, 0] - result.K) / np.abs(result.K)
    assert err.max() < 1e-12
    # and against eq. (7) written independently (away from its poles and zeros)
    ref = full_K(omega, STB_PARAMS)
    ok = result.flags == 0
    assert np.max(np.abs(net.z[ok, 0, 0] - ref[ok]) / np.abs(ref[ok])) < 1e-9
    assert "m/(N*s)" in net.name and "NOT ohms" in net.comments
    R = float(net.z0[0, 0].real)
    assert R == 2.0 ** round(math.log2(R))          # a power of two


def test_sweep_touchstone_round_trip(tmp_path, capsys):
    path = tmp_path / "stb.s1p"
    status, out, err = run(["sweep", STB, "--omega-min", 0, "--omega-max", 1e4,
                            "--points", 201, "--touchstone", path], capsys)
    assert status == 0, err
    assert f"Touchstone written to {path}" in out
    assert "1 point(s) with omega = 0" in out        # ω = 0: K infinite, left out
    omega = np.linspace(0, 1e4, 201)[1:]
    K = mechcirc.load(STB).sweep(omega).K
    text = path.read_text().splitlines()
    option = next(line for line in text if line.startswith("#"))
    assert option.split()[:4] == ["#", "Hz", "Z", "RI"]
    R = float(option.split()[5])
    rows = np.array([line.split() for line in text if line[0] not in "!#"], dtype=float)
    # The file holds K/R exactly (R a power of two): back to K bit for bit.
    np.testing.assert_array_equal(rows[:, 1] * R + 1j * rows[:, 2] * R, K)
    np.testing.assert_array_equal(rows[:, 0], omega / (2 * math.pi))
    net = skrf.Network(str(path))
    assert net.nports == 1 and len(net.f) == 200
    assert np.max(np.abs(net.z[:, 0, 0] - K) / np.abs(K)) < 1e-12


def test_a_rotary_sweep_says_its_unit_in_the_file_and_the_network(tmp_path, capsys):
    """New-user pass, session 28: the Touchstone header of a rotary netlist said
    m/(N*s); K is in rad/(N·m·s) there (the sweep's own summary says so)."""
    src = tmp_path / "rotor.mcir"
    src.write_text("drive W p 0 velocity=2 rad/s\nspring kt p a 5000 N*m/rad\n"
                   "mass J a 0 0.05 kg*m^2\ndamper ct a 0 0.5 N*m*s/rad\n")
    out = tmp_path / "rot.s1p"
    status, _, err = run(["sweep", src, "--omega-min", 1, "--omega-max", 1000, "--points", 20,
                          "--touchstone", out], capsys)
    assert status == 0, err
    head = out.read_text().splitlines()[1:3]
    assert all("rad/(N*m*s)" in line and "m/(N*s)" not in line for line in head), head
    net = mechcirc.load(src).sweep(np.geomspace(1, 1e3, 20)).to_skrf()
    assert "rad/(N*m*s)" in net.name and "K = v/Q in rad/(N*m*s)" in net.comments


def test_reference_mobility_is_a_power_of_two_near_the_data():
    assert reference_mobility([1e-3, 1e-5]) == 2.0 ** round(math.log2(1e-4))
    assert reference_mobility([np.inf, 0.0]) == 1.0


def test_write_touchstone_refuses_all_singular(tmp_path):
    with pytest.raises(MechcircError, match="nothing to write"):
        write_touchstone(tmp_path / "x.s1p", [0.0], [np.inf])


def _lever_circuit(m=2.0, r=0.5, k=800.0):
    return mechcirc.parse(f"mass m a 0 {m}\nlever L a 0 b 0 ratio={r}\nspring k b 0 {k}\n"
                          "drive F a 0 force=1\n")


def test_two_port_of_a_lever_matches_the_hand_formula():
    # Primary: mass m to frame; secondary: spring k to frame; v_S = r v_P, Q_P = r Q_S.
    # Z11 = 1/(jωm + k r²/(jω)), Z21 = v_S/Q_P = r Z11,
    # Z22 = 1/(jωm/r² + k/(jω)), Z12 = Z22/r (= Z21: reciprocity).
    m, r, k = 2.0, 0.5, 800.0
    omega = np.array([3.0, 30.0, 300.0])
    Z = two_port_z(_lever_circuit(m, r, k), "a", "0", "b", "0", omega)
    jw = 1j * omega
    Z11 = 1 / (jw * m + k * r**2 / jw)
    Z22 = 1 / (jw * m / r**2 + k / jw)
    np.testing.assert_allclose(Z[:, 0, 0], Z11, rtol=1e-12)
    np.testing.assert_allclose(Z[:, 1, 0], r * Z11, rtol=1e-12)
    np.testing.assert_allclose(Z[:, 1, 1], Z22, rtol=1e-12)
    np.testing.assert_allclose(Z[:, 0, 1], Z22 / r, rtol=1e-12)
    net = _lever_circuit(m, r, k).two_port("a", "0", "b", "0", omega)
    assert net.nports == 2
    np.testing.assert_allclose(net.z, Z, rtol=1e-12)


def test_two_port_Z11_is_the_drive_mobility_of_a_damped_chain():
    text = ("mass m1 a 0 1\nspring k1 a b 1e4\ndamper c1 b 0 20\nmass m2 b 0 0.5\n"
            "spring k2 b c 5e3\nmass m3 c 0 0.2\ndrive F a 0 force=1\n")
    c = mechcirc.parse(text)
    omega = np.geomspace(1, 1e3, 50)
    Z = two_port_z(c, "a", "0", "c", "0", omega)
    np.testing.assert_allclose(Z[:, 0, 0], c.sweep(omega).K, rtol=1e-11)
    np.testing.assert_allclose(Z[:, 0, 1], Z[:, 1, 0], rtol=1e-11)   # reciprocity


def test_two_port_two_ports_written_and_read_back(tmp_path):
    omega = np.array([30.0, 300.0])
    Z = two_port_z(_lever_circuit(), "a", "0", "b", "0", omega)
    path = tmp_path / "lever.s2p"
    write_touchstone(path, omega, Z, name="lever")
    net = skrf.Network(str(path))
    np.testing.assert_allclose(net.z, Z, rtol=1e-12)


def test_two_port_bad_port_names_the_node():
    with pytest.raises(TopologyError, match="'x' is not a node"):
        two_port_z(_lever_circuit(), "a", "0", "x", "0", [1.0])


def test_compare_reports_a_known_error(tmp_path, capsys):
    # A "measurement": the eq. (7) mobility 1 % too large, written by scikit-rf
    # itself as S parameters on a 50 reference, so the reader is not ours.
    omega = np.geomspace(10, 600, 80)        # below the first resonance
    K = full_K(omega, STB_PARAMS) * 1.01
    freq = skrf.Frequency.from_f(omega / (2 * math.pi), unit="hz")
    skrf.Network.from_z(K.reshape(-1, 1, 1), frequency=freq, z0=50).write_touchstone(
        str(tmp_path / "meas"))
    measured = tmp_path / "meas.s1p"
    from mechcirc.interop.skrf import compare

    cmp = compare(mechcirc.load(STB), measured)
    summary = cmp.summary()
    assert summary["compared"] == 80
    assert summary["rel_max"] == pytest.approx(0.01, rel=1e-6)
    assert summary["db_rms"] == pytest.approx(20 * math.log10(1.01), rel=1e-6)
    assert summary["phase_max_deg"] < 1e-6
    status, out, err = run(["compare", STB, measured, "--plot", tmp_path / "c.png"], capsys)
    assert status == 0, err
    assert "max 0.01 " in out and "median 0.01" in out
    assert (tmp_path / "c.png").read_bytes()[:8] == PNG
    status, out, err = run(["compare", STB, measured, "--omega-min", 100, "--omega-max",
                            "50Hz", "--json"], capsys)
    doc = __import__("json").loads(out)
    assert status == 0 and doc["omega_min"] >= 100 and doc["omega_max"] <= 100 * math.pi
    assert 0 < doc["points"] < 80
    status, _, err = run(["compare", STB, measured, "--omega-min", "1000Hz"], capsys)
    assert status == 2 and "no measured point" in err


def test_compare_says_a_measured_zero_is_not_compared_for_itself(tmp_path, capsys):
    # a measured K of 0 at 62.8 rad/s, where the model's K is -0.068j (its first resonance
    # at 706 rad/s): it was blamed on "a pole or zero of the model's K"
    (tmp_path / "z.s1p").write_text("# Hz Z RI R 1\n10 0 0\n20 0 -0.01\n30 0 -0.01\n")
    status, out, err = run(["compare", STB, tmp_path / "z.s1p"], capsys)
    assert status == 0, err
    assert "1 point(s) not compared: on or near a pole or zero of the model's K, or a " \
        "measured K of 0" in out


def test_compare_missing_or_bad_file_is_a_user_error(tmp_path, capsys):
    status, _, err = run(["compare", STB, tmp_path / "none.s1p"], capsys)
    assert status == 2 and "no such file" in err
    bad = tmp_path / "bad.s1p"
    bad.write_text("this is not touchstone\n")
    status, _, err = run(["compare", STB, bad], capsys)
    assert status == 2 and "bad.s1p" in err


def test_import_mechcirc_stays_light(light_imports):
    # import mechcirc, mechcirc.netlist, mechcirc.units and build the parser
    # (one process with the other light-import checks: tests/conftest.py, light_imports)
    heavy = ("skrf", "sympy", "pint", "dask", "distributed", "matplotlib", "pandas")
    assert [m for m in light_imports["build_parser"] if m.split(".")[0] in heavy] == []
