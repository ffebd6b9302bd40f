"""A scene over a crank revolution: resonances and |Q0| at the shaft harmonics.

At each of ``points`` crank rotations θ (evenly spaced over 2π, continued
from the pose by :meth:`Linkage.solve`), the scene is linearised
(:func:`~mechcirc.scene.build`) and its circuit gives the natural
frequencies seen from the drive (:meth:`Circuit.resonances`) and the drive's
force amplitude Q0 at ω = h·|Ω| for h = 1 … ``harmonics`` (Ω the crank speed).
The map a designer reads first: where in the cycle a resonance meets a
harmonic of the shaft speed (:meth:`CycleMap.crossings`).

A θ where the linearisation does not exist (a dead centre, see
:func:`~mechcirc.scene.build`) is recorded in ``skipped`` with the reason and
NaN values; the rest of the map is kept.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ..batch import Designs, from_circuits, network_shape
from ..errors import GeometryError, InputError, SolverError, did_you_mean
from ..motion_laws import Motion, motion_table
from ..sources import brief, data_frame, summary_repr
from ..units import FREQUENCY_UNITS, in_unit
from .files import Scene
from .model import (RANK_TOL, ReflectMode, build, drive_ratio, element_ratios, part_singular_values,
                    part_speeds, scaled_motion)

__all__ = ["CycleMap", "cycle_map", "drive_motion"]

#: Rigid-kinematics samples of the drive's motion over a revolution (quintic Hermite between).
DRIVE_SAMPLES = 720


@dataclass(frozen=True, eq=False)
class CycleMap:
    """Resonances and harmonic forces of a scene against crank angle.

    Attributes
    ----------
    theta : ndarray, shape (n,)
        Crank rotation from the pose [rad].
    resonances : list of tuple of Resonance
        Per θ, the zeros of K (drive held), ascending; empty where skipped.
    antiresonances : list of tuple of Resonance
        Per θ, the poles of K (drive released).
    harmonics : ndarray of int, shape (H,)
    omega_shaft : float
        |Ω|, the crank speed [rad/s].
    Q0 : ndarray of complex, shape (n, H)
        Drive force amplitude at ω = h·|Ω| [N·m or N]; NaN where skipped.
    skipped : dict[int, str]
        Index of θ → why the scene could not be linearised there.
    rotational : bool
        Units of Q0: N·m (True) or N.
    cycle : float
        The span of ``theta`` [rad]: 2π, or the cycle of geared cranks (then
        ``omega_shaft`` is the cycle's fundamental |Ω|/revolutions).
    """

    __repr__ = summary_repr

    theta: NDArray[np.float64]
    resonances: list
    antiresonances: list
    harmonics: NDArray[np.int64]
    omega_shaft: float
    Q0: NDArray[np.complex128]
    skipped: dict
    rotational: bool
    cycle: float = 2 * math.pi

    def natural_frequencies(self, kind: str = "resonance") -> NDArray[np.float64]:
        """Array (n, m) of ωₙ [rad/s] of the underdamped modes, NaN-padded (m the most at any θ);
        ``kind`` ``"resonance"`` (of :attr:`resonances`) or ``"antiresonance"`` (:attr:`antiresonances`)."""
        if kind not in ("resonance", "antiresonance"):
            raise InputError(f"kind must be 'resonance' or 'antiresonance', got {brief(kind)}"
                             f"{did_you_mean(str(kind), ('resonance', 'antiresonance'))}")
        rows = [[r.omega for r in row if r.zeta < 1.0]
                for row in (self.resonances if kind == "resonance" else self.antiresonances)]
        m = max((len(r) for r in rows), default=0)
        out = np.full((len(rows), m), np.nan)
        for i, r in enumerate(rows):
            out[i, :len(r)] = r
        return out

    def crossings(self) -> list[dict]:
        """Where the k-th underdamped resonance meets a harmonic h·|Ω| between two grid angles.

        Returns dicts with ``mode`` k (0 = lowest), ``harmonic`` h,
        ``theta_deg`` (linear interpolation between the bracketing grid
        points, wrapping over the revolution) and ``omega`` [rad/s].
        """
        W, out = self.natural_frequencies(), []
        n = len(self.theta)
        for k in range(W.shape[1]):
            for h in self.harmonics:
                target = h * self.omega_shaft
                for i in range(n):
                    j = (i + 1) % n
                    a, b = W[i, k] - target, W[j, k] - target
                    # (b = 0: counted at the next interval)
                    if not (np.isfinite(a) and np.isfinite(b)) or a * b > 0 or a == b or b == 0:
                        continue
                    t0 = self.theta[i]
                    th = t0 + (self.theta[j] - t0) % self.cycle * a / (a - b)
                    out.append({"mode": k, "harmonic": int(h),
                                "theta_deg": math.degrees(th % self.cycle), "omega": float(target)})
        return sorted(out, key=lambda c: (c["theta_deg"], c["harmonic"]))

    def to_dataframe(self):
        """One row per crank angle, the columns of ``mechcirc cycle``'s CSV: ``theta_deg``
        [deg], ``omega_res1``… the underdamped resonances [rad/s] (NaN where fewer, and
        where skipped), ``abs_Q0_h1``… |Q0| at each harmonic h·Ω [N, N·m when rotational];
        ``attrs["units"]`` the unit of each column."""
        cols = {"theta_deg": np.degrees(self.theta),
                **{f"omega_res{k + 1}": w for k, w in enumerate(self.natural_frequencies().T)},
                **{f"abs_Q0_h{h}": q for h, q in zip(self.harmonics, np.abs(self.Q0).T)}}
        force = "N·m" if self.rotational else "N"
        return data_frame(cols, {c: "deg" if c == "theta_deg" else "rad/s" if c[0] == "o"
                                 else force for c in cols})

    def as_dict(self) -> dict:
        """Plain data for JSON output."""
        return {
            "omega_shaft": self.omega_shaft,
            "harmonics": self.harmonics.tolist(),
            "Q0_unit": "N·m" if self.rotational else "N",
            "points": [
                {"theta_deg": math.degrees(t), "resonances": [x.as_dict() for x in r],
                 "antiresonances": [x.as_dict() for x in a], "abs_Q0": np.abs(q).tolist(),
                 **({"skipped": self.skipped[i]} if i in self.skipped else {})}
                for i, (t, r, a, q) in enumerate(zip(self.theta, self.resonances,
                                                     self.antiresonances, self.Q0))],
            "crossings": self.crossings(),
        }


def cycle_map(scene: Scene, *, points: int = 72, harmonics: int = 5,
              reflect: ReflectMode = "eta", progress=None) -> CycleMap:
    """Resonances and |Q0| at the first ``harmonics`` shaft harmonics at ``points`` crank angles.

    Parameters
    ----------
    scene : Scene
    points : int
        Crank angles over one revolution (0 … 2π, end excluded; geared cranks: the
        cycle), ≥ 2.
    harmonics : int
        Number of harmonics h = 1 … H of the crank speed, ≥ 1.
    reflect : {"eta", "lever"}
        Passed to :func:`~mechcirc.scene.build`.
    progress : callable, optional
        ``progress(done, total)`` after each crank angle (the CLI's progress bar).

    Returns
    -------
    CycleMap
        Resonances and |Q0| at each crank angle and harmonic.

    Raises
    ------
    GeometryError
        The crank cannot make a full revolution (the message says where it locks).
    ValueError
        ``points`` < 2 or ``harmonics`` < 1.
    """
    if isinstance(points, bool) or not isinstance(points, int) or points < 2:
        raise ValueError(f"points must be an integer ≥ 2, got {points!r}")
    if isinstance(harmonics, bool) or not isinstance(harmonics, int) or harmonics < 1:
        raise ValueError(f"harmonics must be an integer ≥ 1, got {harmonics!r}")
    theta = np.linspace(0.0, scene.cycle, points, endpoint=False)
    try:
        motion = scene.linkage.motion(theta)
    except GeometryError as exc:
        raise GeometryError(f"{scene.source}: the crank cannot make a full revolution, so there "
                            f"is no cycle to map ({exc})") from None
    hs = np.arange(1, harmonics + 1)
    omega_shaft = abs(scene.omega_shaft) / scene.cycle_revolutions   # the cycle's fundamental
    parts, skipped = _cycle_batches(scene, theta, motion, reflect)
    res, anti, Q0 = _batch_roots(parts, points, hs * omega_shaft)
    if progress is not None:
        for i in range(points):
            progress(i + 1, points)
    return CycleMap(theta, res, anti, hs, omega_shaft, Q0, skipped,
                    scene.drive.link is not None, scene.cycle)


def _batch_roots(parts, points: int, omegas):
    """Resonances, anti-resonances and Q0 at ``omegas`` of each of ``points`` crank angles,
    from the batches ``parts`` (``[(Designs, angle indices)]``, :func:`_cycle_batches`)."""
    Q0 = np.full((points, len(omegas)), np.nan, dtype=complex)
    res: list = [()] * points
    anti: list = [()] * points
    for part, where in parts:
        found = part.resonances()
        with np.errstate(all="ignore"):
            q = part.sweep(omegas).Q0
        for d in range(part.size):
            i = int(where[d])
            if d in found.failed:
                raise SolverError(found.failed[d])
            rows = found.list(d)
            res[i] = tuple(r for r in rows if r.kind == "resonance")
            anti[i] = tuple(r for r in rows if r.kind == "antiresonance")
            Q0[i] = q[d]
    return res, anti, Q0


def _cycle_batches(scene: Scene, theta, motion, reflect: ReflectMode):
    """Every crank angle as a design: ``[(Designs, angle indices)]``, from
    :func:`_cycle_designs` and, for the angles it leaves (near a dead centre, a
    topology of their own), from build; and the angles build refuses (index → why)."""
    n = len(theta)
    batch, alone = _cycle_designs(scene, motion, reflect) if _BATCHED else (None, range(n))
    states = motion.states() if len(alone) else []
    circuits, single, skipped = [], [], {}
    for i in alone:
        try:
            circuits.append(build(scene, theta[i], state=states[i], reflect=reflect).circuit)
            single.append(i)
        except GeometryError as exc:
            skipped[i] = str(exc)
    parts = [] if batch is None else [batch]
    if circuits:
        try:                            # one topology over the cycle: one batch
            built = [(from_circuits(circuits), np.array(single))]
        except InputError:
            built = [(from_circuits([c]), np.array([i])) for c, i in zip(circuits, single)]
        for ds, where in built:
            # the same elements, levers and drive (names, kinds, nodes): they join the batch
            if parts and network_shape(parts[0][0].circuit) == network_shape(ds.circuit):
                parts[0] = (_joined(parts[0][0], ds), np.concatenate([parts[0][1], where]))
            else:
                parts.append((ds, where))
    return parts, skipped


#: Batch the crank angles (False: one scene.build per angle, the reference path).
_BATCHED = True
#: An angle within this factor of a decision of build (a ratio "at rest", a part's
#: rank) is left to build, so that the batch never decides differently.
_MARGIN = 1e3


def _joined(a, b):
    """The designs of ``a`` then those of ``b`` (one network)."""
    return replace(a, values=np.hstack([a.values, b.values]), eta=np.hstack([a.eta, b.eta]),
                   ratios=np.hstack([a.ratios, b.ratios]),
                   amplitude=np.concatenate([a.amplitude, b.amplitude]),
                   valid=np.concatenate([a.valid, b.valid]))


def _cycle_designs(scene: Scene, motion, reflect: ReflectMode):
    """The circuits of the scene at every angle of ``motion`` as one batch of designs.

    :func:`~mechcirc.scene.build` at one angle gives the network (elements,
    nodes, what is left out); at every other angle only the reflection factors
    change, η = r² with r each element's velocity ratio to the drive, from
    build's own formulas (:func:`~mechcirc.scene.model.element_ratios`)
    evaluated on the motion's arrays for all angles at once.  The angles where
    build would decide differently, or nearly so (a ratio within ``_MARGIN``
    of "at rest", a rigid part whose joint constraints are within
    ``_MARGIN`` of losing rank), are returned for build to do one by one.
    Only ``reflect="eta"`` on a linkage (or a cam) whose sliders, if any, run
    on fixed guides; else every angle goes to build.  As a check, the ratios
    at the template's angle must equal build's to 1e-12, else the same.

    Returns ``((Designs, angle indices), angles for build)``.
    """
    every, lk = range(len(motion.theta)), scene.linkage
    if reflect != "eta" or any(s.guide != "ground" for s in lk.sliders) or \
            not set(lk.ground) <= set(motion.point_names):
        return None, every
    m = scaled_motion(scene, np.degrees(motion.theta),
                      dict(zip(motion.point_names, np.swapaxes(motion.points, 0, 1))),
                      dict(zip(motion.point_names, np.swapaxes(motion.velocities, 0, 1))),
                      dict(zip(motion.link_names, motion.angular_velocities.T)))
    ok, found = _clear_angles(scene, m)
    if not ok.any():
        return None, every
    i0 = int(np.argmax(ok))
    try:
        template = build(scene, float(motion.theta[i0]), state=motion.state(i0), reflect=reflect)
    except GeometryError:
        return None, every
    dropped = {name for name, _ in template.dropped}
    if set(found) != set(template.ratios) or template.circuit.levers:
        return None, every
    for name, r in template.ratios.items():          # the check against build
        if not abs(found[name][0][i0] - r) <= 1e-12 * max(abs(r), 1e-300):
            return None, every
        ok &= (found[name][1] > m.tiny) == (name not in dropped)  # the same elements left out
    where = np.flatnonzero(ok)
    source = {k: e.name for e in scene.elastic + scene.torsions + scene.loads
              for k in (e.name, e.name + "_d")}
    c = template.circuit
    eta = np.array([found[source.get(e.name, e.name)][0][where] ** 2 for e in c.elements])
    values = np.repeat(np.array([[e.value] for e in c.elements]), where.size, axis=1)
    with np.errstate(all="ignore"):
        valid = (np.isfinite(values * eta) & (values * eta > 0)).all(axis=0)
    ds = Designs(c, {}, values, eta, np.zeros((0, where.size)),
                 np.full(where.size, float(c.require_drive().amplitude)), valid, None)
    return (ds, where), np.flatnonzero(~ok).tolist()


def _clear_angles(scene: Scene, m):
    """(Angles where each decision of build is clear by ``_MARGIN``: the drive and every
    part moving, each part's constraints of rank 3·len(part) − 1, each element moving or
    at rest, rods on one body turning alike; the element ratios)."""
    ok = np.ones(m.tiny.shape, dtype=bool)
    for t in scene.torsions:       # build refuses rods on one body turning differently
        ok &= m.ang[t.link] == m.ang[t.body]
    r0, r0_size, _ = drive_ratio(scene, m)
    ok &= (r0_size > m.tiny * _MARGIN) & np.isfinite(r0)
    for part in scene.parts:
        speeds = [size for size, _ in part_speeds(scene, part, m).values()]
        ok &= np.max(speeds, axis=0) > m.tiny * _MARGIN
        s = part_singular_values(scene, part, m)                 # (n, k) descending
        thr = RANK_TOL * s[:, :1]
        rank = (s > thr).sum(axis=1)
        ok &= ((s > thr * _MARGIN) | (s < thr / _MARGIN)).all(axis=1) & \
            (3 * len(part) - rank == 1)
    found = element_ratios(scene, m, r0)
    for _, size in found.values():      # moving or at rest, not close to the threshold
        ok &= (size > m.tiny * _MARGIN) | (size < m.tiny / _MARGIN)
    return ok, found


def plot_cycle(cmap: CycleMap, ax=None, *, fig=None, unit: str = "rad/s"):
    """Resonances against crank angle with the harmonic lines, and |Q0| at each harmonic.

    Every line is labelled: each resonance branch, each harmonic line h·Ω and
    the crossings.  Nothing the caller drew is deleted or cleared (versions
    before this one deleted ``ax`` and drew a two-panel Figure in its place).

    Parameters
    ----------
    cmap : CycleMap
        From :func:`cycle_map`.
    ax : matplotlib Axes, optional
        Draw only the upper panel (the resonances, the harmonic lines and the
        crossings) on it and return it, as :func:`mechcirc.plotting.plot_sweep`
        draws only |K|.
    fig : matplotlib Figure or SubFigure, optional
        An empty one to fill with both panels
        (:func:`mechcirc.plotting.new_panels`); a new Figure by default.
    unit : {"rad/s", "Hz", "rpm"}
        Frequency unit of the upper panel.

    Returns
    -------
    The Axes ``ax`` when given, else ``fig`` (empty) or the new Figure (what it drew on).
    """
    if unit not in FREQUENCY_UNITS:
        raise InputError(f"unit must be one of {', '.join(map(repr, FREQUENCY_UNITS))}, "
                         f"got {brief(unit)}{did_you_mean(str(unit), FREQUENCY_UNITS)}")
    deg = np.degrees(cmap.theta)
    if ax is not None:
        _resonance_panel(ax, cmap, deg, unit)
        return ax
    from ..plotting import laid_out, new_panels

    made = fig is None
    fig, ((a1,), (a2,)) = new_panels(fig, 2, caller="plot_cycle", figsize=(8, 7), sharex=True)
    _resonance_panel(a1, cmap, deg, unit)
    runit = "N·m" if cmap.rotational else "N"
    for j, h in enumerate(cmap.harmonics):
        a2.semilogy(deg, np.abs(cmap.Q0[:, j]), label=f"h = {h}")
    a2.set(xlabel="crank rotation from the pose θ [deg]", ylabel=f"|Q0| at ω = h·Ω [{runit}]")
    a2.legend(fontsize=7, ncol=3)
    return laid_out(made, fig)         # a given figure keeps the caller's layout


def _resonance_panel(a1, cmap: CycleMap, deg, unit: str) -> None:
    """The upper panel of :func:`plot_cycle` on ``a1``."""
    W = cmap.natural_frequencies()
    for k in range(W.shape[1]):
        a1.plot(deg, in_unit(W[:, k], unit), ".-", ms=3, label=f"resonance {k + 1}")
    for h in cmap.harmonics:
        line = in_unit(h * cmap.omega_shaft, unit)
        a1.axhline(line, color="0.6", lw=0.7, ls=":")
        a1.annotate(f"{h}·Ω", (1.0, line), xycoords=("axes fraction",
                    "data"), xytext=(2, 0), textcoords="offset points", fontsize=7,
                    va="center", color="0.4")
    for n, c in enumerate(cmap.crossings()):
        a1.plot(c["theta_deg"], in_unit(c["omega"], unit), "kx", ms=6,
                label="resonance = h·Ω" if n == 0 else None)
    a1.set(ylabel=f"natural frequency [{unit}]  (dotted: h·Ω)",
           title=a1.get_title() or "resonances (K = 0, drive held) over the cycle; × where one "
           "meets h·Ω")
    a1.legend(fontsize=7, loc="upper left")


def drive_motion(scene: Scene, theta: float, *, samples: int = DRIVE_SAMPLES) -> Motion:
    """The motion the rigid linkage imposes on the scene's drive over one crank revolution.

    The drive of the circuit built at crank rotation ``theta``
    (:func:`~mechcirc.scene.build`) moves, over θ' ∈ [0, 2π) from the pose,

    * a link drive: x(θ') = φ_link(θ') [rad], the link's angle (a link that
      turns whole revolutions: less its steady rotation, which has no harmonic);
    * a point drive P: x(θ') = u·P(θ') [m], u the direction of P's velocity at
      ``theta`` (the drive's direction in that circuit).

    x, dx/dθ' and d²x/dθ'² are taken from the rigid kinematics
    (:meth:`Linkage.motion`) at ``samples`` even crank angles and joined by
    quintic Hermite pieces (:func:`~mechcirc.motion_laws.motion_table`), whose
    ``error`` estimates the interpolation as for a table.

    Parameters
    ----------
    scene : Scene
        The scene; its drive is the motion's output.
    theta : float
        Crank rotation [rad] at which the circuit is linearised.
    samples : int
        Kinematic samples over the revolution, ≥ 16.

    Returns
    -------
    Motion
        For :func:`mechcirc.periodic.periodic` with the circuit at ``theta``.

    Raises
    ------
    GeometryError
        The crank cannot make a full revolution, or the linkage does not come
        back to its pose after one (several cranks at unrelated speeds).
    """
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 16:
        raise ValueError(f"samples must be an integer ≥ 16, got {samples!r}")
    lk = scene.linkage
    th = np.linspace(0.0, 2 * math.pi, samples + 1)
    try:
        km = lk.motion(th)
    except GeometryError as exc:
        raise GeometryError(f"{scene.source}: the crank cannot make a full revolution, so the "
                            f"drive has no periodic motion ({exc})") from None
    if np.max(np.abs(km.points[-1] - km.points[0])) > 1e-9 * lk.length_scale():
        raise GeometryError(f"{scene.source}: the linkage is not back at its pose after one "
                            "turn of the first crank, so the drive's motion is not periodic "
                            "in the crank angle")
    x, dx, ddx, what = (_link_drive(scene, km, th) if scene.drive.link is not None
                        else _point_drive(scene, km, theta))
    return motion_table(np.degrees(th), x - x[0], f"motion from the linkage: {what}, "
                        f"{samples} samples", slope=dx, curvature=ddx)


def _link_drive(scene: Scene, km, th):
    """x, dx/dθ, d²x/dθ² and a description of a link drive's angle over the samples ``th``."""
    w = scene.linkage.cranks[0].omega
    link = {t.body: t.link for t in scene.torsions}.get(scene.drive.link, scene.drive.link)
    j = km.link_names.index(link)
    x = np.unwrap(km.q[:, 3 * j + 2])
    dx, ddx = km.qdot[:, 3 * j + 2] / w, km.qddot[:, 3 * j + 2] / w ** 2
    what = f"angle of link {link}"
    turns = (x[-1] - x[0]) / (2 * math.pi)          # whole turns per revolution
    x, dx = x - turns * th, dx - turns
    if round(turns):
        what += f", less its steady rotation ({round(turns):+d} turn per revolution)"
        if np.max(np.abs(dx)) <= 1e-12 * abs(turns):      # the crank itself: rounding
            x, dx, ddx = (np.zeros_like(x) for _ in range(3))
            what += "; nothing is left: it turns at the crank's steady speed"
    return x, dx, ddx, what


def _point_drive(scene: Scene, km, theta):
    """The same for a point drive: its displacement along its velocity at ``theta``."""
    lk, d = scene.linkage, scene.drive
    w, L = lk.cranks[0].omega, scene.length_scale
    i = km.point_names.index(d.point)
    v0 = lk.solve(float(theta)).velocities[d.point]
    u = np.asarray(v0, float) / np.hypot(*v0)
    x, dx, ddx = (a[:, i] @ u * (L / w ** k)      # d^k/dθ^k = (d^k/dt^k) / ω^k
                  for k, a in enumerate((km.points, km.velocities, km.accelerations)))
    return x, dx, ddx, f"displacement of point {d.point} along ({u[0]:.6g}, {u[1]:.6g})"
