"""The shipped inputs that several test files use, by path (independent of mechcirc)."""

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
#: The seed's STB heald mechanism (eq. 7; closed form in :mod:`reference.stb_eq7`).
STB = REPO / "netlists" / "stb_heald.mcir"

#: A crank–rocker four-bar in mm (crank 40, coupler 150, rocker 150 on a 200 base),
#: crank at 60 rad/s: the rigid part of the small scenes the scene tests add
#: masses and elastic links to (its closed form is written in each test).
FOURBAR_SCENE = """units = "mm"
[points]
A = [0.0, 0.0]
B = [40.0, 0.0]
C = [60.0, 150.0]
D = [200.0, 0.0]
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 60.0
"""
