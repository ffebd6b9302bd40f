"""Bad scene input (issue 7 §5): each a clear error, located where a line is to blame."""

import math
from pathlib import Path

import pytest

import _scene_helpers as helpers
from mechcirc.errors import GeometryError, NetlistError
from mechcirc.kinematics.fourbar import FourBar
from mechcirc.scene import build, parse_scene

BASE = '''units = "m"
[points]
O1 = [0.0, 0.0]
A  = [0.1, 0.25]
B  = [0.55, 0.3]
O2 = [0.6, 0.0]
C  = [0.9, 0.2]
[ground]
points = ["O1", "O2"]
[links]
lever1 = ["O1", "A"]
rod = ["A", "B"]
lever2 = ["O2", "B", "C"]
[[cranks]]
link = "lever1"
omega = 5.0
[[elastic]]
link = "rod"
stiffness = 3.0e5
[[masses]]
point = "C"
mass = 4.0
[drive]
link = "lever1"
velocity = 1.0
'''


def _where(text, needle):
    """1-based (line, col) of ``needle`` in ``text``, found by the test itself."""
    for n, line in enumerate(text.splitlines(), start=1):
        if needle in line:
            return n, line.index(needle) + 1
    raise AssertionError(needle)


def test_the_base_scene_is_valid():
    assert build(parse_scene(BASE), 0.1).circuit.resonances()


def test_mass_at_a_point_that_does_not_exist():
    text = BASE.replace('point = "C"', 'point = "Q"')
    with pytest.raises(NetlistError) as e:
        parse_scene(text, "s.toml")
    assert "'Q' does not exist" in e.value.message
    assert (e.value.line, e.value.col) == _where(text, '"Q"')
    assert str(e.value).startswith(f"s.toml:{e.value.line}:")


def test_elastic_link_not_in_the_linkage():
    text = BASE.replace('link = "rod"', 'link = "rod9"')
    with pytest.raises(NetlistError) as e:
        parse_scene(text)
    assert "elastic link 'rod9' is not in the linkage" in e.value.message
    assert e.value.line == _where(text, 'link = "rod9"')[0]
    assert "rod" in e.value.expected


def test_crank_angle_where_the_mechanism_cannot_be_assembled():
    # a non-Grashof four-bar: the input link rocks, it cannot reach 180° from the pose
    fb = FourBar(60.0, 50.0, 70.0, 65.0)
    assert not fb.crank_rotates_fully
    P = helpers.fourbar_pose(fb, math.radians(80.0))
    pts = "\n".join(f"{k} = [{x!r}, {y!r}]" for k, (x, y) in P.items())
    scene = parse_scene(f'''units = "mm"
[points]
{pts}
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 1.0
[[masses]]
link = "rocker"
inertia = 1.0
[drive]
link = "crank"
velocity = 1.0
''')
    build(scene, 0.2)
    with pytest.raises(GeometryError, match=r"cannot be assembled .* infinite"):
        build(scene, math.pi)


def test_dead_centre_names_the_singular_ratio():
    from mechcirc.sley import preset

    p = preset("one-side", 1)
    theta_pose = 0.3
    scene = parse_scene(helpers.sley_scene_text(p, theta_pose))
    for dc in p.fourbar().dead_centres():
        with pytest.raises(GeometryError) as e:
            build(scene, dc.theta - theta_pose)
        msg = str(e.value)
        assert "dead centre" in msg and "{sley}" in msg and "ω_sley/ω_crank" in msg
    build(scene, p.fourbar().dead_centres()[0].theta - theta_pose + 0.01)   # just beside it


def test_point_drive_at_rest_is_a_dead_centre_of_the_drive():
    fb = FourBar(29.0, 37.0, 188.0, 189.0)
    P = helpers.fourbar_pose(fb, 0.0)
    pts = "\n".join(f"{k} = [{x!r}, {y!r}]" for k, (x, y) in P.items())
    scene = parse_scene(f'''units = "mm"
[points]
{pts}
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 1.0
[[masses]]
point = "B"
mass = 1.0
[drive]
point = "C"
force = 1.0
''')
    with pytest.raises(GeometryError, match=r"drive is at a dead centre: the velocity ratio "
                                            r"\|v_C\|/ω_crank"):
        build(scene, fb.dead_centres()[1].theta)


