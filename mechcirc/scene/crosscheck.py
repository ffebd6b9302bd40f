"""Cross-check a scene's circuit at θ against its time-domain motion near θ (issue 13 §2).

The circuit :func:`mechcirc.scene.build` gives at crank rotation θ predicts
the resonances (K = 0 with the drive held).  The time-domain model
(:mod:`mechcirc.scene.motion`, a different code path: tabulated kinematics,
Lagrange II, RK4) is started in its rigid state at θ with the crank all but
stopped (Ω = 1e-9 of the shaft speed, so the coefficients stay those at θ),
every free part is kicked, and the ringing is recorded.  Its natural
frequencies and damping ratios come from the recorded states by a least-squares
fit of the one-sample map y_{k+1} = A y_k (exact for a linear motion): the
eigenvalues μ of A give s = log(μ)/Δt, ω_n = |s|, ζ = −Re s/|s|.

Clearances are closed for the check (the circuit has none; a kick inside a gap
would not ring); the notes say so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import MechcircError
from .files import Scene

__all__ = ["SceneCrosscheck", "crosscheck_scene"]


@dataclass(frozen=True)
class SceneCrosscheck:
    """Resonances of the circuit at θ beside the ringing of the time-domain motion.

    ``resonances``: list of dicts with ``omega`` (circuit ω_n [rad/s]), ``zeta``,
    ``ringing_omega`` and ``ringing_zeta`` (time domain), ``rel_error``
    (|ringing_omega − omega| / omega).
    """

    source: str
    theta_deg: float
    resonances: list
    notes: tuple = field(default=())

    def summary(self) -> dict:
        return {"file": self.source, "theta_deg": self.theta_deg,
                "resonances": list(self.resonances), "notes": list(self.notes)}


def crosscheck_scene(scene: Scene, theta: float, *, steps_per_period: float = 400.0,
                     periods: float = 3.0) -> SceneCrosscheck:
    """Compare the circuit's resonances at ``theta`` [rad] with the ringing after a kick.

    Raises
    ------
    GeometryError
        θ is a dead centre (the circuit does not exist there).
    MechcircError
        The circuit has no resonance to compare.
    """
    from . import build
    from .motion import motion_model
    from .simfile import apply_overrides
    from .simulation import kernels_for

    notes = []
    gaps = {f"{x.name}.clearance": 0.0 for x in (*scene.elastic, *scene.torsions) if x.clearance}
    if gaps:
        scene = apply_overrides(scene, gaps)
        notes.append("clearances closed for the check (the circuit has none): "
                     + ", ".join(k.split(".")[0] for k in gaps))
    circuit = build(scene, theta).circuit
    found = [r for r in circuit.resonances() if r.kind == "resonance"]
    if not found:
        raise MechcircError(f"{scene.source}: the circuit at θ = {math.degrees(theta):.6g}° has "
                            "no resonance to compare")
    omega_slow = scene.omega_shaft * 1e-9
    model = motion_model(scene, omega_slow)
    n = model.n_free
    rate = max(r.omega for r in found)          # the fastest mode sets the step
    w_min = min(r.omega for r in found)
    h = 2 * math.pi / rate / steps_per_period
    sample = max(1, int(steps_per_period // 16))
    nsamp = int(math.ceil(periods * 2 * math.pi / w_min / (h * sample))) + 1
    nsamp = max(nsamp, 4 * n + 4)
    kern, backend = kernels_for("rk4")
    y0 = model.rigid_state(theta)
    # kick: a velocity on every free part, sized so the deflections stay ~1e-7 of a radian
    kick = 1e-7 * rate * np.array([1.0 + 0.37 * i for i in range(n)])
    y = y0.copy()
    y[n:] += kick
    args = model.kernel_args(theta, 1e300)
    rec_y = np.empty((nsamp, 2 * n))
    rec_t = np.empty(nsamp)
    kern.rk4_run(y, 0.0, h, (nsamp - 1) * sample, 0.0, h * sample, rec_y, rec_t, *args,
                 model.naux())
    dev = rec_y - y0[None, :]
    dt = h * sample
    rows = []
    for r in found:
        # fit over three periods of this resonance from the kick (a fast, damped mode has
        # died out later), at least enough samples for the 2n-dimensional map
        m = min(nsamp, max(4 * n + 4, int(math.ceil(3 * 2 * math.pi / r.omega / dt)) + 1))
        modes = _modes(dev[:m], dt)
        if not modes:
            rows.append({"omega": r.omega, "zeta": r.zeta, "ringing_omega": None,
                         "ringing_zeta": None, "rel_error": None})
            continue
        w, z = min(modes, key=lambda md: abs(md[0] - r.omega))
        rows.append({"omega": r.omega, "zeta": r.zeta, "ringing_omega": float(w),
                     "ringing_zeta": float(z), "rel_error": float(abs(w - r.omega) / r.omega)})
    notes.append(f"time domain: RK4 ({backend}), step {h:.3g} s ({steps_per_period:g} per "
                 f"period of the fastest mode), {nsamp} samples over {periods:g} periods of the "
                 f"slowest resonance, crank all but stopped (Ω = {omega_slow:.3g} rad/s)")
    return SceneCrosscheck(scene.source, math.degrees(theta), rows, tuple(notes))


def _modes(dev, dt):
    """(ω_n, ζ) of the underdamped modes of the sampled motion ``dev`` (rows: samples)."""
    scale = np.maximum(np.std(dev, axis=0), 1e-300)
    Z = dev / scale
    A = Z[1:].T @ np.linalg.pinv(Z[:-1].T, rcond=1e-13)
    s = np.log(np.linalg.eigvals(A).astype(complex)) / dt
    return sorted((abs(x), -x.real / abs(x)) for x in s if x.imag > 0)
