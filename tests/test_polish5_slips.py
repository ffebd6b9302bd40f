"""Slips of a new user answered with what was meant (exit 2, one line, no traceback).

* an option of another command (``forces --element``) says which commands take
  it, instead of "did you mean '--element'?" (the very word given);
* a misspelt option suggests the command's own options only;
* ``transient --waveform harmonc:300`` / ``stepp``, ``periodic --elements k44`` and
  ``reduce --element k44``: "did you mean";
* ``transient --dt`` longer than ``--t-end`` is refused (it silently ran to t = dt).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_helpers import assert_user_error
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]


def test_another_commands_option_names_the_commands_that_take_it(capsys):
    err = assert_user_error(["forces", STB, "--omega", "300", "--element", "k4"], capsys,
                            "unrecognized arguments: --element k4",
                            "--element is an option of ", "not of forces")
    owners = err.split("is an option of ")[1].split(", not of")[0].split(", ")
    assert {"sweep", "transient", "reduce"} <= set(owners) and "forces" not in owners
    assert "did you mean '--element'" not in err
    err = assert_user_error(["linkage", REPO / "examples/fnf_sixbar.toml", "--points", "10"],
                            capsys, "--points is an option of ", "not of linkage")


def test_a_misspelt_option_is_matched_against_the_commands_own_options(capsys):
    err = assert_user_error(["sweep", STB, "--omega-min", "10", "--omega-max", "1e4",
                             "--methd", "nodal"], capsys, "did you mean '--method'?")
    # the command is named, and its own --help is the one that lists its options
    assert err.startswith("mechcirc sweep: error:") and "(see 'mechcirc sweep --help')" in err
    err = assert_user_error(["forces", STB, "--omega", "300", "--elemnt", "k4"], capsys,
                            "unrecognized arguments: --elemnt k4")
    assert "--element" not in err.replace("--elemnt", "")     # not an option of forces


@pytest.mark.parametrize("wave, meant", [("harmonc:300", "harmonic"), ("stepp", "step"),
                                         ("impuls", "impulse")])
def test_transient_drive_kind_did_you_mean(wave, meant, capsys, tmp_path):
    out = tmp_path / "t.csv"
    assert_user_error(["transient", STB, "--t-end", "0.01", "--waveform", wave, "-o", out],
                      capsys, f"--waveform {wave!r} is not understood",
                      f"did you mean {meant!r}?")
    assert not out.exists()


def test_periodic_and_reduce_element_names_did_you_mean(capsys):
    assert_user_error(["periodic", STB, "--rpm", "600", "--elements", "k44"], capsys,
                      "unknown element 'k44'; did you mean 'k4'? (given to --elements")
    assert_user_error(["reduce", STB, "--band", "10:2000", "--tol", "0.01", "--element",
                       "k44"], capsys, "output 'k44': no element of that name; did you mean 'k4'?")


def test_transient_step_longer_than_the_run_is_refused(capsys, tmp_path):
    import mechcirc
    from mechcirc.errors import MechcircError
    from mechcirc.transient import transient

    out = tmp_path / "t.csv"
    assert_user_error(["transient", STB, "--t-end", "0.01", "--dt", "1", "-o", out], capsys,
                      "--dt 1 s is longer than --t-end 0.01 s")
    assert not out.exists()
    c = mechcirc.parse("drive F a 0 force=1\nspring k a 0 100\nmass m a 0 1\n")
    with pytest.raises(MechcircError, match="longer than --t-end"):
        transient(c, 0.01, 1.0, "step")
    r = transient(c, 0.01, 0.01, "step")         # dt = t_end: one step, ends at t_end
    assert r.time.tolist() == [0.0, 0.01]


def test_study_plot_column_did_you_mean_and_needs_plot(tmp_path, capsys):
    net = tmp_path / "n.mcir"
    net.write_text(".param m=2\nmass m1 a 0 m\nspring k a 0 100\ndrive V a 0 velocity=1\n")
    spec = tmp_path / "s.toml"
    spec.write_text(f'netlist = "{net.as_posix()}"\nanalysis = "sweep"\n'
                    '[omega]\nmin = 1\nmax = 100\npoints = 5\n[grid]\nm = [1.0, 2.0]\n')
    out, png = tmp_path / "o.csv", tmp_path / "o.png"
    assert_user_error(["study", spec, "--workers", "1", "-o", out, "--plot", png,
                       "--plot-column", "K_abs_mx"], capsys,
                      "--plot-column 'K_abs_mx' is not a result column; did you mean 'K_abs_max'?")
    assert_user_error(["study", spec, "--workers", "1", "-o", out, "--plot-column",
                       "K_abs_max"], capsys, "--plot-column applies to the --plot", "add --plot IMAGE")
    assert not out.exists() and not png.exists()


def test_a_sliders_misspelt_link_is_named(tmp_path, capsys):
    """[[sliders]] link = "blok": the error was about the one-point link 'block' only."""
    text = (REPO / "examples/slider_crank_scene.toml").read_text()
    assert text.count('link = "block"') == 1
    f = tmp_path / "s.toml"
    f.write_text(text.replace('link = "block"', 'link = "blok"'))
    assert_user_error(["scene", f, "--theta", "60"], capsys, "s.toml:",
                      "[[sliders]] names 'blok', which is no link; did you mean 'block'?")


def test_a_bare_word_that_is_near_an_options_choice(capsys):
    """``mechcirc synth medum`` meant ``--load medium``."""
    assert_user_error(["synth", "medum"], capsys, "unrecognized arguments: medum; "
                      "did you mean '--load medium'?")
    err = assert_user_error(["check", STB, "extra"], capsys, "unrecognized arguments: extra")
    assert "did you mean" not in err


def test_linkage_on_a_scene_file_points_to_the_scene_commands(capsys):
    err = assert_user_error(["linkage", REPO / "examples/heald_scene.toml"], capsys,
                            "heald_scene.toml:", "unknown top-level key 'elastic'",
                            "[elastic] is a table of a scene: 'mechcirc scene ",
                            "load_scene(FILE).linkage")
    assert err.count("(expected ") == 1


def test_simulate_set_unknown_parameter_did_you_mean(capsys):
    assert_user_error(["simulate", "--revolutions", "1", "--set", "C22=1"], capsys,
                      "--set C22: no such parameter; did you mean 'C2'?", "(there are C2, C4")


@pytest.mark.parametrize("argv, what", [
    (["sweep", STB, "--omega-min", "10", "--omega-max", "1e4", "-o", "{out}.png"], "a CSV table"),
    (["transient", STB, "--t-end", "0.01", "-o", "{out}.pdf"], "a CSV table"),
    (["reduce", STB, "--band", "10:2000", "--tol", "0.01", "-o", "{out}.svg"],
     "the reduced netlist"),
    (["scene", REPO / "examples/heald_scene.toml", "--theta", "40", "-o", "{out}.png"],
     "a CSV table (--cycle) or a netlist (--theta)"),
    # these four wrote their CSV text into the image's name
    (["simulate", "--variant", "3", "-o", "{out}.png"], "a CSV table"),
    (["simulate", REPO / "examples/heald_scene.toml", "-o", "{out}.png"], "a CSV table"),
    (["periodic", REPO / "docs/examples/cam_drive.mcir", "--rpm", "600", "-o", "{out}.png"],
     "a CSV table"),
    (["cam", "--law", "cycloidal", "--rise", "120", "--dwell", "60", "--return", "120",
      "--stroke", "20", "--base-radius", "40", "--roller-radius", "10", "-o", "{out}.png"],
     "a CSV table"),
])
def test_a_table_output_named_like_an_image_is_refused(argv, what, tmp_path, capsys):
    """``-o K.png`` wrote CSV text into K.png; the message names the command's own
    drawing option (cam's is --svg: it named --plot, which cam has not, session 28)."""
    out = tmp_path / "out"
    argv = [str(a).replace("{out}", str(out)) for a in argv]
    assert_user_error(argv, capsys, f"-o writes {what}", "not an image", {
        "cam": "--svg SVG", "reduce": "this command draws none"}.get(argv[0], "--plot IMAGE"))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv", [
    ["crosscheck", "--theta", "60", "--netlist", "{out}.png"],
    ["crosscheck", REPO / "examples/heald_scene.toml", "--theta", "40", "--netlist",
     "{out}.png"],
])
def test_a_netlist_output_named_like_an_image_is_refused(argv, tmp_path, capsys):
    """``crosscheck --netlist x.png`` wrote the netlist's text into x.png."""
    out = tmp_path / "out"
    argv = [str(a).replace("{out}", str(out)) for a in argv]
    assert_user_error(argv, capsys, "--netlist writes the netlist", "not an image",
                      "this command draws none")     # (it named --plot, which it has not)
    assert list(tmp_path.iterdir()) == []


def test_a_table_output_named_json_points_to_json(tmp_path, capsys):
    out = tmp_path / "T.json"
    assert_user_error(["transient", STB, "--t-end", "0.01", "-o", out], capsys,
                      "-o writes a CSV table, not JSON; --json prints the JSON document")
    assert not out.exists()


def test_a_misspelt_required_option_is_named(capsys):
    """argparse reports the required option missing before the unknown one: the misspelling
    ('--omga' for '--omega') is named with what was meant."""
    assert_user_error(["forces", STB, "--omga", "100"], capsys,
                      "required: --omega", "--omga is not an option; did you mean '--omega'?")
    err = assert_user_error(["sweep", STB, "--omega-max", "10"], capsys, "required: --omega-min")
    assert "is not an option" not in err                 # nothing misspelt: nothing said


def test_a_netlist_given_for_a_toml_file_says_so(capsys):
    assert_user_error(["scene", STB, "--theta", "10"], capsys, "stb_heald.mcir:12:1",
                      "TOML syntax", "this is a netlist (.mcir)", "mechcirc sweep")
