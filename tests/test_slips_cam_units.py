"""A drive with ``motion=`` (a cam law or a table) takes the rotary units (rad/s, N·m)
by the same rule as a velocity or force drive: the stroke's unit when given (an angle:
rotary; a length: translational), else the element kinds on the driven nodes."""

import shutil
import warnings
from pathlib import Path

import pytest
from cli_helpers import run

from mechcirc import load, parse
from mechcirc.circuit import units_of
from mechcirc.errors import UnitMixWarning

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"

ROTARY = """\
drive  V0  T 0 motion=cycloidal rise=120 dwell=60 return=120 stroke={stroke}
mass   J1  T 0 0.01 kg*m^2
spring k1  T A 500 N*m/rad
mass   J2  A 0 0.05 kg*m^2
"""
LINEAR = ROTARY.replace("kg*m^2", "kg").replace("N*m/rad", "N/mm")


@pytest.mark.parametrize("stroke, text, rotary", [
    ("20 deg", ROTARY, True),      # an angle: rotary, whatever the nodes carry
    ("0.3 rad", LINEAR, True),
    ("0.3", ROTARY, True),         # no unit: the nodes carry rotary units only
    ("0.3", LINEAR, False),
    ("100 mm", ROTARY, False),     # a length: translational
])
def test_cam_law_drive_rotary_rule(stroke, text, rotary):
    # A stroke's unit that disagrees with the elements on the drive's node decides, and
    # says so (UnitMixWarning: "0.3 rad" against kg, "100 mm" against kg·m²).
    mixed = stroke.split()[-1] in ("rad", "mm") and (text is LINEAR) is rotary
    with (pytest.warns(UnitMixWarning, match="node 'T'") if mixed else warnings.catch_warnings()):
        if not mixed:
            warnings.simplefilter("error", UnitMixWarning)
        c = parse(text.format(stroke=stroke))
    assert c.drive.rotational is rotary
    assert units_of(c.drive)["Q"] == ("N·m" if rotary else "N")


def test_table_drive_follows_its_nodes(tmp_path):
    shutil.copy(EXAMPLES / "lift.csv", tmp_path / "lift.csv")
    net = tmp_path / "rot.mcir"
    net.write_text(ROTARY.format(stroke="0").splitlines()[0].split(" motion=")[0]
                   + " motion=lift.csv\n" + "\n".join(ROTARY.splitlines()[1:]) + "\n")
    assert load(net).drive.rotational is True
    assert load(EXAMPLES / "cam_table.mcir").drive.rotational is False


def test_periodic_prints_rotary_units(tmp_path, capsys):
    net = tmp_path / "rot.mcir"
    net.write_text(ROTARY.format(stroke="20 deg"))
    status, text, err = run(["periodic", net, "--rpm", "600", "--harmonics", "40"], capsys)
    assert status == 0, err
    assert "N·m at θ" in text and "rad/s" in text and "|Q_k| [N·m]" in text
    assert " m/s" not in text and "[N]" not in text
    status, text, err = run(["periodic", EXAMPLES / "cam_drive.mcir", "--rpm", "600",
                             "--harmonics", "40"], capsys)
    assert status == 0, err        # the translational cam is unchanged
    assert "|Q_k| [N]" in text and "up to 6 m/s" in text and "N·m" not in text


@pytest.mark.parametrize("text, stroke", [(ROTARY, "20 deg"), (ROTARY, "0.3"),
                                          (LINEAR, "0.1")])
def test_written_cam_netlist_reads_back_with_its_units(text, stroke):
    from mechcirc.netlist_writer import write

    c = parse(text.format(stroke=stroke))
    back = parse(write(c))          # the writer gives SI numbers without units
    assert back.drive.rotational is c.drive.rotational
    assert back.drive.motion.spec == c.drive.motion.spec
