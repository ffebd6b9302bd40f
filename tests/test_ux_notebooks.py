"""Notebook and command-line surface: DataFrames, resonance tables, frequency units,
rotary units, node and element responses from ``mechcirc sweep``."""

import csv
import math
import pickle
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run
from reference.inputs import STB as STB_PATH

import mechcirc
from mechcirc.resonances import Resonances, find_resonances

REPO = Path(__file__).resolve().parents[1]
STB = str(STB_PATH)

# mass m between a and b, spring k from b to the frame, velocity drive V0 at a:
# K = 1/(jωm) + jω/k, the spring's force Q = V0/K, node b's velocity v_b = Q·jω/k.
TWO = "drive V a 0 velocity=0.5\nmass m a b 2\nspring k b 0 800\n"


def _closed_form(w):
    Km, Kk = 1 / (1j * w * 2.0), 1j * w / 800.0
    Q = 0.5 / (Km + Kk)
    return Q, Q * Kk


def _read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


def test_to_dataframe_columns_are_the_sweep_arrays():
    pytest.importorskip("pandas")
    s = mechcirc.load(STB).sweep(np.geomspace(10, 1e4, 57))
    df = s.to_dataframe()
    assert list(df.columns) == ["omega", "K", "|K|", "Q0", "|Q0|", "flag", "error"]
    np.testing.assert_array_equal(df["omega"].to_numpy(), s.omega)
    np.testing.assert_array_equal(df["K"].to_numpy(), s.K)
    np.testing.assert_array_equal(df["|K|"].to_numpy(), np.abs(s.K))
    np.testing.assert_array_equal(df["Q0"].to_numpy(), s.Q0)
    np.testing.assert_array_equal(df["flag"].to_numpy(), s.flags)
    np.testing.assert_array_equal(df["error"].to_numpy(), s.error)


def test_to_dataframe_of_a_force_drive_has_v0():
    pytest.importorskip("pandas")
    s = mechcirc.parse("mass m a 0 2\nspring k a 0 800\ndrive F a 0 force=3\n").sweep([5., 30.])
    df = s.to_dataframe()
    assert "v0" in df.columns and "|v0|" in df.columns
    np.testing.assert_array_equal(df["v0"].to_numpy(), s.v0)


def test_to_xarray_or_a_clear_import_error():
    s = mechcirc.parse(TWO).sweep([5., 30.])
    try:
        import xarray  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="needs xarray"):
            s.to_xarray()
        return
    ds = s.to_xarray()
    np.testing.assert_array_equal(ds["omega"].to_numpy(), s.omega)
    np.testing.assert_array_equal(ds["abs_K"].to_numpy(), np.abs(s.K))
    assert ds["K"].attrs["units"] == "m/(N·s)"


def test_resonances_are_a_list_with_a_table_repr():
    c = mechcirc.load(STB)
    found = find_resonances(c, omega_max=5000)
    assert isinstance(found, list) and type(found) is Resonances
    assert type(c.resonances()) is Resonances
    text = repr(found)
    assert len(text.splitlines()) == len(found) + 1
    for r in found:
        assert f"{r.omega:.10g}" in text and r.kind in text
    html = found._repr_html_()
    assert html.count("<tr>") == len(found) + 1
    back = pickle.loads(pickle.dumps(found))
    assert type(back) is Resonances and back == found
    assert isinstance(found[:2], list)


def test_resonance_table_in_rpm_and_hz():
    found = find_resonances(mechcirc.parse(TWO))
    (r,) = found                                     # ω = √(k/m) = 20 rad/s
    assert r.omega == pytest.approx(20.0, rel=1e-14)
    rpm, hz = found.table("rpm"), found.table("Hz")
    assert "n [rpm]" in rpm[0] and "f [Hz]" in hz[0]
    assert float(rpm[1].split()[1]) == pytest.approx(20 * 60 / (2 * math.pi), rel=1e-9)
    assert float(hz[1].split()[1]) == pytest.approx(20 / (2 * math.pi), rel=1e-9)


def test_resonance_table_in_hz_shows_the_damped_frequency():
    """TWO with a damper c = 8 beside the spring: K = 0 where m s² + c s + k = 0, so
    s = −2 ± j√396 (ζ = 0.1); the Hz table's f and f_d columns are 20/2π and √396/2π,
    and in_unit gives the same f_d from one root (what ``Resonance.fd_hz`` gave)."""
    from mechcirc.units import in_unit

    found = find_resonances(mechcirc.parse(TWO + "damper c b 0 8\n"), kind="resonance")
    (r,) = found                # (the anti-resonance: a first-order mode, k/c = 100 rad/s)
    assert r.zeta == pytest.approx(0.1, rel=1e-12)
    f, f_d = (float(v) for v in found.table("Hz")[1].split()[1:3])
    assert f == pytest.approx(20 / (2 * math.pi), rel=1e-9)
    assert f_d == pytest.approx(math.sqrt(396.0) / (2 * math.pi), rel=1e-9)
    assert in_unit(r.omega_d, "Hz") == pytest.approx(math.sqrt(396.0) / (2 * math.pi),
                                                     rel=1e-13)


