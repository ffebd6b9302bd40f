"""Cross-check a scene's circuit at θ against its time-domain motion near θ.

The circuit :func:`mechcirc.scene.build` gives at crank rotation θ predicts
the resonances (K = 0 with the drive held).  The time-domain model
(:mod:`mechcirc.scene.motion`, a different code path: tabulated kinematics,
Lagrange II, RK4) is started in its rigid state at θ with the crank all but
stopped (Ω = 1e-9 of the shaft speed, so the coefficients stay those at θ),
every free part is kicked, and the ringing is recorded.  Its natural
frequencies and damping ratios come from the recorded states by the matrix pencil
of four delays (:func:`mechcirc.identify.poles`) with 2n + 2 poles: the 2n modes
of the n free coordinates and a double pole near 0, the crank's slow drift (a
one-sample map y_{k+1} = A y_k has no room for it and was up to 3e-4 off); each
resonance is matched to the nearest pole s, ω_n = |s|, ζ = −Re s/|s|.

Forced response: the circuit's |Q0(ω)| (the drive's force amplitude for its
velocity amplitude V0) against the time domain with the drive speed rippled,
θ̇ = Ω_slow + A cos(ω t) (A tiny: a linear motion), at a few ω near and away from
the resonances.  The drive's generalised force of the time-domain model (the
``drive.moment`` output) is fitted by least squares to a sinusoid at ω plus the
free modes measured from the ringing (so the start transient need not die out);
its amplitude, per unit drive velocity amplitude and times V0, is Q0_time.  A
load to the frame (``[[loads]]``) is held on the *mean* crank motion for this run
(``loads_on_mean``): in the circuit it is attached to the frame, so the drive's
ripple deforms it; in a simulation it follows the actual rigid motion (its
deformation is the departure from it).  With the loads following the ripple the
heald scene's warp was 2.4 % off below the first resonance; held, ≤ 3e-7.

Clearances are closed for the check (the circuit has none; a kick inside a gap
would not ring); the notes say so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import MechcircError
from ..identify import fit_sinusoid, judge_pole, nearest_pole, pole_of, poles
from ..verdict import checked_repr, judge, summarise
from .files import Scene

#: Tolerances of the verdicts: the ringing's ω_n (RK4 record, its modes by the matrix
#: pencil; achieved ≤ 6.9e-7 on the heald, Mrázek, rocker, cam and slider scenes) and
#: the forced |Q0| (achieved ≤ 1.9e-6).  ζ is shown, not judged.
TOL_RINGING, TOL_FORCED = 1e-5, 1e-5

__all__ = ["SceneCrosscheck", "crosscheck_scene"]


@dataclass(frozen=True)
class SceneCrosscheck:
    """Resonances of the circuit at θ beside the ringing of the time-domain motion.

    ``resonances``: list of dicts with ``omega`` (circuit ω_n [rad/s]), ``zeta``,
    ``ringing_omega`` and ``ringing_zeta`` (time domain), ``rel_error``
    (|ringing_omega − omega| / omega).
    ``forced``: list of dicts with ``omega`` (of the drive ripple [rad/s]),
    ``Q0_circuit`` and ``Q0_time`` (|Q0| at the drive's amplitude V0 [N·m or N]) and
    ``rel_error``.  Every row also has ``verdict``, ``tol`` and ``why``
    (:func:`mechcirc.verdict.judge`).
    """

    __repr__ = checked_repr

    source: str
    theta_deg: float
    resonances: list
    notes: tuple = field(default=())
    forced: list = field(default_factory=list)

    @property
    def verdict(self) -> dict:
        """Overall verdict (:func:`mechcirc.verdict.summarise`)."""
        return summarise(list(self.resonances) + list(self.forced))

    def summary(self) -> dict:
        return {"file": self.source, "theta_deg": self.theta_deg,
                "verdict": self.verdict["verdict"], "summary": self.verdict,
                "resonances": list(self.resonances), "forced": list(self.forced),
                "notes": list(self.notes)}


def crosscheck_scene(scene: Scene, theta: float, *, steps_per_period: float = 400.0,
                     periods: float = 3.0, forced: bool = True) -> SceneCrosscheck:
    """Compare the circuit's resonances at ``theta`` [rad] with the ringing after a kick,
    and (``forced``) its |Q0(ω)| with the forced response to a drive-speed ripple.

    Parameters
    ----------
    scene : Scene
        The scene whose circuit and time-domain motion are compared.
    theta : float
        Crank angle [rad] at which the circuit is built.
    steps_per_period : float
        Time steps per period of the fastest mode compared.
    periods : float
        Length of the ringing record, in periods of the slowest mode.
    forced : bool
        Also compare |Q0(ω)| with the forced response.

    Returns
    -------
    SceneCrosscheck
        One line per resonance (and per forcing frequency), each with its verdict.

    Raises
    ------
    GeometryError
        θ is a dead centre (the circuit does not exist there).
    MechcircError
        The circuit has no resonance to compare.
    """
    from . import build
    from .motion import motion_model

    scene, notes = _clearances_closed(scene)
    built = build(scene, theta)
    found = [r for r in built.circuit.resonances() if r.kind == "resonance"]
    if not found:
        raise MechcircError(f"{scene.source}: the circuit at θ = {math.degrees(theta):.6g}° has "
                            "no resonance to compare")
    omega_slow = scene.omega_shaft * 1e-9
    model = motion_model(scene, omega_slow)
    dev, dt, h, nsamp, kern, backend = _kick_record(model, theta, found, steps_per_period,
                                                    periods)
    rows = _ringing_rows(found, dev, dt, model.n_free)
    notes.append(f"time domain: RK4 ({backend}), step {h:.3g} s ({steps_per_period:g} per "
                 f"period of the fastest mode), {nsamp} samples over {periods:g} periods of the "
                 f"slowest resonance, crank all but stopped (Ω = {omega_slow:.3g} rad/s)")
    frows = []
    if forced:
        # free modes of the time-domain motion (for the fit), from the whole kick record
        whole = _modes(dev, dt)
        frows = _forced_rows(built, found, model, kern, theta,
                             [nearest_pole(whole, pole_of(r), dt) for r in found], h)
        notes.append("forced: drive speed rippled by A cos(ω t) (A/ω = 1e-7 rad) at 0.5 and "
                     "0.9 × the lowest resonance, between resonances and 1.5 × the highest; "
                     "the drive's force fitted to the ripple plus the ringing's free modes")
    return SceneCrosscheck(scene.source, math.degrees(theta), rows, tuple(notes), frows)


def _clearances_closed(scene):
    """The scene with every clearance closed (the circuit has none) and the notes saying
    so: the scene itself and no note if it has no clearance."""
    from .files import apply_overrides

    gaps = {f"{x.name}.clearance": 0.0 for x in (*scene.elastic, *scene.torsions) if x.clearance}
    if not gaps:
        return scene, []
    return apply_overrides(scene, gaps), ["clearances closed for the check (the circuit has "
                                          "none): " + ", ".join(k.split(".")[0] for k in gaps)]


def _kick_record(model, theta, found, steps_per_period, periods):
    """The motion's deviation from the rigid state at ``theta`` after a kick, a velocity on
    every free part sized so the deflections stay ~1e-7 of a radian, by RK4 at
    ``steps_per_period`` steps per period of the fastest resonance of ``found`` over
    ``periods`` periods of the slowest: (record, its sample interval, step, samples,
    kernels, their backend)."""
    from .simulation import kernels_for

    n = model.n_free
    rate = max(r.omega for r in found)          # the fastest mode sets the step
    w_min = min(r.omega for r in found)
    h = 2 * math.pi / rate / steps_per_period
    sample = max(1, int(steps_per_period // 16))
    nsamp = max(int(math.ceil(periods * 2 * math.pi / w_min / (h * sample))) + 1, 4 * n + 4)
    kern, backend = kernels_for("rk4", long=True)     # the forced records take it too
    y0 = model.rigid_state(theta)
    y = y0.copy()
    y[n:] += 1e-7 * rate * (1.0 + 0.37 * np.arange(n))
    rec_y = _record(model, kern, y, h, sample, nsamp, model.kernel_args(theta, 1e300))[0]
    return rec_y - y0[None, :], h * sample, h, nsamp, kern, backend


def _record(model, kern, y, h, sample, nsamp, args):
    """RK4 from the state ``y`` at t = 0 (``args``: the model's kernel arguments) with step
    ``h``, the state recorded every ``sample`` steps, ``nsamp`` times: (states, times)."""
    rec_y, rec_t = np.empty((nsamp, y.size)), np.empty(nsamp)
    kern.rk_run(y, 0.0, h, (nsamp - 1) * sample, 0.0, h * sample, rec_y, rec_t, *args,
                model.naux(), *kern.tableau("rk4"))
    return rec_y, rec_t


def _ringing_rows(found, dev, dt, n) -> list:
    """One judged row per resonance of ``found``: its ω_n and ζ against the nearest
    mode identified in the kick's record ``dev`` (step ``dt``, ``n`` parts)."""
    rows = []
    for r in found:
        # fit over three periods of this resonance from the kick (a fast, damped mode has
        # died out later), at least enough samples for the 2n + 2 poles
        m = min(len(dev), max(4 * n + 4, int(math.ceil(3 * 2 * math.pi / r.omega / dt)) + 1))
        rows.append(judge_pole({"omega": r.omega, "zeta": r.zeta, "ringing_omega": None,
                                "ringing_zeta": None, "rel_error": None}, pole_of(r),
                               _modes(dev[:m], dt), dt, TOL_RINGING, measure="omega_n",
                               why=None))
    return rows


def _forced_rows(built, found, model, kern, theta, free, h) -> list:
    """|Q0| of the circuit against the forced response of the time domain, judged, at
    0.5 and 0.9 × the lowest resonance, between resonances and 1.5 × the highest."""
    circuit, ws = built.circuit, sorted(r.omega for r in found)
    probe = [0.5 * ws[0], 0.9 * ws[0], *(math.sqrt(a * b) for a, b in zip(ws, ws[1:])),
             1.5 * ws[-1]]
    sw, rows = circuit.sweep(np.array(probe)), []
    for w, q0 in zip(probe, sw.Q0):
        qt = _forced_amplitude(model, kern, theta, w, free, h, built.drive_ratio)
        v0 = abs(circuit.drive.amplitude)
        rel = float(abs(qt * v0 - abs(q0)) / abs(q0))
        rows.append(judge({"omega": float(w), "Q0_circuit": float(abs(q0)),
                           "Q0_time": float(qt * v0), "rel_error": rel}, rel, TOL_FORCED))
    return rows


def _forced_amplitude(model, kern, theta, w, free, h, r0):
    """|drive force| / |drive velocity| of the time-domain motion under a speed ripple at ω.

    The ripple is on the crank (the cam for a cam scene): the drive's velocity is
    r0 times it, and ``drive.moment``, the generalised force conjugate to the crank
    angle, is r0 times the drive's force (virtual work), so the ratio is
    |drive.moment| / (|ripple| r0²), with r0 the circuit's drive ratio at θ.
    """
    amp = 1e-7 * w                          # the crank swings ±1e-7 rad
    # the step resolves both the fastest mode and the ripple; the record spans 40 periods
    # of the beat between the ripple and the nearest free mode (at least 30 ripple periods)
    hh = min(h, 2 * math.pi / w / 400.0)
    gap = min([abs(w - s.imag) for s in free] + [w])
    span = max(60 * 2 * math.pi / w, 20 * 2 * math.pi / max(gap, 1e-300))
    span = min(span, 2e6 * hh)
    sample = max(1, int(round(2 * math.pi / w / hh / 24)))
    nsamp = int(span / (hh * sample)) + 1
    y = model.rigid_state(theta, model.omega + amp)
    rec_y, rec_t = _record(model, kern, y, hh, sample, nsamp, model.kernel_args(
        theta, 1e300, ripple=(amp, w), loads_on_mean=True))
    out = np.empty((model.naux(), nsamp))
    kern.outputs(rec_t, rec_y, out, *model.kernel_args(theta, 1e300, outputs=True,
                                                          ripple=(amp, w), loads_on_mean=True))
    q = out[len(model.bodies) + 2 * len(model.elements)]       # drive.moment
    # fit the second half: a strongly damped mode has died out there, and a slight error
    # of its measured damping cannot leak into the ripple's amplitude
    half = nsamp // 2
    return fit_sinusoid(rec_t[half:], q[half:], w, free)[0] / (amp * r0 * r0)


def _modes(dev, dt):
    """Poles [1/s] of the sampled motion ``dev`` (rows: samples of the 2n free coordinates
    and rates): its 2n modes and the double pole near 0 of the crank's slow drift, by the
    matrix pencil of four delays."""
    return poles(dev, dt, delays=4, order=dev.shape[1] + 2)
