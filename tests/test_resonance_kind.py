"""find_resonances(kind=...): only the roots of one kind, polished alone, bit-identical
to the same roots of kind=None (the other kind's polish is skipped, not changed)."""

import math
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc.errors import InputError
from mechcirc.resonances import find_resonances
from reference.networks import damped_ladder_lines, grid_text

NETLISTS = Path(__file__).resolve().parents[1] / "netlists"


def _as_tuples(found):
    return [(r.kind, r.omega, r.omega_d, r.zeta, r.error) for r in found]


CASES = {
    "stb_heald": lambda: mechcirc.load(NETLISTS / "stb_heald.mcir"),
    "heald_damped": lambda: mechcirc.load(NETLISTS / "heald_damped.mcir"),
    "damped_ladder": lambda: mechcirc.parse("\n".join(damped_ladder_lines(12, seed=3))),
    "undamped_grid": lambda: mechcirc.parse(grid_text(3)),
    # One dof: a zero of K at sqrt(k/m) = 10 rad/s and no pole.
    "one_dof": lambda: mechcirc.parse("drive V a 0 velocity=1\nmass m a b 1\nspring k b 0 100\n"),
    # A root shared by both eigenproblems: the antisymmetric mode b = -c
    # (omega^2 = (100 + 2*50)/1) leaves a at rest, held or released, and cancels in K.
    "shared_root": lambda: mechcirc.parse(
        "drive V a 0 velocity=1\nspring k1 a b 100\nspring k2 a c 100\nmass mb b 0 1\n"
        "mass mc c 0 1\nspring kbc b c 50\n"),
}


@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("omega_max", [None, 200.0])
def test_kind_is_bit_identical_to_filtered_all(name, omega_max):
    c = CASES[name]()
    both = find_resonances(c, omega_max=omega_max)
    for kind in ("resonance", "antiresonance"):
        alone = find_resonances(c, omega_max=omega_max, kind=kind)
        want = _as_tuples(r for r in both if r.kind == kind)
        got = _as_tuples(alone)
        # Exact equality of every float (==, so also -0.0 vs 0.0 would pass: compare repr).
        assert [tuple(map(repr, t)) for t in got] == [tuple(map(repr, t)) for t in want], kind
        assert c.resonances(omega_max=omega_max, kind=kind) == list(alone)


def test_kind_roots_against_closed_form():
    # One dof: K = 0 at sqrt(k/m) = 10 rad/s, no pole (the drive released: a free mass).
    c = CASES["one_dof"]()
    res = find_resonances(c, kind="resonance")
    assert [r.kind for r in res] == ["resonance"]
    assert math.isclose(res[0].omega, 10.0, rel_tol=1e-14)
    assert find_resonances(c, kind="antiresonance") == []


def test_shared_root_cancels_for_each_kind():
    # Closed form: K = 1/Q0 with Q0 = 2 / (1/(j w m) + j w / k) (the two branches
    # k-m in parallel, kbc carries no force when b and c move alike): a zero of
    # K at sqrt(k/m) = 10 rad/s, no pole above 0, nothing at sqrt(200).
    c = CASES["shared_root"]()
    res = find_resonances(c, kind="resonance")
    assert [r.kind for r in res] == ["resonance"]
    assert math.isclose(res[0].omega, 10.0, rel_tol=1e-14)
    assert not any(math.isclose(r.omega, math.sqrt(200), rel_tol=1e-6)
                   for r in find_resonances(c, kind="antiresonance"))


def test_kind_cases_are_not_empty():
    # The comparison above means something only where both kinds occur.
    for name in ("stb_heald", "heald_damped", "damped_ladder", "undamped_grid"):
        kinds = {r.kind for r in find_resonances(CASES[name]())}
        assert kinds == {"resonance", "antiresonance"}, name


def test_bad_kind_is_an_input_error():
    with pytest.raises(InputError, match="kind must be"):
        find_resonances(CASES["one_dof"](), kind="zero")


def test_peak_uses_its_kind_only():
    # Q0's peak under a velocity drive sits on a zero of K; the peak found with
    # kind-only roots equals the one found from all roots given explicitly.
    c = mechcirc.load(NETLISTS / "stb_heald.mcir")
    omega = np.geomspace(10, 10000, 400)
    s = c.sweep(omega)
    from mechcirc._sweep import peak

    fast = peak(s)
    full = peak(s, resonances=c.resonances(omega_max=omega[-1] * (1 + 1e-9)))
    assert repr(fast) == repr(full)


def test_a_resonance_and_an_antiresonance_one_rounding_apart_sort_as_a_tie():
    """ω equal to 1e-14 (one rounding of a shared ω: the batched path's roots may differ
    from the single path's in the last bit) sort as a tie, the anti-resonance first; a
    real gap, or NaN and inf slots, keep their order."""
    import numpy as np

    from mechcirc.resonances import tie_order

    w = 14.142135623730951
    pole = np.array([[False, True, False, True], [False, True, True, False],
                     [False, True, False, False]])
    mag = np.array([[w * (1 - 2e-16), w, 2 * w, 2 * w * (1 + 1e-12)],
                    [1.0, 1.0, 1.0, np.nan], [np.inf, np.inf, np.nan, np.nan]])
    assert tie_order(pole, mag).tolist() == [[1, 0, 2, 3], [1, 2, 0, 3], [0, 1, 2, 3]]


@pytest.mark.parametrize("kind, hint", [("resonanse", "; did you mean 'resonance'?"),
                                        ("anti", "; did you mean 'antiresonance'?"),
                                        ("zzz", "")])
def test_an_unknown_kind_names_the_nearest(kind, hint):
    c = mechcirc.load(NETLISTS / "stb_heald.mcir")
    with pytest.raises(InputError) as got:
        c.resonances(kind=kind)
    assert str(got.value) == ("kind must be 'resonance', 'antiresonance' or None, got "
                              f"{kind!r}{hint}")