@pytest.mark.parametrize("old,new,needle,match", [
    ('units = "m"\n', '', None, "needs units"),
    ('units = "m"', 'units = "furlong"', 'units', "needs units"),
    ('stiffness = 3.0e5', 'stiffness = -3.0e5', 'stiffness', "must be a finite number > 0"),
    ('[drive]\n', '[drive]\nlinkk = "x"\n', 'linkk', "unknown key 'linkk'"),
    ('velocity = 1.0', 'velocity = 1.0\nforce = 2.0', 'force', "exactly one of velocity"),
    ('mass = 4.0', 'inertia = 4.0', 'inertia = 4.0', "takes mass = … \\[kg\\], not inertia"),
    ('[[masses]]\npoint = "C"', '[[masses]]\nlink = "rod"  # here', 'link = "rod"  # here',
     "elastic link has no"),
    ('omega = 5.0\n', 'omega = 5.0\n[bogus]\nx = 1\n', 'bogus', "unknown top-level key"),
])
def test_bad_values_are_located(old, new, needle, match):
    text = BASE.replace(old, new, 1)
    assert text != BASE
    with pytest.raises(NetlistError, match=match) as e:
        parse_scene(text)
    if needle is not None:
        assert e.value.line == _where(text, needle)[0]


def test_toml_syntax_error_is_located():
    text = BASE.replace("mass = 4.0", "mass = = 4.0")
    with pytest.raises(NetlistError, match="TOML syntax") as e:
        parse_scene(text)
    assert e.value.line == _where(text, "mass = =")[0]


def test_elastic_link_pinned_to_the_frame_leaves_a_two_dof_part():
    text = BASE.replace('rod = ["A", "B"]', 'rod = ["A", "B"]\nlever2b = ["O2", "B"]') \
        .replace('lever2 = ["O2", "B", "C"]', 'lever2 = ["B", "C"]\nlink3 = ["C", "O3"]') \
        .replace('points = ["O1", "O2"]', 'points = ["O1", "O2", "O3"]') \
        .replace('C  = [0.9, 0.2]', 'C  = [0.9, 0.2]\nO3 = [1.0, -0.3]') \
        .replace('link = "rod"', 'link = "lever2b"')
    with pytest.raises(GeometryError, match=r"W = 3·3 − 2·4 = 1|degrees of freedom"):
        parse_scene(text)


def test_ternary_link_cannot_be_an_axial_spring():
    text = BASE.replace('link = "rod"', 'link = "lever2"')
    with pytest.raises(NetlistError, match="only a binary link"):
        parse_scene(text)


def test_duplicate_element_names():
    text = BASE.replace('[[masses]]\npoint = "C"', '[[masses]]\nname = "rod"\npoint = "C"')
    with pytest.raises(NetlistError, match="'rod' is already used") as e:
        parse_scene(text)
    assert e.value.line == _where(text, 'name = "rod"')[0]


@pytest.mark.parametrize("table,needle,match", [
    ("[analysis]\nband = [480.0, 30.0]\ntol = 0.01\n", "band", "not below"),
    ("[analysis]\nband = [0.0, 30.0]\ntol = 0.01\n", "band", "must be > 0"),
    ("[analysis]\nband = [30.0]\ntol = 0.01\n", "band", r"band must be \[W1, W2\]"),
    ("[analysis]\nband = [30.0, 300.0]\n", "band", "band and tol together"),
    ("[analysis]\noutput = \"k9\"\n", "output", "not an element"),
    ("[analysis]\ntol = -1.0\nband = [1.0, 2.0]\n", "tol", "must be a finite number > 0"),
    ("[analysis]\nthetadeg = 3.0\n", "thetadeg", "unknown key"),
])
def test_analysis_table_errors_are_located(table, needle, match):
    text = BASE + table
    with pytest.raises(NetlistError, match=match) as e:
        parse_scene(text)
    assert e.value.line == _where(text, needle + " =")[0]


def test_damper_name_clash_is_refused():
    text = BASE.replace("stiffness = 3.0e5", "stiffness = 3.0e5\ndamping = 2.0") \
        .replace('[[masses]]\npoint = "C"', '[[masses]]\nname = "rod_d"\npoint = "C"')
    with pytest.raises(NetlistError, match="'rod_d' in the circuit, but that name is taken") as e:
        parse_scene(text)
    assert e.value.line == _where(text, '"rod_d"')[0]


def test_cycle_of_a_crank_that_cannot_turn_fully():
    from mechcirc.scene.cycle import cycle_map

    fb = FourBar(60.0, 50.0, 70.0, 65.0)
    P = helpers.fourbar_pose(fb, math.radians(80.0))
    pts = "\n".join(f"{k} = [{x!r}, {y!r}]" for k, (x, y) in P.items())
    scene = parse_scene(f'''units = "mm"
[points]
{pts}
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 1.0
[[masses]]
link = "rocker"
inertia = 1.0
[drive]
link = "crank"
velocity = 1.0
''')
    with pytest.raises(GeometryError, match="cannot make a full revolution.*locks near"):
        cycle_map(scene, points=8)