def test_cli_resonance_table_is_the_library_table(capsys):
    status, out, _ = run(["resonances", STB, "--omega-max", "5000"], capsys)
    assert status == 0
    table = find_resonances(mechcirc.load(STB), omega_max=5000).table()
    assert out.splitlines()[1:] == [f"  {line}" for line in table]


def test_transient_result_repr_is_a_summary():
    from mechcirc.transient.simulate import transient

    res = transient(mechcirc.load(STB), 0.05)
    text = repr(res)
    assert len(text) < 400 and "stb_heald" in text and "2001 samples" in text


def test_sweep_unit_rpm_column(tmp_path, capsys):
    out = tmp_path / "K.csv"
    status, text, _ = run(["sweep", STB, "--omega-min", "10", "--omega-max", "1e4",
                           "--points", "40", "--log", "--unit", "rpm", "-o", out], capsys)
    assert status == 0
    header, data = _read_csv(out)
    assert header[0] == "n_rpm"
    expected = np.geomspace(10, 1e4, 40) * 60 / (2 * math.pi)
    np.testing.assert_allclose(data[:, 0], expected, rtol=1e-15)
    assert "n 95.493 .. 95493 rpm" in text


def test_sweep_unit_hz_column(tmp_path, capsys):
    out = tmp_path / "K.csv"
    status, _, _ = run(["sweep", STB, "--omega-min", "10", "--omega-max", "1e4",
                        "--points", "5", "--unit", "Hz", "-o", out], capsys)
    assert status == 0
    header, data = _read_csv(out)
    assert header[0] == "f_Hz"
    np.testing.assert_allclose(data[:, 0], np.linspace(10, 1e4, 5) / (2 * math.pi),
                               rtol=1e-15)


def test_sweep_node_and_element_columns(tmp_path, capsys):
    net = tmp_path / "two.mcir"
    net.write_text(TWO)
    out = tmp_path / "K.csv"
    status, text, _ = run(["sweep", net, "--omega-min", "3", "--omega-max", "50",
                           "--points", "9", "--node", "b", "--element", "k", "--element", "m",
                           "-o", out], capsys)
    assert status == 0, text
    header, data = _read_csv(out)
    assert header[5:9] == ["v_abs(b)", "x_abs(b)", "Q_abs(k)", "Q_abs(m)"]
    w = np.linspace(3, 50, 9)
    Q, vb = _closed_form(w)
    np.testing.assert_allclose(data[:, 5], np.abs(vb), rtol=1e-12)
    np.testing.assert_allclose(data[:, 6], np.abs(vb) / w, rtol=1e-12)
    np.testing.assert_allclose(data[:, 7], np.abs(Q), rtol=1e-12)
    np.testing.assert_allclose(data[:, 8], np.abs(Q), rtol=1e-12)     # in series
    s = mechcirc.parse(TWO).sweep(w)
    np.testing.assert_allclose(data[:, 5], np.abs(s.node_velocity("b")), rtol=1e-15)


def test_node_velocity_by_either_method():
    w = np.geomspace(1, 300, 31)
    for method in ("sp", "nodal"):
        s = mechcirc.parse(TWO).sweep(w, method=method)
        np.testing.assert_allclose(s.node_velocity("b"), _closed_form(w)[1], rtol=1e-12)
        np.testing.assert_allclose(s.node_velocity("a"), 0.5, rtol=1e-14)


def test_sweep_unknown_node_and_element_say_what_was_meant(capsys):
    status, _, err = run(["sweep", STB, "--omega-min", "10", "--omega-max", "20",
                          "--element", "k44"], capsys)
    assert status == 2 and "did you mean 'k4'?" in err
    status, _, err = run(["sweep", STB, "--omega-min", "10", "--omega-max", "20",
                          "--node", "b"], capsys)
    assert status == 2 and "did you mean 'B'?" in err, err


ROTARY = "drive W p 0 velocity=2 rad/s\nspring k p 0 100 N*m/rad\nmass J p 0 1 kg*m^2\n"


