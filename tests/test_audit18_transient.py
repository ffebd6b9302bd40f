"""``mechcirc transient`` as a designer reads it (audit18): the block-propagation note says
what was done and why, not that something was refused; ``--waveform`` is read once, by the
parser the run uses, also to decide whether ``--amplitude`` applies."""

from pathlib import Path

import pytest
from cli_helpers import assert_user_error, run

NETLISTS = Path(__file__).resolve().parents[1] / "netlists"


def test_block_propagation_note_is_not_an_error(capsys):
    status, out, err = run(["transient", NETLISTS / "stb_heald.mcir", "--t-end", "0.01"], capsys)
    assert status == 0, err
    note = next(ln for ln in err.splitlines() if "linear propagation" in ln)
    assert note.startswith("note: linear propagation: block propagation (exact; ")
    assert "the modal path needs independent mode shapes and is not used here: eigenvector " \
           "matrix condition number" in note
    assert "refused" not in err and "error" not in note       # main: "(modal path refused: ..."


@pytest.mark.parametrize("wave, hint", [("csv", "write it as csv:PATH"),
                                        ("rest:5", "write it as rest")])
def test_bad_waveform_is_named_before_amplitude(wave, hint, capsys):
    """The old test by the text before ':' took 'csv' and 'rest:5' for waveforms that ignore
    --amplitude, and refused --amplitude instead of saying the waveform is malformed."""
    err = assert_user_error(["transient", NETLISTS / "stb_heald.mcir", "--t-end", "0.01",
                             "--waveform", wave, "--amplitude", "2"], capsys,
                            f"--waveform {wave!r} is not understood", hint)
    assert "--amplitude" not in err


def test_amplitude_still_refused_at_rest_and_taken_by_a_step(capsys):
    assert_user_error(["transient", NETLISTS / "stb_heald.mcir", "--t-end", "0.01", "--waveform",
                       "rest", "--amplitude", "2"], capsys, "--amplitude applies to a harmonic")
    status, _, err = run(["transient", NETLISTS / "stb_heald.mcir", "--t-end", "0.01",
                          "--waveform", "step", "--amplitude", "2"], capsys)
    assert status == 0, err
