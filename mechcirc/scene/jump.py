"""Follower jump in a scene: the cam contact over a simulated revolution, the jump speed.

A scene whose ``[cam]`` has a ``contact`` (:mod:`.cam`, docs/scenes.md "A follower
that can jump") is simulated by :func:`~mechcirc.scene.simulate_scene`;
:func:`contact_report` reads the contact's force, the separations and the least
contact force from it, and :func:`scene_jump_speed` finds the shaft speed at which
that least force reaches zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import MechcircError
from .cam import SPRING, contact_geometry
from .simulation import flight, simulate_scene

__all__ = ["ContactReport", "contact_report", "flight", "JumpSpeed", "scene_jump_speed"]


@dataclass(frozen=True)
class ContactReport:
    """The cam contact over a simulated revolution (plain data); see :func:`contact_report`.

    Attributes
    ----------
    angle_deg : ndarray
        Cam angle [deg] of each sample.
    contact_force : ndarray
        The force the cam gives the follower [N] (0 while the contact is open).
    travel : ndarray
        The follower's rise from the pose [m].
    min_contact, min_contact_angle_deg : float
        The least force the contact spring would carry, k_c × its compression
        (negative once the follower has left the cam), refined between samples
        by a parabola, and where [deg].
    separations : tuple of (float, float)
        Each opening of the contact: the cam angle it opens at and how long it
        stays open [deg].
    """

    angle_deg: np.ndarray
    contact_force: np.ndarray
    travel: np.ndarray
    min_contact: float
    min_contact_angle_deg: float
    separations: tuple


def contact_report(scene, sm) -> ContactReport:
    """The contact force, separations and least contact force of a simulated cam scene.

    Parameters
    ----------
    scene : Scene
        A scene whose ``[cam]`` has a ``contact`` (it can open).
    sm : SceneMotion
        Its :func:`~mechcirc.scene.simulate_scene` result.

    Returns
    -------
    ContactReport

    Raises
    ------
    MechcircError
        The scene's contact cannot open, or the follower left the cam by the whole
        gap the model gives it (2 × (stroke + preload/spring), see :func:`flight`).
    """
    from ..transient.follower import least_sample

    lk = scene.linkage
    if not getattr(lk, "contact", ""):
        raise MechcircError(f"{scene.source}: the scene's [cam] has no contact that can open "
                            "(contact = NAME)")
    if flew := flight(scene, sm):
        raise MechcircError(flew)
    el, _, _, _, half = contact_geometry(scene)
    squeeze = -el.stiffness * (sm.values[f"{el.name}.deformation"] + half)
    lo, at = least_sample(squeeze, periodic=True)
    deg = np.degrees(sm.crank_angle)
    step = 360.0 / deg.size
    open_ = sm.values[f"{el.name}.force"] >= 0.0
    k0 = int(np.argmin(open_))                 # the runs of open samples from a closed one
    edges = np.diff(np.concatenate(([0], np.roll(open_, -k0), [0])))
    seps = sorted((float(deg[(s + k0) % deg.size]), (e - s) * step) for s, e in
                  zip(np.flatnonzero(edges > 0).tolist(), np.flatnonzero(edges < 0).tolist()))
    if open_.all():
        seps = [(0.0, 360.0)]
    return ContactReport(deg, -sm.values[f"{el.name}.force"],
                         -sm.values[f"{SPRING}.deformation"] - lk.preload / lk.spring, lo,
                         float((deg[0] + at * step) % 360.0), tuple(seps))


@dataclass(frozen=True)
class JumpSpeed:
    """The jump speed of a cam scene (plain data); see :func:`scene_jump_speed`.

    Attributes
    ----------
    omega : float
        The shaft speed [rad/s] at which the least contact force reaches 0, to ``rtol``.
    bracket : (float, float)
        The last speeds [rad/s] with the contact closed and open about it.
    least : (float, float)
        The least contact force [N] at each end of ``bracket`` (> 0, ≤ 0).
    runs : int
        How many one-revolution simulations the search took.
    rtol : float
        The root's relative tolerance.
    """

    omega: float
    bracket: tuple
    least: tuple
    runs: int
    rtol: float


def scene_jump_speed(scene, bracket=None, *, rtol: float = 1e-8, grow: float = 1.05,
                     **simulate) -> JumpSpeed:
    """The cam shaft speed at which the simulated least contact force reaches zero.

    N(Ω), the least contact force over one revolution from the pose
    (:func:`contact_report` of :func:`~mechcirc.scene.simulate_scene`), is positive
    while the follower stays on the cam and ≤ 0 once it leaves it.  First a bracket
    [Ω_lo, Ω_hi] with N(Ω_lo) > 0 ≥ N(Ω_hi) is found by stepping from the scene's
    shaft speed by the factor ``grow`` (up while the contact holds, down while it
    opens), unless given; then secants in Ω² through runs where the contact holds
    (:func:`_secant_in_omega_squared`), until two roots agree to ``rtol``.

    Parameters
    ----------
    scene : Scene
        A scene whose ``[cam]`` has a contact that can open.
    bracket : (float, float), optional
        Two shaft speeds [rad/s], the contact closed at the first and open at the second.
    rtol : float
        The relative change of the root at which the iteration stops (≥ 4 × machine
        epsilon).
    grow : float
        The factor (> 1) the bracket's search steps by.
    **simulate
        Keywords of :func:`~mechcirc.scene.simulate_scene` (not ``omega``).

    Returns
    -------
    JumpSpeed

    Raises
    ------
    MechcircError
        A given bracket that does not hold the jump, no bracket found within 100
        steps (the contact opens at every speed, or at none up to grow¹⁰⁰ Ω), or no
        convergence in 20 secant steps.
    """
    from .motion import motion_model

    if not (math.isfinite(rtol) and 4 * np.finfo(float).eps <= rtol < 1) or not grow > 1:
        raise MechcircError(f"scene_jump_speed: rtol = {rtol!r} must be in [4 eps, 1) and "
                            f"grow = {grow!r} > 1")
    simulate = {"revolutions": 1, "error_estimate": False, **simulate}
    simulate.setdefault("model", motion_model(scene))
    seen: dict = {}

    def least(w):
        if w not in seen:
            sm = simulate_scene(scene, omega=w, **simulate)
            seen[w] = contact_report(scene, sm).min_contact
        return seen[w]

    lo, hi = _jump_bracket(scene, bracket, grow, least)
    w, lo, hi = _secant_in_omega_squared(scene, seen, least, lo, hi, rtol)
    return JumpSpeed(float(w), (lo, hi), (seen[lo], seen[hi]), len(seen), rtol)


def _secant_in_omega_squared(scene, seen, least, lo, hi, rtol):
    """The root of N(Ω²) by secants through runs that hold, at 0.998/0.999 of each root.

    The two fastest runs with N > 0 give the root of the line through them; the
    next two runs are at 0.998 and 0.999 of it.  For a rigid follower N = F₀ + k s
    + mΩ² s″ at a fixed cam angle is linear in Ω², so this settles in a few steps.
    It stays off N ≈ 0 on purpose: there the contact law bends within a step and a
    fixed-step run's least force falls to 0 early (a bisection on N's sign lands
    below the root by the step: 2e-5 at 200 steps per period).  Every root is kept
    inside the bracket, which each run narrows.  ``seen`` maps the speeds run so
    far to their least contact force; ``least`` runs one more.  Returns the root
    and the narrowed bracket (lo, hi).
    """
    w, previous = math.nan, math.inf
    for _ in range(20):
        held = sorted(v for v in seen if seen[v] > 0)
        if len(held) < 2:                       # one closed run: halve the bracket in Ω²
            w = math.sqrt((lo * lo + hi * hi) / 2)
        else:
            wa, wb = held[-2:]
            na, nb = seen[wa], seen[wb]
            w2 = wb * wb + (wb * wb - wa * wa) * nb / (na - nb) if na > nb else math.nan
            w = math.sqrt(w2) if lo * lo < w2 < hi * hi else math.sqrt((lo * lo + hi * hi) / 2)
            if abs(w - previous) <= rtol * w:
                return w, lo, hi
            previous = w
        for f in ((0.998, 0.999) if len(held) >= 2 else (1.0,)):
            v = max(lo, min(hi, f * w))
            if least(v) > 0:
                lo = max(lo, v)
            else:
                hi = min(hi, v)
    raise MechcircError(f"{scene.source}: the jump speed did not settle to rtol {rtol:g} "
                        f"in 20 secant steps (last {w:g} rad/s)")


def _jump_bracket(scene, bracket, grow, least):
    """(Ω_lo, Ω_hi) with the contact closed at the first and open at the second."""
    if bracket is not None:
        lo, hi = (float(w) for w in bracket)
        if not (0 < lo < hi and least(lo) > 0 >= least(hi)):
            raise MechcircError(f"{scene.source}: the bracket ({lo:g}, {hi:g}) rad/s does not "
                                "hold the jump: the least contact force must be > 0 at the "
                                "first speed and <= 0 at the second")
        return lo, hi
    lo = hi = scene.linkage.cranks[0].omega
    for _ in range(100):
        if least(lo) > 0 >= least(hi) and lo < hi:
            return lo, hi
        lo, hi = (hi, hi * grow) if least(hi) > 0 else (lo / grow, lo)
    raise MechcircError(f"{scene.source}: no speed between {lo:g} and {hi:g} rad/s "
                        "where the follower starts to leave the cam")
