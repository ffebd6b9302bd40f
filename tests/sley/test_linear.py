"""mechcirc.sley.linear: the sley's circuit built as objects (issue 15 §3).

The reference is the netlist text ``to_netlist`` wrote before the circuit was
built as objects (frozen below, verbatim but for the function name), parsed by
the netlist parser: the built circuit must be that circuit, element by element,
and give the same K(ω).
"""

import math

import numpy as np
import pytest

import mechcirc
from mechcirc.sley import ParameterError, preset, to_circuit, to_netlist

OMEGA = np.geomspace(1.0, 1e5, 400)


def _old_netlist_text(p, theta0, *, lever=False, damping=True, velocity=None):
    """The text of ``to_netlist`` as of commit 9e37876 (before ``to_circuit``)."""
    mu = float(p.fourbar().transfer(float(theta0))[1])
    mu2 = mu * mu
    v = p.omega if velocity is None else velocity
    lines = [f"# Mrázek sley ({p.drive}), linearised at crank angle "
             f"{math.degrees(theta0):.6g} deg; mu = {mu!r}",
             f".param mu={mu!r} r={abs(mu)!r}   # mu(theta0) and the lever ratio |mu|",
             f"drive V shaft 0 velocity={v!r}",
             f"spring C2 shaft crank {p.C2!r}"]
    if damping and p.k2 > 0:
        lines.append(f"damper k2 shaft crank {p.k2!r}")
    lines.append(f"mass J2 crank 0 {p.I2P + p.I4 * mu2!r}")

    def rocker_side(crank, rocker, c, k, tag):
        out = []
        if lever:
            out.append(f"lever L{tag} {crank} 0 {rocker} 0 ratio=r")
            eta = ""
        else:
            eta = " eta={mu^2}"
            rocker = crank
        out.append(f"spring C{tag} {rocker} sley {c!r}{eta}")
        if damping and k > 0:
            out.append(f"damper k{tag} {rocker} sley {k!r}{eta}")
        return out

    lines += rocker_side("crank", "rocker", p.C4, p.k4, "4")
    if p.drive == "both-sides":
        lines.append(f"spring C5 shaft crank5 {p.C5!r}")
        if damping and p.k5 > 0:
            lines.append(f"damper k5 shaft crank5 {p.k5!r}")
        lines.append(f"mass J5 crank5 0 {p.I5P + p.I7 * mu2!r}")
        lines += rocker_side("crank5", "rocker7", p.C7, p.k7, "7")
    eta = "" if lever else " eta={mu^2}"
    lines.append(f"mass I4P sley 0 {p.I4P!r}{eta}")
    return "\n".join(lines) + "\n"


def _fields(x):
    """Everything but where it was written (line, column)."""
    return {k: v for k, v in vars(x).items() if k not in ("line", "col")}


CASES = [(drive, variant, theta0, lever, damping)
         for drive in ("one-side", "both-sides")
         for variant in (1, 3, 7)
         for theta0 in (0.3, 2.0, 4.0)
         for lever in (False, True)
         for damping in (False, True)]


@pytest.mark.parametrize("drive,variant,theta0,lever,damping", CASES)
def test_built_circuit_is_the_old_parsed_netlist(drive, variant, theta0, lever, damping):
    p = preset(drive, variant)
    built = to_circuit(p, theta0, lever=lever, damping=damping)
    old = mechcirc.parse(_old_netlist_text(p, theta0, lever=lever, damping=damping))
    assert [_fields(e) for e in built.elements] == [_fields(e) for e in old.elements]
    assert [_fields(lv) for lv in built.levers] == [_fields(lv) for lv in old.levers]
    # the old text wrote the shaft's speed without its unit (read as m/s); the shaft turns
    assert _fields(built.drive) == {**_fields(old.drive), "rotational": True}
    assert built.initial == old.initial == ()
    # the same circuit gives the same K; both go through the same solver, so
    # equal inputs must give equal outputs to the last bits
    k_built, k_old = built.sweep(OMEGA).K, old.sweep(OMEGA).K
    np.testing.assert_allclose(k_built, k_old, rtol=1e-14, atol=0)


@pytest.mark.parametrize("drive", ["one-side", "both-sides"])
@pytest.mark.parametrize("lever", [False, True])
def test_netlist_text_reads_back_as_the_built_circuit(drive, lever):
    p = preset(drive, 3)
    built = to_circuit(p, 1.0, lever=lever, velocity=2.5)
    text = to_netlist(p, 1.0, lever=lever, velocity=2.5)
    back = mechcirc.parse(text)
    assert [_fields(e) for e in back.elements] == [_fields(e) for e in built.elements]
    assert [_fields(lv) for lv in back.levers] == [_fields(lv) for lv in built.levers]
    assert _fields(back.drive) == _fields(built.drive)
    mu = p.fourbar().transfer(1.0)[1]
    assert f"mu = {mu!r}" in text.splitlines()[0]


def test_reflection_by_hand():
    # the rocker side seen from the crank: C4·μ², k4·μ², I4P·μ² (one side, damped)
    p = preset("one-side", 3)
    mu = float(p.fourbar().transfer(2.0)[1])
    c = to_circuit(p, 2.0)
    got = {e.name: (e.kind, e.n1, e.n2, e.value * e.eta) for e in c.elements}
    assert got == {"C2": ("spring", "shaft", "crank", p.C2),
                   "k2": ("damper", "shaft", "crank", p.k2),
                   "J2": ("mass", "crank", "0", p.I2P + p.I4 * mu * mu),
                   "C4": ("spring", "crank", "sley", p.C4 * (mu * mu)),
                   "k4": ("damper", "crank", "sley", p.k4 * (mu * mu)),
                   "I4P": ("mass", "sley", "0", p.I4P * (mu * mu))}
    assert (c.drive.kind, c.drive.amplitude) == ("velocity", p.omega)
    # the shaft turns: rad/s, N·m, rad/(N·m·s) in every label, and so reads its netlist back
    assert c.drive.rotational and mechcirc.parse(to_netlist(p, 2.0)).drive.rotational


def test_dead_centre_is_refused():
    p = preset("one-side", 3)
    from scipy.optimize import brentq

    theta = brentq(lambda t: p.fourbar().transfer(t)[1], 0.0, math.pi) \
        if p.fourbar().transfer(0.0)[1] * p.fourbar().transfer(math.pi)[1] < 0 else None
    if theta is None:
        pytest.skip("no sign change of μ on [0, π] for this preset")
    for f in (to_circuit, to_netlist):
        with pytest.raises(ParameterError, match="dead centre"):
            f(p, theta)
