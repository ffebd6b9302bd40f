"""A new user's pass over the command line (audit18): every frequency shown in --unit."""

import math

import pytest
from cli_helpers import run
from reference.inputs import STB



@pytest.mark.parametrize("unit, head", [
    ("rad/s", f"omega = 300 rad/s ({300 / (2 * math.pi):.6g} Hz)"),
    ("Hz", f"f = {300 / (2 * math.pi):.6g} Hz"),
    ("rpm", f"n = {300 * 60 / (2 * math.pi):.6g} rpm"),
])
def test_forces_shows_its_frequency_in_unit(unit, head, capsys):
    status, out, err = run(["forces", STB, "--omega", "300", "--unit", unit], capsys)
    assert status == 0, err                    # main: unrecognized arguments: --unit
    assert out.splitlines()[0].startswith(f"{STB}: {head}, K = "), out


def test_fourbar_dead_centres_label_nu(capsys):
    status, out, err = run(["fourbar", "--crank", "29", "--coupler", "37", "--rocker", "188",
                            "--frame", "189"], capsys)
    assert status == 0, err
    centres = [ln for ln in out.splitlines() if "dead centre" in ln]
    assert len(centres) == 2
    assert all(ln.endswith(" 1/rad") for ln in centres), centres    # main: 'ν = +0.278765'


def test_ic_on_an_unknown_node_says_did_you_mean(tmp_path, capsys):
    net = tmp_path / "ic.mcir"
    net.write_text("mass m1 phi 0 1 kg*m^2\nspring k1 phi 0 1000 N*m/rad\n.ic phii x=5 deg\n")
    status, _, err = run(["transient", net, "--t-end", "0.01"], capsys)
    assert status == 2
    assert "ic.mcir:3:5: error: .ic names node 'phii', which no element uses; did you mean " \
           "'phi'?" in err                                   # main: no 'did you mean'
