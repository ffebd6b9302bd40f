"""Public functions refuse what is not meant (audit18): ``resonance_pairs`` and
``find_resonances`` take ``omega_max`` as a real number > 0 or None; a bool is no number
(``True`` was read as 1 rad/s, an empty answer with no word of why); ``periodic`` takes
``rpm`` likewise (``True`` ran at 1 rev/min)."""


import numpy as np
import pytest

import mechcirc
from mechcirc.errors import InputError
from mechcirc.resonances import find_resonances, resonance_pairs
from reference.inputs import STB



@pytest.mark.parametrize("bad", [True, False, np.bool_(True)])
@pytest.mark.parametrize("function", [resonance_pairs, find_resonances])
def test_omega_max_bool_refused(function, bad):
    with pytest.raises(InputError, match=r"omega_max must be > 0 rad/s or None, got "):
        function(mechcirc.load(STB), bad)


def test_omega_max_numpy_numbers_still_taken():
    c = mechcirc.load(STB)
    want = [r.omega for r in find_resonances(c, 2000.0)]
    assert len(want) >= 2
    for value in (np.int64(2000), np.float32(2000.0), 2000):
        assert [r.omega for r in find_resonances(c, value)] == want


@pytest.mark.parametrize("bad", [True, np.bool_(True)])
def test_periodic_rpm_bool_refused(bad):
    """``periodic(c, rpm=True)`` ran at 1 rev/min; a speed is a number, not a flag."""
    from mechcirc.errors import MechcircError
    from mechcirc.periodic import periodic

    with pytest.raises(MechcircError, match=r"machine speed must be a finite number > 0"):
        periodic(mechcirc.load(STB), bad)
