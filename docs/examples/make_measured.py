"""Write docs/examples/measured.s1p: the "measurement" of docs/ecosystem.md.

The STB heald netlist with k4 = 1.8e6 N/m instead of 2e6, 200 log-spaced
points from 10 to 3000 rad/s, 2 % complex noise (seeded), written by
scikit-rf as S parameters on a 50 reference.  Run from the repository root:
``python docs/examples/make_measured.py``.
"""

from pathlib import Path

import numpy as np
import skrf

import mechcirc

here = Path(__file__).resolve().parent
root = here.parents[1]
text = (root / "netlists" / "stb_heald.mcir").read_text()
text = text.replace("spring k4  D  0  2.0e6", "spring k4  D  0  1.8e6")
assert "1.8e6" in text
circuit = mechcirc.parse(text, source="stb_heald_k4.mcir")
omega = np.geomspace(10, 3000, 200)
rng = np.random.default_rng(7)
K = circuit.sweep(omega).K * (1 + 0.02 * (rng.standard_normal(200) + 1j * rng.standard_normal(200)) / np.sqrt(2))
freq = skrf.Frequency.from_f(omega / (2 * np.pi), unit="Hz")
net = skrf.Network(frequency=freq, z=K.reshape(-1, 1, 1), z0=50, name="measured")
net.write_touchstone(str(here / "measured"), form="ri")
print("wrote", here / "measured.s1p")