def test_rotary_drive_is_labelled_in_rotary_units(tmp_path, capsys):
    c = mechcirc.parse(ROTARY)
    assert c.drive.rotational
    # without a unit on the drive, its node's rotary elements decide
    assert mechcirc.parse(ROTARY.replace(" rad/s", "")).drive.rotational
    assert not mechcirc.parse(TWO).drive.rotational
    net = tmp_path / "rot.mcir"
    net.write_text(ROTARY)
    status, out, _ = run(["sweep", net, "--omega-min", "1", "--omega-max", "100"], capsys)
    assert status == 0
    assert "rad/(N·m·s)" in out and "N·m" in out and "m/(N·s)" not in out
    assert mechcirc.parse(ROTARY).sweep([1.0]).units["Q"] == "N·m"


def test_sweep_plot_in_rpm_with_a_node_panel_and_rotary_labels():
    pytest.importorskip("matplotlib")
    from mechcirc.plotting import plot_sweep

    w = np.geomspace(1, 100, 20)
    s = mechcirc.parse(ROTARY).sweep(w)
    fig = plot_sweep(s, unit="rpm", extra={"|v(p)| [rad/s]": np.abs(s.node_velocity("p"))})
    axes = fig.axes
    assert len(axes) == 4
    assert axes[-1].get_xlabel() == "n [rpm]"
    np.testing.assert_allclose(axes[0].lines[0].get_xdata(), w * 60 / (2 * math.pi),
                               rtol=1e-15)
    assert axes[0].get_ylabel() == "|K| [rad/(N·m·s)]"
    assert axes[2].get_ylabel() == "|Q0| [N·m]"
    assert "V0 = 2 rad/s" in fig._suptitle.get_text()


def test_check_columns_fit_long_names_without_trailing_spaces(tmp_path, capsys):
    net = tmp_path / "rot.mcir"
    net.write_text(ROTARY.replace("spring k p 0", "spring k_very_long_name p q")
                   .replace("mass J p 0", "mass J q 0"))
    status, out, _ = run(["check", net], capsys)
    assert status == 0
    lines = out.splitlines()
    assert "drive W: velocity 2 rad/s between p and 0" in lines
    assert all(line == line.rstrip() for line in lines)
    rows = [line for line in lines if line.startswith(("  spring", "  mass"))]
    # values with their rotary SI units: torsional stiffness N·m/rad, inertia kg·m²
    assert rows[0].split() == ["spring", "k_very_long_name", "p", "q", "100", "N·m/rad"]
    assert rows[1].split() == ["mass", "J", "q", "0", "1", "kg·m²"]
    # the columns line up although one name is longer than the column's default
    assert rows[0].index("100 N·m/rad") == rows[1].index("1 kg·m²")       # the values
    assert rows[0].rindex("q") == rows[1].rindex("0")         # the second nodes


def test_check_shows_the_backlash_with_the_drive_unit(tmp_path, capsys):
    """The total gap B in rad for a rotary drive, in m for a translational one."""
    for text, unit in ((ROTARY.replace("100 N*m/rad", "100 N*m/rad backlash=0.01"), "rad"),
                       ("drive V p 0 velocity=0.1\nspring k p 0 100 backlash=2e-3\n"
                        "mass m p 0 1\n", "m")):
        net = tmp_path / "gap.mcir"
        net.write_text(text)
        status, out, _ = run(["check", net], capsys)
        assert status == 0
        row = next(line for line in out.splitlines() if line.startswith("  spring"))
        assert row.endswith(f"backlash={0.01 if unit == 'rad' else 0.002:g} {unit}"), row


def test_transient_table_of_a_rotary_drive_says_rad_and_newton_metres(tmp_path, capsys):
    net = tmp_path / "rot.mcir"
    net.write_text(ROTARY.replace("spring k p 0", "spring k p q").replace("mass J p 0",
                                                                           "mass J q 0"))
    status, out, _ = run(["transient", net, "--t-end", "0.1", "--waveform", "step"], capsys)
    assert status == 0
    assert "x(end) [rad]" in out and "v(end) [rad/s]" in out and "max|F| [N·m]" in out
    assert "drive moment: max |F|" in out and "[m]" not in out


@pytest.mark.parametrize("text, needle", [
    ("drive V a 0 velocity=1\nmas m a 0 1\n", "unknown keyword 'mas'; did you mean 'mass'?"),
    ("drive V a 0 velocty=1\nmass m a 0 1\n",
     "unknown option 'velocty' for drive; did you mean 'velocity'?"),
    ("drive V a 0 velocity=1\nmass m a 2\n", "mass line is missing a node"),
])
def test_netlist_slips_say_what_was_meant(tmp_path, capsys, text, needle):
    net = tmp_path / "slip.mcir"
    net.write_text(text)
    status, _, err = run(["check", net], capsys)
    assert status == 2 and needle in err, err
    assert "missing VALUE" not in err


