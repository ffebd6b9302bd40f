"""Whether two checkouts' compiled plans give the same bits: K, its error bound and the flags.

For a change to the compiled series–parallel kernel (``mechcirc/_sp_kernel.py``)
meant to leave every number as it was.  Each checkout runs in a fresh process
(``mechcirc._jit.COMPILED`` True) over a fixed corpus: 150 random trees each
lossless, damped and fully damped (1–60 leaves, ``tests/reference/sp_corpus.py``),
30 more whose sums have magnitudes 1e±170 … 1e±200 (every leaf value scaled), the
two ladders of ``bench_work_precision.py`` (45 and 999 elements) and
``netlists/stb_heald.mcir``; at ω = 0, ∞, 1e-200, 1e200 and 200 points from 1e-3
to 1e3: K alone, K with its bound, and the flags of a sweep (at the finite ω > 0).
It prints how many arrays differ (bit for bit), and which.  Run from the
repository root::

    python benchmarks/check_sp_bits.py --compare /path/to/other/checkout
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

DUMP = r"""
import sys
import numpy as np
sys.path[:0] = [TREE, ROOT + "/tests", ROOT + "/benchmarks"]
import mechcirc
from mechcirc import _jit, reduction
from reference import sp_corpus as corpus
from bench_work_precision import ladder, ladder_netlist
_jit.COMPILED = True

def scaled(e, s):
    if e[0] == "leaf":
        return ("leaf", e[1], e[2] / s)
    if e[0] == "lever":
        return ("lever", e[1], scaled(e[2], s))
    return (e[0], [scaled(c, s) for c in e[1]])

rng = np.random.default_rng(20261127)
circuits = []
for kind, damped in (("lossless", 0.0), ("damped", 0.2), ("fully", 1.0)):
    for i in range(150):
        e = corpus.random_tree(rng, int(rng.integers(1, 61)), damped=damped)
        circuits.append((f"{kind}{i}", corpus.to_circuit(e)))
for i in range(30):
    s = 10.0 ** (rng.choice([-1, 1]) * rng.uniform(170, 200))
    e = corpus.random_tree(rng, int(rng.integers(1, 61)), damped=(0.0, 0.2, 1.0)[i % 3])
    circuits.append((f"huge{i}", corpus.to_circuit(scaled(e, s))))
for n in (45, 999):
    circuits.append((f"ladder{n}", mechcirc.parse(ladder_netlist(*ladder(n)))))
circuits.append(("stb_heald", mechcirc.load(ROOT + "/netlists/stb_heald.mcir")))
grids = {"grid": np.geomspace(1e-3, 1e3, 200), "special": np.array([0.0, np.inf, 1e-200, 1e200])}
out = {}
for name, c in circuits:
    for g, w in grids.items():
        out[f"{name}/{g}/K"] = reduction.evaluate(c.tree, w)
        out[f"{name}/{g}/Kb"], out[f"{name}/{g}/bound"] = reduction.evaluate(c.tree, w, error=True)
        out[f"{name}/{g}/flags"] = mechcirc.sweep(c, w[np.isfinite(w) & (w > 0)]).flags
np.savez(sys.argv[1], **out)
"""


def dump(tree: Path, path: Path) -> None:
    """Run the corpus with the mechcirc of ``tree`` into ``path`` (.npz)."""
    src = DUMP.replace("TREE", repr(str(tree))).replace("ROOT", repr(str(ROOT)))
    env = dict(os.environ, PYTHONPATH=str(tree), MECHCIRC_NO_WARM="1")
    done = subprocess.run([sys.executable, "-c", src, str(path)], cwd=tree, env=env,
                          capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(done.stderr[-2000:])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--compare", metavar="DIR", required=True, help="the other checkout")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        here, there = Path(tmp, "here.npz"), Path(tmp, "there.npz")
        dump(ROOT, here)
        dump(Path(args.compare).resolve(), there)
        a, b = np.load(here), np.load(there)
        if sorted(a.files) != sorted(b.files):
            print("the two checkouts dumped different arrays")
            return 1
        differ = [k for k in a.files
                  if a[k].dtype != b[k].dtype or a[k].tobytes() != b[k].tobytes()]
    print(f"{len(a.files)} arrays compared, {len(differ)} differ"
          + (": " + ", ".join(differ[:20]) if differ else ""))
    return 1 if differ else 0


if __name__ == "__main__":
    raise SystemExit(main())