FNF = (Path(__file__).resolve().parents[2] / "examples" / "fnf_sixbar_scene.toml").read_text(
    encoding="utf-8")
KLOSS = ('motor = "kloss"       # an induction motor, referred to crank 1\'s shaft\n'
         'sync_speed = 21.0     # [rad/s]\nbreakdown_torque = 2.0\nbreakdown_slip = 0.2\n')
MOMENT = '[[moments]]\nbody = "organ"\namplitude = 5.0\nwindow_deg = 30.0\n'
ALIASES = ('[simulate.aliases]\neps_organ = "organ.acceleration"\n'
           'eps_organ_rigid = "output6.rigid_acceleration"\nM1 = "C1.force"\n')
TABLE_MOTOR = 'motor = "table"\nspeeds = [0.0, 25.0]\ntorques = [2.0, 0.0]\n'


@pytest.mark.parametrize("old, new, needle, fragments", [
    ('units = "mm"', 'units = "mm"\nmoments = 3', "moments = 3",
     ["moments must be an array of tables [[moments]]"]),
    ("[drive]", MOMENT + 'name = "J1"  # taken\n[drive]', 'name = "J1"  # taken',
     ["[[moments]] #1: name 'J1' is not a valid unused name", "(expected an identifier"]),
    ("[drive]", MOMENT.replace("30.0", "400.0") + "[drive]", "window_deg = 400",
     ["window_deg of 'M_organ' must be < 360, got 400.0", "(expected 0 < window_deg < 360)"]),
    ("[drive]", MOMENT + 'centre = "middle"\n[drive]', 'centre = "middle"',
     ["centre 'middle' of 'M_organ' is unknown", '(expected "front-dead-centre"']),
    ('M1 = "C1.force"', 'M1 = "C1force"', "M1 =",
     ["[simulate.aliases] maps names to \"THING.quantity\" strings, got M1 = 'C1force'",
      '(expected eps2P = "crank.acceleration")']),
    (ALIASES, "aliases = 3\n", "aliases = 3",
     ["[simulate] aliases must be a table [simulate.aliases]"]),
    ("revolutions = 4 ", "revolutions = 0 ", "revolutions = 0",
     ["[simulate] revolutions must be an integer ≥ 1, got 0"]),
    ("revolutions = 4 ", "points = 8\nrevolutions = 4 ", "points = 8",
     ["[simulate] points must be an integer ≥ 16, got 8"]),
    ("revolutions = 4 ", "omega = -1.0\nrevolutions = 4 ", "omega = -1.0",
     ["[simulate] omega must be a finite number > 0, got -1.0"]),
    # (session 28: it was simulated at +20, the rod forces up to 20 % off a clockwise run)
    ("omega = 20.0", "omega = -20.0", "omega = -20.0",
     ["the first crank turns at omega = -20 rad/s; a scene's first crank turns the positive "
      "way", "mirror the points"]),
    (KLOSS, TABLE_MOTOR.replace("speeds = [0.0, 25.0]\n", ""), 'motor = "table"',
     ["[shaft] a motor table needs speeds = [...]", "(expected speeds = [[rad/s], increasing])"]),
    (KLOSS, TABLE_MOTOR.replace("[0.0, 25.0]", "[25.0, 0.0]"), 'motor = "table"',
     ["[shaft] the motor table's speeds must increase, got [25.0, 0.0]"]),
    ("breakdown_slip = 0.2", "", 'motor = "kloss"',
     ["[shaft] a Kloss motor needs breakdown_slip, or rated_power and rated_speed"]),
    ("breakdown_slip = 0.2", "breakdown_slip = -0.2", "breakdown_slip = -0.2",
     ["[shaft] breakdown_slip must be a finite number > 0, got -0.2"]),
])
def test_bad_moments_simulate_and_shaft_tables_exit_2_at_their_line(old, new, needle,
                                                                     fragments, tmp_path, capsys):
    """scene/simfile's refusals ([[moments]], [simulate], [shaft] motors) through the CLI:
    exit 2, one line 'file:line:col: error: …' at the offending key (the line found here),
    what is wrong and, where a form is expected, what would be right."""
    from cli_helpers import assert_user_error

    text = FNF.replace(old, new, 1)
    assert text != FNF
    f = tmp_path / "s.toml"
    f.write_text(text, encoding="utf-8")
    line, col = _where(text, needle)
    assert_user_error(["scene", f, "--theta", "40"], capsys, f"s.toml:{line}:{col}: error: ",
                      *fragments)