def test_a_missing_value_is_still_called_that(tmp_path, capsys):
    net = tmp_path / "slip.mcir"
    net.write_text("drive V a 0 velocity=1\nmass m a 0\n")      # '0' is the frame
    status, _, err = run(["check", net], capsys)
    assert status == 2 and "mass line is missing VALUE" in err


@pytest.mark.parametrize("argv, needle", [
    (["swep", STB], "did you mean 'sweep'?"),
    (["sweep", STB, "--omega-min", "1", "--omega-max", "2", "--method", "spp"],
     "did you mean 'sp'?"),
    (["sweep", STB, "--omega-min", "1", "--omega-max", "2", "--methd", "sp"],
     "did you mean '--method'?"),
])
def test_command_line_slips_say_what_was_meant(capsys, argv, needle):
    status, _, err = run(argv, capsys)
    assert status == 2 and needle in err, err


def test_did_you_mean():
    from mechcirc.sources import did_you_mean

    assert did_you_mean("maximum", ("min", "max", "num", "log")) == "; did you mean 'max'?"
    assert did_you_mean("b", ("A", "B")) == "; did you mean 'B'?"
    assert did_you_mean("zzz", ("min", "max")) == ""
    # ω written as w, with or without separators: difflib's ratio alone finds neither
    options = ("--omega-min", "--omega-max", "--points", "--log")
    assert did_you_mean("--wmax", options) == "; did you mean '--omega-max'?"
    assert did_you_mean("--w_min", options) == "; did you mean '--omega-min'?"


def _nx_loaded_groups(groups, a, b):
    """The reference: the block of edge a–b by networkx (what loaded_groups used before).

    A pair (u, u) (a lever whose sides share a node) is a self-loop, which
    networkx puts into whichever block its DFS has open: it couples nothing,
    so it is left out of the graph and of the test of the group.
    """
    import networkx as nx

    g = nx.Graph()
    g.add_nodes_from(n for pairs in groups for p in pairs for n in p)
    g.add_edges_from(p for pairs in groups for p in pairs if p[0] != p[1])
    if a not in g or b not in g or not nx.has_path(g, a, b):
        return None
    g.add_edge(a, b)
    block = set()
    for comp in nx.biconnected_component_edges(g):
        pairs = {frozenset(p) for p in comp}
        if frozenset((a, b)) in pairs:
            block = pairs
            break
    return [i for i, pairs in enumerate(groups)
            if all(frozenset(p) in block for p in pairs if p[0] != p[1])]


def test_loaded_groups_agree_with_networkx_on_random_graphs():
    from mechcirc.errors import TopologyError
    from mechcirc.topology import loaded_groups

    rng = np.random.default_rng(26)
    for trial in range(1500):
        n = int(rng.integers(2, 12))
        m = int(rng.integers(1, 3 * n))
        nodes = [str(i) for i in range(n)]
        groups = []
        for _ in range(m):
            if rng.random() < 0.15:         # a lever: the clique of four terminals (may repeat)
                t = [nodes[int(i)] for i in rng.integers(0, n, 4)]
                groups.append([(t[i], t[j]) for i in range(4) for j in range(i + 1, 4)])
            else:
                u, w = rng.choice(n, 2, replace=False)
                groups.append([(nodes[int(u)], nodes[int(w)])])
        a, b = nodes[0], nodes[1]
        expected = _nx_loaded_groups(groups, a, b)
        if expected is None:
            with pytest.raises(TopologyError):
                loaded_groups(groups, a, b)
        else:
            assert loaded_groups(groups, a, b) == expected, (trial, groups)


def test_sweep_json_carries_the_node_and_element_responses(tmp_path, capsys):
    import json

    net = tmp_path / "two.mcir"
    net.write_text(TWO)
    status, out, _ = run(["sweep", net, "--omega-min", "3", "--omega-max", "50",
                          "--points", "4", "--node", "b", "--element", "k", "--json"], capsys)
    assert status == 0
    doc = json.loads(out)
    w = np.linspace(3, 50, 4)
    Q, vb = _closed_form(w)
    np.testing.assert_allclose(doc["responses"]["v_abs(b)"], np.abs(vb), rtol=1e-12)
    np.testing.assert_allclose(doc["responses"]["Q_abs(k)"], np.abs(Q), rtol=1e-12)
