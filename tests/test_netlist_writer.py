"""mechcirc.netlist_writer.write: parse(write(c)) is c, for shipped netlists and generated circuits."""

from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mechcirc import load, parse
from mechcirc.circuit import Circuit, Drive, Element, Lever, units_of
from mechcirc.errors import NetlistError
from mechcirc.netlist_writer import write

ROOT = Path(__file__).resolve().parent.parent


def _shipped():
    out = []
    for folder in ("netlists", "examples", "docs/examples"):
        for path in sorted((ROOT / folder).glob("*.mcir")):
            try:
                load(path)
            except NetlistError:
                continue         # the docs ship some broken netlists on purpose
            out.append(path)
    return out


def _unlocated(c: Circuit):
    """What text carries: everything but line/col, the name, the source and the .params."""
    return (tuple(replace(e, line=0, col=0) for e in c.elements),
            None if c.drive is None else replace(c.drive, line=0, col=0),
            tuple(replace(lv, line=0, col=0) for lv in c.levers),
            tuple(c.initial))


SHIPPED = _shipped()


def test_the_shipped_netlists_are_found():
    names = {p.name for p in SHIPPED}
    assert {"stb_heald.mcir", "msl_backlash.mcir"} <= names


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_shipped_netlist_round_trips(path):
    c = load(path)
    text = write(c, header=("written by the test", "two lines"))
    back = parse(text, source=str(path))
    assert _unlocated(back) == _unlocated(c)
    assert back.name == c.name
    assert write(back, header=("written by the test", "two lines")) == text


# ----------------------------------------------------------------- generated circuits
_name_text = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,6}|[1-9][0-9]{0,3}", fullmatch=True,
                           alphabet="ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_")
# alphabet= holds every character the pattern can match, so the names are the same set;
# without it hypothesis first maps every Unicode code point through the utf-8 codec
# (about 0.8 s of CPU in each process whose .hypothesis folder lacks that table: a fresh
# clone, as in CI).
# The same strategy behind deferred(): fresh() below filters it once per name, and a
# filter of from_regex(...) itself would rebuild the regex strategy every time (that
# rebuilding was most of this file's CPU); the names drawn are the same.
_names = st.deferred(lambda: _name_text)
_positive = st.floats(min_value=5e-324, max_value=1.7976931348623157e308,
                      allow_nan=False, allow_infinity=False)
_finite = st.floats(allow_nan=False, allow_infinity=False)


@st.composite
def circuits(draw):
    nodes = draw(st.lists(_names, min_size=2, max_size=6, unique=True))
    nodes = ["0"] + [n for n in nodes if n != "0"]
    used: set[str] = set()

    def fresh():
        n = draw(_names.filter(lambda s: s not in used and s + "_damping" not in used))
        used.add(n)
        return n

    def pair():
        a, b = draw(st.lists(st.sampled_from(nodes), min_size=2, max_size=2, unique=True))
        return a, b

    elements = []
    for _ in range(draw(st.integers(1, 8))):
        kind = draw(st.sampled_from(["mass", "spring", "damper"]))
        name = fresh()
        n1, n2 = pair()
        eta = draw(st.one_of(st.just(1.0), _positive))
        e = Element(kind, name, n1, n2, draw(_positive), eta)
        if kind == "spring":
            e = replace(e, backlash=draw(st.one_of(st.just(0.0), _positive)))
            damping = draw(st.one_of(st.just(0.0), _positive))
            if damping and name + "_damping" not in used:
                used.add(name + "_damping")
                elements += [e, Element("damper", name + "_damping", n1, n2, damping, eta)]
                continue
        elements.append(e)
    levers = []
    for _ in range(draw(st.integers(0, 2))):
        p1, p2 = pair()
        s1, s2 = pair()
        levers.append(Lever(fresh(), p1, p2, s1, s2, draw(_positive)))
    a, b = pair()
    drive = Drive(fresh(), a, b, draw(st.sampled_from(["velocity", "force"])), draw(_finite))
    ic_nodes = draw(st.lists(st.sampled_from(nodes[1:]), unique=True, max_size=3))
    known = {n for e in elements for n in (e.n1, e.n2)} | \
        {n for lv in levers for n in (lv.p1, lv.p2, lv.s1, lv.s2)} | {drive.n1, drive.n2}
    initial = tuple((n, draw(_finite), draw(_finite)) for n in ic_nodes if n in known)
    return Circuit(tuple(elements), drive, tuple(levers), initial=initial)


@settings(max_examples=50, deadline=None)
@given(c=circuits())
def test_generated_circuit_round_trips(c):
    assert _unlocated(parse(write(c))) == _unlocated(c)


def test_free_vibration_circuit_without_drive_round_trips():
    c = parse("mass m a 0 2\nspring k a 0 5\n.ic a x=0.1\n", require_drive=False)
    text = write(c)
    assert not text.startswith("drive")
    assert _unlocated(parse(text, require_drive=False)) == _unlocated(c)


def test_header_lines_are_comments():
    c = parse("drive V a 0 velocity=1\nmass m a 0 2\n")
    text = write(c, header="first\nsecond")
    assert text.splitlines()[:2] == ["# first", "# second"]
    assert _unlocated(parse(text)) == _unlocated(c)