@pytest.mark.parametrize("text, needle, fragments", [
    (BASE.replace('units = "m"', 'units = "m"\nelastic = 3').replace(
        '[[elastic]]\nlink = "rod"\nstiffness = 3.0e5\n', ""), "elastic = 3",
     ["elastic must be an array of tables [[elastic]]"]),
    (BASE.replace('link = "rod"\nstiffness', 'link = "lever1"\nstiffness'), '"lever1"\nstiff',
     ["the crank 'lever1' cannot be an axial spring"]),
    (BASE.replace("[[masses]]", '[[elastic]]\nname = "rod2"\nlink = "rod"  # again\n'
                  "stiffness = 1.0\n[[masses]]"), '"rod"  # again',
     ["link 'rod' is declared elastic twice"]),
    (BASE.replace('[drive]\nlink = "lever1"', '[drive]\nlink = "rod"'), 'link = "rod"\nvel',
     ["[drive] link 'rod' is not a rigid link or torsion body", "(expected one of lever1, lever2)"]),
    (BASE.replace('[drive]\nlink = "lever1"', '[drive]\npoint = "Z"'), 'point = "Z"',
     ["[drive] point 'Z' does not exist in [points]", "(expected one of O1, A, B, O2, C)"]),
    (BASE.replace('[drive]\nlink = "lever1"', '[drive]\nlink = "lever1"\npoint = "C"'),
     'link = "lever1"\npoint', ["[drive] needs exactly one of link or point",
                                 '(expected link = "…" or point = "…")']),
    (BASE.replace("velocity = 1.0", 'velocity = 1.0\nname = "rod"'), 'name = "rod"',
     ["[drive] name 'rod' is not a valid unused element name"]),
    (BASE + '[[loads]]\npoint = "C"\nanchor = "A"\nstiffness = 10.0\n', '"A"\nstiff',
     ["load #1: anchor 'A' is not a ground point", "(expected one of O1, O2)"]),
    (BASE + '[[loads]]\npoint = "C"\ndirection = [0.0, 0.0]\nstiffness = 10.0\n', "direction",
     ["load #1: direction must be [dx, dy], not zero, got [0.0, 0.0]"]),
    (BASE + '[[loads]]\npoint = "C"  # free\ndirection = [0.0, 1.0]\n', 'point = "C"  # free',
     ["load 'load_C' needs stiffness > 0 or damping > 0"]),
    (BASE.replace("stiffness = 3.0e5", 'stiffness = 3.0e5\nclearance_law = "foo"'),
     "clearance_law", ["[[elastic]] #1: clearance_law 'foo' is unknown",
                       '(expected "elastobacklash" or "dead-zone")']),
    (FNF.replace('link = "crank1"\nbody = "shaft"', 'link = "crank1"\npivot = "A"\nbody = "shaft"'),
     'pivot = "A"', ["torsion rod #1 must sit at a ground pivot of link 'crank1' (its ground "
                     "pivots: ['O1'])", "(expected pivot = one of the link's ground pivots)"]),
    (FNF.replace('body = "shaft"', 'body = "crank2"'), 'body = "crank2"',
     ["torsion rod #1: body 'crank2' must be a new name"]),
    (FNF.replace("ratio = -1.5", "ratio = -2.5"), "ratio = -2.5",
     ["[[gears]] #1: crank 'crank2' has omega = -30 rad/s in [[cranks]] but the gear ratio "
      "-2.5 makes it -50 rad/s", "(expected ratio = -1.5, or omega = -50)"]),
    (FNF.replace('crank = "crank2"', 'crank = "crank1"'), '"crank1"\nratio',
     ["[[gears]] #1: crank 'crank1' is not a crank after the first", "(expected one of crank2)"]),
])
def test_bad_scene_tables_exit_2_at_their_line(text, needle, fragments, tmp_path, capsys):
    """scene/files' refusals ([[elastic]], [drive], [[loads]], [[torsion]], [[gears]])
    through the CLI: exit 2, one line at file:line:col of the offending value (its line
    found here from the text; a needle spanning two lines names the first), what is wrong
    and what is expected."""
    from cli_helpers import assert_user_error

    first = needle.split("\n")[0]
    line = next(n for n, ln in enumerate(text.splitlines(), 1)
                if first in ln and (needle == first or needle.split("\n")[1]
                                    in text.splitlines()[n]))
    f = tmp_path / "s.toml"
    f.write_text(text, encoding="utf-8")
    err = assert_user_error(["scene", f, "--theta", "40"], capsys, *fragments)
    assert f"s.toml:{line}:" in err and ": error: " in err, err
