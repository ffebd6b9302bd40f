"""Options the CLI read only with another option (or for some inputs), and ignored
without a word otherwise (audit17): each is refused, exit 2, one line, saying to
what it applies and how to leave it out or make it apply."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_helpers import assert_user_error

REPO = Path(__file__).resolve().parents[1]
FILES = {"STB": str(REPO / "netlists" / "stb_heald.mcir"),
         "CAM": str(REPO / "docs" / "examples" / "cam_drive.mcir"),
         "SCENE": str(REPO / "examples" / "heald_scene.toml"),
         "STUDY": str(REPO / "examples" / "study_stb.toml"),
         "SLEY": str(REPO / "docs" / "examples" / "sley_scene.toml"),
         "LIFT": str(REPO / "docs" / "examples" / "lift.csv"),
         "SHAFT": str(REPO / "examples" / "fnf_sixbar_scene.toml")}

#: command line (FILES by their key) | what its error line says | how to make it apply
CASES = """\
sweep STB --omega-min 10 --omega-max 1e4 --tol 1e-3 | --tol applies to --adaptive sweeps | add --adaptive
sweep STB --omega-min 10 --omega-max 1e4 --adaptive --no-refine | --no-refine applies to a fixed \
grid | leave out --adaptive
cam --motion LIFT --return 90 --base-radius 30 --roller-radius 5 | --return applies to a --law cycle |
cam --motion LIFT --return-law harmonic --base-radius 30 --roller-radius 5 | --return-law applies to |
scene SCENE --cycle --reduce | --reduce applies to one crank angle, not to --cycle |
periodic CAM --rpm 600 --points 50 | --points applies to a speed map | add --rpm-min
periodic CAM --rpm-min 100 --rpm-max 1200 --angles 90 | --angles applies to one speed | give --rpm
periodic CAM --rpm-min 100 --rpm-max 1200 --near 0.1 | --near applies to one speed | give --rpm
transient STB --t-end 0.01 --amplitude 2 | --amplitude applies to | add --waveform
transient STB --t-end 0.01 --waveform rest --amplitude 2 | --amplitude applies to | add --waveform
transient STB --t-end 0.01 --waveform step --rtol 5 | --rtol applies to netlists with a clearance |
scene SCENE --theta 40 --points 10 | --points applies to --cycle | add --cycle
scene SCENE --theta 40 --harmonics 3 | --harmonics applies to --cycle | add --cycle
study STUDY --connect-timeout 5 | --connect-timeout applies to a --scheduler | add --scheduler
study STUDY --scheduler tcp://127.0.0.1:9 --workers 2 | --workers applies to local processes |
study STUDY --plot-column Q0_abs_max | --plot-column applies to the --plot | add --plot IMAGE
synth --swing 25 --omega 50 | --omega applies to the files --export writes | add --export DIR
synth --swing 25 --c4 1e4 | --c4 applies to the files --export writes | add --export DIR
synth --swing 25 --swing-step 0.1 | --swing-step applies to |
simulate SLEY --alpha 20 | --alpha applies to a sley preset |
simulate SLEY --variant 2 | --variant applies to a sley preset |
simulate SLEY --beat-sign 1 | --beat-sign applies to a sley preset |
simulate --start-deg 10 | --start-deg applies to a scene file |
simulate --shaft | --shaft applies to a scene file's [shaft] table |
simulate --rigid | --rigid applies to --shaft | add --shaft
simulate --flywheel 0.1 | --flywheel applies to --shaft | add --shaft
simulate SHAFT --shaft --revolutions 2 | --revolutions applies to a fixed crank speed |
simulate SHAFT --shaft --plot p.png | --plot applies to a fixed crank speed |
frame --crank 35 --coupler 120 --rocker 100 --frame 140 --rpm 300 --reed-point 10,5 \
| --reed-point applies to the --reed-force | add --reed-force
frame --crank 35 --coupler 120 --rocker 100 --frame 140 --rpm 300 --beat-window 30 \
| --beat-window applies to the --reed-force | add --reed-force"""


@pytest.mark.parametrize("case", CASES.splitlines())
def test_an_option_that_would_be_ignored_is_refused(case, capsys, tmp_path):
    """``sweep --tol 1e-3`` (no --adaptive) ran the fixed grid, ``periodic --rpm 600
    --points 50`` one speed, ``transient --amplitude 2`` (no waveform) left the drive at
    rest, ``scene --theta 40 --points 10`` wrote the netlist, ``study --workers 2`` ran on
    the --scheduler's cluster, ``synth --c4 1e4`` (no --export) wrote nothing: the value
    went unread."""
    line, needle, hint = (part.strip() for part in case.split("|"))
    argv = [FILES.get(word, word) for word in line.split()]
    out = [] if argv[0] == "synth" else ["-o", str(tmp_path / "out.csv")]   # synth: no -o
    assert_user_error([*argv, *out], capsys, needle, hint, f"leave {needle.split()[0]} out")
    assert not (tmp_path / "out.csv").exists()
