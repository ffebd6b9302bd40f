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

from .cam import SPRING, contact_geometry

__all__ = ["ContactReport", "contact_report", "scene_jump_speed"]


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
        gap the model gives it (2 × (stroke + preload/spring)).
    """
    from ..errors import MechcircError
    from ..transient.follower import least_sample

    lk = scene.linkage
    if not getattr(lk, "contact", ""):
        raise MechcircError(f"{scene.source}: the scene's [cam] has no contact that can open "
                            "(contact = NAME)")
    el, _, _, _, half = contact_geometry(scene)
    e = sm.values[f"{el.name}.deformation"]
    if np.any(e > half):
        raise MechcircError(f"{scene.source}: the follower left the cam by more than the "
                            f"model's gap ({2 * half:g} m): the contact's far flank was hit")
    squeeze = -el.stiffness * (e + half)
    lo, at = least_sample(squeeze, periodic=True)
    deg = np.degrees(sm.crank_angle)
    step = 360.0 / deg.size
    open_ = sm.values[f"{el.name}.force"] >= 0.0
    seps = []
    if open_.any() and not open_.all():
        k0 = int(np.argmin(open_))                 # start the scan where the contact is closed
        run = None
        for k in range(k0, k0 + deg.size + 1):
            o = open_[k % deg.size]
            if o and run is None:
                run = k
            elif not o and run is not None:
                seps.append((float(deg[run % deg.size]), (k - run) * step))
                run = None
        seps.sort()
    elif open_.all():
        seps.append((0.0, 360.0))
    return ContactReport(deg, -sm.values[f"{el.name}.force"],
                         -sm.values[f"{SPRING}.deformation"] - lk.preload / lk.spring, lo,
                         float((deg[0] + at * step) % 360.0), tuple(seps))


def scene_jump_speed(scene, omegas, **simulate) -> tuple:
    """The cam shaft speed at which the simulated contact force first reaches zero.

    The scene is simulated (:func:`~mechcirc.scene.simulate_scene`, one revolution
    from the pose, ``simulate`` passed on) at the two shaft speeds ``omegas``, both
    below the jump; its least contact force N(Ω) (:func:`contact_report`) is
    extrapolated to 0 linearly in Ω².  For a rigid follower N = F₀ + k s + mΩ² s″
    at a fixed cam angle is linear in Ω², and the least over the angle bends only a
    little: from 0.998 and 0.999 of the jump speed the extrapolation is ~2e-8 off
    (the cycloidal cam of docs/cams.md); just below the jump the contact force
    nears 0, where a fixed step is least accurate, which is why it is not sought
    there.

    Parameters
    ----------
    scene : Scene
        A scene whose ``[cam]`` has a contact that can open.
    omegas : (float, float)
        Two shaft speeds [rad/s] below the jump.
    **simulate
        Keywords of :func:`~mechcirc.scene.simulate_scene` (not ``omega``).

    Returns
    -------
    omega, least : float, tuple of float
        The jump speed [rad/s] and the least contact force [N] at each of ``omegas``.

    Raises
    ------
    MechcircError
        The contact opens at one of ``omegas`` (its least force is not positive).
    """
    from ..errors import MechcircError
    from .motion import motion_model
    from .simulation import simulate_scene

    simulate = {"revolutions": 1, "error_estimate": False, **simulate}
    simulate.setdefault("model", motion_model(scene))
    least = []
    for w in omegas:
        lo = contact_report(scene, simulate_scene(scene, omega=w, **simulate)).min_contact
        if not lo > 0:
            raise MechcircError(f"{scene.source}: at {w:g} rad/s the least contact force is "
                                f"{lo:g} N: give two speeds below the jump")
        least.append(lo)
    (wa, wb), (na, nb) = omegas, least
    if na == nb:
        raise MechcircError(f"{scene.source}: the least contact force is the same at both "
                            "speeds: give two different speeds below the jump")
    return math.sqrt(wa * wa + (wb * wb - wa * wa) * na / (na - nb)), tuple(least)