@pytest.mark.parametrize("bad, match", [
    (Element("mass", "a b", "1", "0", 1.0), "not a name"),
    (Element("mass", "m", "007", "0", 1.0), "not a name"),
    (Element("mass", "m", "1", "0", float("inf")), "not a finite number"),
])
def test_what_text_cannot_hold_is_refused(bad, match):
    c = Circuit((bad,), Drive("V", "1", "0", "velocity", 1.0))
    with pytest.raises(ValueError, match=match):
        write(c)


def test_a_springs_damping_is_stored_once_in_its_damper():
    # damping=3 is the damper k_damping and nothing else: editing that damper is
    # editing the spring's damping, for the analyses and for the text alike
    c = parse("drive V 1 0 velocity=1\nspring k 1 0 3 damping=3\n")
    assert not hasattr(c.element("k"), "damping")
    edited = replace(c, elements=(c.elements[0],
                                              replace(c.elements[1], value=30.0)))
    assert "damping=30.0" in write(edited)
    assert parse(write(edited)).element("k_damping").value == 30.0
    assert edited.sweep([1.0]).K[0] == pytest.approx(1 / (30 - 3j))
    # a damper of that name away from its spring is an ordinary damper
    moved = replace(c, elements=c.elements[::-1])
    assert "damping=" not in write(moved)
    assert [(e.kind, e.name, e.value) for e in parse(write(moved)).elements] == \
        [("damper", "k_damping", 3.0), ("spring", "k", 3.0)]


def test_comments_follow_their_lines_and_read_back():
    from mechcirc import parse
    from mechcirc.netlist_writer import write

    c = parse("drive V a 0 velocity=1\nmass m a 0 2\nspring k a b 800\n"
              "lever L b 0 c 0 ratio=2\ndamper d c 0 3\n")
    text = write(c, "head", comments={"V": "[m/s]", "k": "ratio = 0.5\nsecond line",
                                      "L": "a lever", "nobody": "ignored"})
    lines = text.splitlines()
    assert lines[0] == "# head"
    assert lines[1] == "drive V a 0 velocity=1.0   ; [m/s]"
    assert "spring k a b 800.0   ; ratio = 0.5 second line" in lines
    assert "lever L b 0 c 0 ratio=2.0   ; a lever" in lines
    assert "mass m a 0 2.0" in lines and "ignored" not in text
    back = parse(text)
    assert [(e.kind, e.name, e.n1, e.n2, e.value, e.eta) for e in back.elements] == \
        [(e.kind, e.name, e.n1, e.n2, e.value, e.eta) for e in c.elements]
    assert back.levers[0].ratio == 2.0 and back.drive.amplitude == 1.0


@pytest.mark.parametrize("drive", ["velocity=2.5 rad/s", "force=3 N*m"])
def test_rotary_drive_reads_back_rotary(drive):
    """The drive's unit is written: element values carry none, so without it a rotary
    drive would read back as translational (m/s, N)."""
    c = parse(f"drive W p 0 {drive}\nmass J p 0 0.2 kg*m^2\nspring k p 0 5e3 N*m/rad\n")
    assert c.drive.rotational
    back = parse(write(c))
    assert back.drive.rotational and back.drive.amplitude == c.drive.amplitude
    assert units_of(back.drive) == units_of(c.drive)
    plain = parse("drive V a 0 velocity=2.5\nmass m a 0 1\n")
    assert not parse(write(plain)).drive.rotational


def test_rotary_motion_table_reads_back_rotary(tmp_path):
    """A table has no stroke to carry the unit: ``motion=PATH rad`` says the displacements
    are angles; the writer adds it for a rotary drive whose elements carry no units."""
    table = tmp_path / "lift.csv"
    table.write_text("angle_deg,displacement\n0,0\n90,0.05\n180,0.1\n270,0.05\n360,0\n")
    rotary = parse(f"drive W p 0 motion={table} rad\nmass J p 0 0.2\nspring k p 0 5e3\n")
    by_nodes = parse(f"drive W p 0 motion={table}\nmass J p 0 0.2 kg*m^2\nspring k p 0 5e3 N*m/rad\n")
    for c in (rotary, by_nodes):
        assert c.drive.rotational
        text = write(c)
        assert text.splitlines()[0] == f"drive W p 0 motion={table} rad"
        back = parse(text)
        assert back.drive.rotational and back.drive.motion == c.drive.motion
    plain = parse(f"drive V a 0 motion={table} m\nmass m a 0 1\n")
    assert not plain.drive.rotational and not parse(write(plain)).drive.rotational
    assert write(plain).splitlines()[0] == f"drive V a 0 motion={table}"
    for unit, why in (("mm", "would scale them"), ("deg", "would scale them"),
                      ("kg", "needs length or angle")):
        with pytest.raises(NetlistError, match=why) as exc:
            parse(f"drive V a 0 motion={table} {unit}\nmass m a 0 1\n")
        assert exc.value.col == len(f"drive V a 0 motion={table} ") + 1
