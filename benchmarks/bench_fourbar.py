"""Benchmark: four-bar φ4, μ, ν and γ at 3,600 crank positions (issue 4 §1: ≤ 5 ms).

Times the vectorised closed form (``FourBar.evaluate``) against a baseline
measured in the same run: a per-point scalar loop over ``FourBar.transfer``
plus the transmission angle (plain ``math``, no numpy).  Also reports the cold
import time of ``mechcirc.kinematics`` (no compilation happens on import) and
checks that both paths agree.

Run:  python benchmarks/bench_fourbar.py
"""

from __future__ import annotations

import math
import platform
import subprocess
import sys
import time

import numpy as np
from timing import samples


def best_of(fn, repeat=50):
    """(least, median) wall seconds of ``repeat`` calls of ``fn()``."""
    times, _ = samples(fn, repeat, time.perf_counter)
    return min(times), float(np.median(times))


def main() -> None:
    cold = subprocess.run(
        [sys.executable, "-c",
         "import time; t = time.perf_counter(); import mechcirc.kinematics; "
         "print(time.perf_counter() - t)"], capture_output=True, text=True, check=True)
    import_s = float(cold.stdout)

    from mechcirc.kinematics import FourBar

    fb = FourBar(29.0, 37.0, 188.0, 189.0)           # Mrázek's beat-up drive [mm]
    theta = np.linspace(0.0, 2 * math.pi, 3600, endpoint=False)

    def vectorised():
        st = fb.evaluate(theta)
        return st.phi4, st.mu, st.nu, st.gamma

    th_list = theta.tolist()

    a, c, d = fb.crank, fb.rocker, fb.frame

    def scalar_loop():
        out = []
        for th in th_list:
            phi4, mu, nu = fb.transfer(th)
            # coupler angle (direction B→C) and γ in plain math, as transfer does
            phi3 = math.atan2(c * math.sin(phi4) - a * math.sin(th),
                              c * math.cos(phi4) + d - a * math.cos(th))
            out.append((phi4, mu, nu, math.atan2(abs(math.sin(phi4 - phi3)),
                                                 abs(math.cos(phi4 - phi3)))))
        return out

    v = vectorised()
    s = np.array(scalar_loop())
    err = max(float(np.max(np.abs(v[k] - s[:, k]))) for k in range(4))

    t_vec, m_vec = best_of(vectorised, 200)
    t_loop, m_loop = best_of(scalar_loop, 10)
    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")
    print(f"cold import of mechcirc.kinematics: {import_s * 1e3:.1f} ms")
    print(f"3600 positions, φ4 μ ν γ, vectorised closed form: best {t_vec * 1e3:.3f} ms "
          f"(median {m_vec * 1e3:.3f} ms)  goal ≤ 5 ms: {'met' if t_vec <= 5e-3 else 'MISSED'}")
    print(f"baseline, per-point scalar loop:                 best {t_loop * 1e3:.1f} ms "
          f"(median {m_loop * 1e3:.1f} ms)")
    print(f"speed-up vectorised / loop: {t_loop / t_vec:.0f}×; max |difference| {err:.1e}")
    t_one, _ = best_of(lambda: fb.transfer(1.234), 20000)
    print(f"one scalar FourBar.transfer (φ4, μ, ν): {t_one * 1e6:.2f} µs")


if __name__ == "__main__":
    main()
