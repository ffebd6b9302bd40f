"""The user-facing surface of issue 17 §2: results that show what was asked."""

import json
import math
from pathlib import Path

import pytest

from mechcirc.cli import main
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]


def test_version(capsys):
    import mechcirc

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"mechcirc {mechcirc.__version__}"


def test_force_driven_sweep_prints_the_velocity_response(tmp_path, capsys):
    p = tmp_path / "f.mcir"
    p.write_text("mass m a 0 2\nspring k a 0 800\ndamper c a 0 4\ndrive F a 0 force=3\n")
    assert main(["sweep", str(p), "--omega-min", "20", "--omega-max", "20.0001",
                 "--points", "2"]) == 0
    out = capsys.readouterr().out
    assert "|Q0|" not in out and "|v0|" in out and "velocity response" in out
    # at ω = 20 rad/s = √(k/m) the parallel m, k cancel: v0 = F0/c = 0.75 m/s
    v = float(out.split("|v0|")[1].split("..")[0])
    assert v == pytest.approx(0.75, rel=1e-3)


def test_touchstone_refuses_a_two_port_name(tmp_path, capsys):
    path = tmp_path / "K.s2p"
    assert main(["sweep", str(STB), "--omega-min", "10", "--omega-max", "100",
                 "--touchstone", str(path)]) == 2
    assert ".s1p" in capsys.readouterr().err and not path.exists()


def test_reduce_output_is_a_file_and_element_names_the_element(tmp_path, capsys):
    out = tmp_path / "r.mcir"
    assert main(["reduce", str(STB), "--band", "10:2000", "--tol", "0.01", "--output",
                 str(out), "--points", "200"]) == 0
    assert out.exists() and "drive" in out.read_text()
    capsys.readouterr()
    assert main(["reduce", str(STB), "--band", "1Hz:300Hz", "--tol", "0.01", "--element", "k0",
                 "--points", "200", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["file"] == str(STB)


def test_json_nonfinite_are_numbers_for_json_and_pandas(tmp_path, capsys):
    p = tmp_path / "m.mcir"
    p.write_text("mass m a 0 2\ndrive V a 0 velocity=0.1\n")
    assert main(["sweep", str(p), "--omega-min", "0", "--omega-max", "1", "--points", "2",
                 "--json"]) == 0
    text = capsys.readouterr().out
    doc = json.loads(text)
    assert all(isinstance(x, float) for x in doc["K"]["im"] + doc["Q0"]["im"])
    assert math.isinf(doc["K"]["im"][0]) and doc["Q0"]["im"][1] == pytest.approx(0.2, rel=1e-15)


def test_scene_cycle_plot_unit_option(tmp_path, capsys):
    png = tmp_path / "c.png"
    assert main(["scene", str(REPO / "examples" / "heald_scene.toml"), "--cycle", "--points",
                 "4", "--harmonics", "2", "--plot", str(png), "--unit", "Hz"]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_import_and_help_do_not_load_matplotlib(light_imports):
    # import mechcirc, mechcirc.cli and build the parser (one process with the other light-import checks: tests/conftest.py, light_imports)
    loaded = light_imports["build_parser"]
    assert not any(m.startswith(("matplotlib", "skrf", "pint")) for m in loaded)


def test_cycle_map_reports_progress():
    from mechcirc.scene import load_scene
    from mechcirc.scene.cycle import cycle_map

    calls = []
    cycle_map(load_scene(REPO / "examples" / "heald_scene.toml"), points=5, harmonics=2,
              progress=lambda done, total: calls.append((done, total)))
    assert calls == [(i, 5) for i in range(1, 6)]


ROTARY = """# a two-inertia shaft, driven in rotation
drive W p 0 velocity=2 rad/s
mass J1 p 0 0.5
spring k1 p q 1e4
mass J2 q 0 0.2
"""


def test_forces_of_a_rotary_circuit_are_moments(tmp_path, capsys):
    """`forces` on a rotary netlist: N·m, rad/s and rad/(N·m·s) in the text and on the plot.
    Independent check of the numbers: at ω = 100 rad/s the shaft p–q has
    K = 1/(jωJ1 + 1/(jω/k1 + 1/(jωJ2))), so |Q0| = |V0/K|."""
    import matplotlib

    matplotlib.use("Agg")
    from mechcirc.circuit import units_of
    from mechcirc.plotting import plot_forces

    path = tmp_path / "shaft.mcir"
    path.write_text(ROTARY)
    assert main(["forces", str(path), "--omega", "100"]) == 0
    out = capsys.readouterr().out
    w = 100.0
    Y = 1j * w * 0.5 + 1 / (1j * w / 1e4 + 1 / (1j * w * 0.2))
    assert f"|Q0| = {abs(2 * Y):.6g} N·m" in out
    assert "|Q| [N·m]" in out and "|v| [rad/s]" in out and "rad/(N·m·s)" in out
    assert "[N]" not in out and "m/s" not in out.replace("rad/s", "")
    from matplotlib.figure import Figure

    import mechcirc
    from mechcirc.forces import element_forces

    circuit = mechcirc.load(path)
    rows, *_ = element_forces(circuit, 100.0)
    ax = plot_forces(rows, 100.0, ax=Figure().subplots(), units=units_of(circuit.drive))
    assert ax.get_ylabel() == "|Q| [N·m]"
