"""``crosscheck --unit rad/s|Hz|rpm`` (issue 26): every frequency crosscheck prints, in the unit.

For each kind of input (a netlist, a scene, the sley preset) the Hz and rpm outputs'
frequencies are the rad/s output's printed frequencies converted independently here
(f = ω/2π, n = 60ω/2π), to within the two printed roundings (half a unit of the last
printed digit of each number, read from the printed text); the other numbers
(relative differences) are unchanged and the headers name the unit.
"""

from __future__ import annotations

import json
import math
import re
from decimal import Decimal
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
NUM = r"([-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?)"
#: rad/s per unit: a frequency x [rad/s] is x / FACTOR[unit] in unit.
FACTOR = {"Hz": 2 * math.pi, "rpm": 2 * math.pi / 60}
SYMBOL = {"rad/s": "(?:ω|omega)", "Hz": "f", "rpm": "n"}

#: argv, and the patterns whose groups are frequencies (SYM: the unit's symbol), per kind.
KINDS = {
    "netlist": ([str(REPO / "netlists/stb_heald.mcir"), "--omega-max", "5000"],
                [rf"SYM_d\s+{NUM}\s+ringing\s+{NUM}", rf"^\s+SYM\s+{NUM}:"]),
    "scene": ([str(REPO / "examples/heald_scene.toml"), "--theta", "40"],
              [rf"^\s*{NUM}\s+{NUM}\s+{NUM}\s+{NUM}\s+{NUM}\s+agrees",
               rf"^\s*{NUM}\s+{NUM}\s+{NUM}\s+{NUM}\s+agrees"]),
    "preset": ([], [rf"eigen\s+{NUM} \(d\s+{NUM}\)\s+circuit\s+{NUM} \(d\s+{NUM}\)",
                    rf"measured {NUM} \S+, predicted {NUM} ", rf"^\s+SYM\s+{NUM}:"]),
}
#: Which groups of each scene pattern are frequencies (0-based): ω_n and the ringing's ω_n
#: of a resonance row (ω, ζ, ω, ζ, rel. diff), ω of a forced row (ω, |Q0|, |Q0|, rel. diff).
SCENE_GROUPS = ((0, 2), (0,))


def _half_unit(text: str) -> float:
    """Half a unit in the last printed digit of ``text`` (its rounding's bound)."""
    return 0.5 * 10.0 ** Decimal(text).as_tuple().exponent


def _frequencies(out: str, kind: str, unit: str) -> list[str]:
    found = []
    for line in out.splitlines():
        for i, pattern in enumerate(KINDS[kind][1]):
            m = re.search(pattern.replace("SYM", SYMBOL[unit]), line)
            if m:
                groups = SCENE_GROUPS[i] if kind == "scene" else range(len(m.groups()))
                found += [m.group(g + 1) for g in groups]
                break
    return found


def _rel_diffs(out: str) -> list[str]:
    return re.findall(r"(?:rel\. diff|difference)\s+(\S+e[-+]\d+)", out) + \
        re.findall(r"(\d\.\d\de[-+]\d\d)\s+agrees", out)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("unit", ["Hz", "rpm"])
def test_crosscheck_frequencies_are_the_rad_s_ones_converted(cli_once, kind, unit):
    argv = ["crosscheck", *KINDS[kind][0]]
    status, base, _ = cli_once(argv)
    status_u, out, err = cli_once([*argv, "--unit", unit])
    assert (status, status_u) == (0, 0), err
    w, f = _frequencies(base, kind, "rad/s"), _frequencies(out, kind, unit)
    assert len(w) == len(f) == {"netlist": 14, "scene": 8, "preset": 21}[kind]
    k = FACTOR[unit]
    for a, b in zip(w, f):
        # |b - a/k| <= b's rounding + a's rounding / k (+ the division's own rounding)
        bound = _half_unit(b) + _half_unit(a) / k + 1e-15 * abs(float(a))
        assert abs(float(b) - float(a) / k) <= bound, (a, b, unit)
    assert _rel_diffs(out) == _rel_diffs(base) != []      # relative differences unchanged
    assert f"[{unit}]" in out or f" in {unit})" in out
    shown = [line for line in out.splitlines() if not line.lstrip().startswith("note:")]
    assert "rad/s" not in "\n".join(shown)          # (the library's notes are in SI)


def test_crosscheck_headers_name_the_unit(cli_once):
    _, net, _ = cli_once(["crosscheck", *KINDS["netlist"][0], "--unit", "Hz"])
    assert "impulse response [Hz]" in net and "steady state, at f [Hz]" in net
    _, scene, _ = cli_once(["crosscheck", *KINDS["scene"][0], "--unit", "rpm"])
    assert "(frequencies n in rpm)" in scene and "circuit n_n" in scene
    _, sley, _ = cli_once(["crosscheck", "--unit", "Hz"])
    assert "eigenfrequencies [Hz]" in sley and " Hz, predicted " in sley
    assert "|Q0|/V0 [N m s/rad] at f [Hz]" in sley


def test_crosscheck_json_stays_in_rad_s(cli_once):
    argv = ["crosscheck", *KINDS["netlist"][0], "--json"]
    assert json.loads(cli_once(argv)[1]) == json.loads(cli_once([*argv, "--unit", "rpm"])[1])


def test_crosscheck_refuses_an_unknown_unit(capsys):
    """On main --unit was no option of crosscheck (refused as unrecognised): now a choice."""
    from mechcirc.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["crosscheck", *KINDS["netlist"][0], "--unit", "kHz"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "--unit: invalid choice: 'kHz'" in err and "'rad/s', 'Hz', 'rpm'" in err
