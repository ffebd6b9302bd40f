"""A drive of amplitude 0 (``velocity=0``, ``force=0``, often a value not filled in):
K does not depend on it, but Q0, v0 (one of them the drive's own 0) and every
element force are then 0 at every frequency.  The commands ran with no word; each that loads the netlist
for the frequency domain now warns once, at the drive's line and column."""

from __future__ import annotations

import json

import pytest
from cli_helpers import run

NETLIST = "mass m1 a 0 2\nspring k1 a 0 800\n  drive V a 0 {amp}\n"


@pytest.mark.parametrize("amp", ["velocity=0", "force=0 N", "velocity={0*5} mm/s"])
@pytest.mark.parametrize("cmd", [["check"], ["sweep", "--omega-min", "1", "--omega-max", "100",
                                             "--points", "3"], ["forces", "--omega", "10"]])
def test_a_zero_drive_is_warned_at_its_line(amp, cmd, tmp_path, capsys):
    path = tmp_path / "z.mcir"
    path.write_text(NETLIST.format(amp=amp))
    status, out, err = run([cmd[0], path, *cmd[1:]], capsys)
    assert status == 0, err
    lines = [ln for ln in err.splitlines() if "amplitude 0" in ln]
    assert len(lines) == 1, err
    assert lines[0].startswith(f"warning: {path}:3:3: drive 'V' has amplitude 0"), lines
    assert "Q0, v0 and every element force are 0" in lines[0]


def test_a_nonzero_drive_is_not_warned_and_json_lists_the_warning(tmp_path, capsys):
    path = tmp_path / "z.mcir"
    path.write_text(NETLIST.format(amp="velocity=1e-300"))
    status, _, err = run(["check", path], capsys)
    assert status == 0 and err == "", err
    path.write_text(NETLIST.format(amp="velocity=0"))
    status, out, _ = run(["check", path, "--json"], capsys)
    assert status == 0
    assert [w for w in json.loads(out)["warnings"] if "amplitude 0" in w]
