"""Speed of the periodic drive at machine speed (issue 22 §3–4).

(a) ``periodic`` at 600 rpm with 50 harmonics (goal: ≤ 5 ms CPU after start-up),
    against the same superposition written as one would by hand: a loop of
    ``circuit.sweep([k Ω])`` per harmonic and an FFT of the sampled law.
(b) A 200-point operating-speed map (goal: ≤ 0.2 s), against 200 calls of
    ``periodic`` (one per speed), measured in the same run.
(c) A motion read from a table (the cycloidal law sampled every 0.5°, a quintic
    spline of 720 pieces): its 4096 closed-form Fourier coefficients
    (``Motion.fourier``) against numpy's FFT of dx/dθ sampled at 8192 angles (the
    floor: one FFT, but aliased), with each one's error against the other printed;
    then ``periodic`` at 600 rpm to 1e-10 on that table.

On ``docs/examples/cam_drive.mcir`` (5 elements) and on
``netlists/stb_heald.mcir`` (the seed's heald drive, 24 elements) given the
same cycloidal motion.  CPU times (``time.process_time``), best of several
repeats, after one warm-up call (start-up: imports, reduction, resonances).
The script prints; it asserts nothing.  Run from the repository root::

    python benchmarks/bench_periodic.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mechcirc import load
from mechcirc.motion_laws import cam_cycle, motion_table
from mechcirc.periodic import periodic, rpm_to_omega, speed_map
from timing import cpu

ROOT = Path(__file__).resolve().parents[1]
MOTION = cam_cycle("cycloidal", 120, 60, 120, 0.1)


def by_hand(circuit, rpm, n=50, samples=4096):
    """The superposition without mechcirc.periodic: FFT of the sampled velocity, one
    sweep call per harmonic, the sum on 360 angles."""
    W = rpm_to_omega(rpm)
    theta = 2 * np.pi * np.arange(samples) / samples
    v = W * MOTION.evaluate(theta)[1]
    V = 2 * np.fft.rfft(v)[1:n + 1] / samples
    Q = np.empty(n, dtype=complex)
    for k in range(1, n + 1):
        Q[k - 1] = V[k - 1] / circuit.sweep([k * W]).K[0]
    th = np.radians(np.arange(360.0))
    return (np.exp(1j * np.outer(th, np.arange(1, n + 1))) @ Q).real


def main():
    for path in (ROOT / "docs" / "examples" / "cam_drive.mcir",
                 ROOT / "netlists" / "stb_heald.mcir"):
        bench(path)
    bench_table(ROOT / "docs" / "examples" / "cam_drive.mcir")


def bench_table(path, kmax=4096):
    angle = np.linspace(0, 360, 721)
    table = motion_table(angle, MOTION.evaluate(np.radians(angle))[0])

    def closed_form():
        table._cache.pop(("fourier", kmax), None)            # not the kept coefficients
        return table.fourier(kmax)

    def floor():
        theta = 2 * np.pi * np.arange(2 * kmax) / (2 * kmax)
        return np.fft.rfft(table.evaluate(theta)[1])[1:kmax + 1] / (2 * kmax)

    t_c, c = cpu(closed_form, 5, best=True)
    t_f, f = cpu(floor, 5, best=True)
    print(f"table of 721 rows (720 pieces): {kmax} Fourier coefficients {t_c * 1e3:.0f} ms "
          f"CPU, the FFT floor {t_f * 1e3:.1f} ms (ratio {t_c / t_f:.0f}x; they differ by "
          f"{np.max(np.abs(c - f)) / np.max(np.abs(c)):.1e} of the largest, the FFT's aliasing)")
    c = load(path)
    periodic(c, 600, motion=MOTION)                         # start-up
    rows = MOTION.evaluate(np.radians(angle))[0]
    t_p, r = cpu(lambda: periodic(c, 600, motion=motion_table(angle, rows), tol=1e-10), 3,
                 best=True)
    print(f"  {path.name}: periodic 600 rpm on the table to 1e-10 (the table read, its "
          f"coefficients computed): {r.harmonics} harmonics, {t_p * 1e3:.0f} ms CPU")


def bench(path):
    c = load(path)
    periodic(c, 600, motion=MOTION, harmonics=50)            # start-up
    t_p, r = cpu(lambda: periodic(c, 600, motion=MOTION, harmonics=50), 20, best=True)
    t_h, q = cpu(lambda: by_hand(c, 600), 3, best=True)
    diff = np.max(np.abs(q - r.Q)) / r.peak
    print(f"{path.name}: periodic 600 rpm, 50 harmonics: {t_p * 1e3:.2f} ms CPU "
          f"(goal 5 ms); by hand (sweep per harmonic): {t_h * 1e3:.1f} ms; "
          f"ratio {t_h / t_p:.1f}x; same Q within {diff:.1e} of the peak "
          f"(estimated error of the 50-harmonic sum: {r.error:.1e})")
    t_d, r = cpu(lambda: periodic(c, 600, motion=MOTION), 5, best=True)
    print(f"  periodic 600 rpm, harmonics for the default error 1e-4: {r.harmonics} "
          f"harmonics, {t_d * 1e3:.2f} ms CPU")
    speed_map(c, 100, 1200, 200, motion=MOTION, harmonics=50)     # start-up
    t_m, m = cpu(lambda: speed_map(c, 100, 1200, 200, motion=MOTION, harmonics=50), 3, best=True)
    rpms = np.linspace(100, 1200, 200)
    t_l, _ = cpu(lambda: [periodic(c, float(x), motion=MOTION, harmonics=50)
                          for x in rpms], 1, best=True)
    print(f"  speed map 200 speeds, 50 harmonics: {t_m * 1e3:.1f} ms CPU (goal 200 ms); "
          f"200 periodic calls: {t_l * 1e3:.0f} ms; ratio {t_l / t_m:.1f}x")
    t_a, m = cpu(lambda: speed_map(c, 100, 1200, 200, motion=MOTION), 1, best=True)
    print(f"  speed map 200 speeds, default error 1e-4 ({m.harmonics.min()} .. "
          f"{m.harmonics.max()} harmonics): {t_a * 1e3:.0f} ms CPU")


if __name__ == "__main__":
    main()
