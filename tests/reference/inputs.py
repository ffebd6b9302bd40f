"""The shipped inputs that several test files use, by path (independent of mechcirc)."""

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
#: The seed's STB heald mechanism (eq. 7; closed form in :mod:`reference.stb_eq7`).
STB = REPO / "netlists" / "stb_heald.mcir"
