"""How well the sley's RK4 error estimate tracks the true error (issue 11 §8).

For each case: the RK4 result's ``error_estimate`` (change of the extrema at half
the step) and ``periodicity``, and the true error of the same revolution's
extrema against DOP853 at rtol 1e-10 (the reference), all relative to each
quantity's largest magnitude, worst over eps2P, eps4P, M2V (, eps5P, M5V).
Run: python benchmarks/calib_sley_estimate.py
"""

import warnings

from mechcirc.sley import simulate

CASES = [
    ("one-side v1", dict(drive="one-side", variant=1)),
    ("one-side v3", dict(drive="one-side", variant=3)),
    ("both-sides v3", dict(drive="both-sides", variant=3)),
    ("one-side v3, 3 steps/period", dict(drive="one-side", variant=3, steps_per_period=3)),
    ("one-side v3, C2=C4=1e7, R=1", dict(drive="one-side", variant=3, C2=1e7, C4=1e7,
                                         revolutions=1)),
    ("one-side v1, omega=1000", dict(drive="one-side", variant=1, omega=1000.0)),
]
NAMES = ("eps2P", "eps4P", "M2V", "eps5P", "M5V")


def rel(a, b):
    worst = 0.0
    for k in NAMES:
        if k not in a.extrema:
            continue
        lo, hi = a.extrema[k]
        scale = max(abs(lo), abs(hi))
        worst = max(worst, abs(lo - b.extrema[k][0]) / scale, abs(hi - b.extrema[k][1]) / scale)
    return worst


print(f"{'case':<32} {'estimate':>9} {'true err':>9} {'periodic':>9}  warned")
for label, kw in CASES:
    kw = dict(kw)
    spp = kw.pop("steps_per_period", None)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        r = simulate(**kw, steps_per_period=spp)
    ref = simulate(**kw, method="DOP853", error_estimate=False)
    per = "-" if r.periodicity is None else f"{r.periodicity:9.2g}"
    print(f"{label:<32} {r.error_estimate:9.2g} {rel(r, ref):9.2g} {per:>9}  {len(w) > 0}",
          flush=True)
