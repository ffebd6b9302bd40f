"""Mrázek's sley models as scenes: :func:`sley_scene`, :func:`preset_scene`.

One-side (Table 1): the driven shaft -C2∥k2- the four-bar crank 2P (coupler 3,
rocker 4) -C4∥k4- the sley 4P.  Both-sides (Table 2): a second, identical
four-bar on the same shaft (crank 5P, rocker 7) with rods C5∥k5 and C7∥k7; the
two rockers hold the one sley — an elastic loop.  The scene is posed with the
crank at angle 0 (along the frame A→D), so crank rotation from the pose is
the sley's crank angle φ2; the run starts at θ0 where ν = 0, as the paper's.
Every elastic connection has the clearance ϕ with Mrázek's dead-zone law
(eq. (8): damping throughout); the beat-up moment is a moment (``[[moments]]``)
on the sley, centred on the front dead centre, amplitude beat_sign·M0.
"""

from __future__ import annotations

import math

from .models import SleyParameters, start_angle

__all__ = ["sley_scene", "scene_overrides", "preset_scene", "ALIASES"]

ALIASES = {"one-side": {"eps2P": "crank.acceleration", "eps4P": "sley.acceleration",
                        "eps4T": "rocker.rigid_acceleration", "M2V": "C2.force"},
           "both-sides": {"eps2P": "crank.acceleration", "eps4P": "sley.acceleration",
                          "eps5P": "crank5.acceleration", "eps4T": "rocker.rigid_acceleration",
                          "M2V": "C2.force", "M5V": "C5.force"}}


def sley_scene(params: SleyParameters, *, revolutions: int = 5):
    """The scene of ``params``, built from the scene layer's dataclasses.

    ``examples/mrazek_*.toml`` hold this scene of Table 1/2 variant 3 as TOML
    (parsing a file gives the same scene).  Every rod carries the clearance
    (dead-zone law) and the beat-up moment is there even when M0 = 0, so that
    every preset is the shipped scene plus :func:`scene_overrides`.

    Parameters
    ----------
    params : SleyParameters
        Geometry [m], inertias [kg·m²], rods [N·m/rad, N·m·s/rad], clearance [rad].
    revolutions : int
        The ``[simulate]`` revolutions of the scene.

    Returns
    -------
    Scene
        Posed with the crank at angle 0, the run starting at θ0 where ν = 0.
    """
    from ..scene.files import Scene, SceneDrive, SceneMass, Torsion
    from ..scene.simfile import Moment, SimulateSettings

    p = params
    name, source = f"mrazek {p.drive}", f"<sley {p.label or p.drive}>"
    linkage = _sley_linkage(p, name, source)
    rods, masses = _parts(p)
    window, sigma = (math.radians(math.degrees(a)) for a in (p.alpha, p.sigma))  # as in a file
    return Scene(
        name, linkage, "m", 1.0,
        tuple(SceneMass(m, "inertia", float(v), link=link) for m, link, v in masses), (),
        tuple(Torsion(r, link, float(k), float(c), float(p.clearance), "dead-zone",
                      body=body, pivot=pivot)
              for r, link, body, pivot, k, c in rods), (),
        SceneDrive("V", "velocity", float(p.omega), link="shaft"), (), source,
        moments=(Moment("M4", "sley", float(p.beat_sign * p.M0), window, sigma,
                        "front-dead-centre"),),
        simulate=SimulateSettings(revolutions=revolutions,
                                  start_deg=math.degrees(start_angle(p)),
                                  aliases=dict(ALIASES[p.drive])))


def _parts(p: SleyParameters) -> tuple[list, list]:
    """The rods (name, link, body, pivot, rigidity, damping) and the inertias (name, link,
    value) of ``p``'s scene."""
    rods = [("C2", "crank", "shaft", "A", p.C2, p.k2), ("C4", "rocker", "sley", "D", p.C4, p.k4)]
    masses = [("I2P", "crank", p.I2P), ("I4", "rocker", p.I4), ("I4P", "sley", p.I4P)]
    if p.drive == "both-sides":
        I5P, I7, C5, C7, k5, k7 = p.second_side()
        rods += [("C5", "crank5", "shaft", "E", C5, k5), ("C7", "rocker7", "sley", "H", C7, k7)]
        masses += [("I5P", "crank5", I5P), ("I7", "rocker7", I7)]
    return rods, masses


def _sley_linkage(p: SleyParameters, name: str, source: str):
    """The four-bar(s) of ``p`` posed with the crank at angle 0, each crank driven at ω."""
    import numpy as np

    from ..kinematics.linkage import Crank, Linkage

    C = p.fourbar().joints(0.0)[2]
    sides = [("", "A", "B", "C", "D", "rocker")] + ([("5", "E", "F", "G", "H", "rocker7")]
                                                    if p.drive == "both-sides" else [])
    pose: dict = {}
    links: dict = {}
    for n, a, b, c, d, rocker in sides:
        pose.update({a: (0.0, 0.0), b: (p.l2P, 0.0), c: C, d: (p.d, 0.0)})
        links.update({"crank" + n: (a, b), "coupler" + n: (b, c), rocker: (d, c)})
    ground = tuple(pivot for _, a, _, _, d, _ in sides for pivot in (a, d))
    cranks = tuple(Crank("crank" + n, a, float(p.omega)) for n, a, *_ in sides)
    return Linkage(name, {k: np.array(v, dtype=float) for k, v in pose.items()}, ground,
                   links, cranks, source, "m")


def scene_overrides(params: SleyParameters) -> dict:
    """``--set`` overrides that turn the shipped scene of ``params.drive`` into ``params``.

    The geometry (l2P, l3, l4, d, branch) is the scene's and is not overridden.

    Parameters
    ----------
    params : SleyParameters
        The variant's parameters.

    Returns
    -------
    dict[str, float]
        ``NAME.FIELD`` (and ``omega``) → value in SI units, windows in degrees.
    """
    p = params
    rods, masses = _parts(p)
    out = {"omega": p.omega, **{f"{m}.inertia": v for m, _, v in masses},
           "M4.amplitude": p.beat_sign * p.M0, "M4.window_deg": math.degrees(p.alpha),
           "M4.sigma_deg": math.degrees(p.sigma)}
    for r, *_, rigidity, damping in rods:
        out |= {f"{r}.stiffness": rigidity, f"{r}.damping": damping, f"{r}.clearance": p.clearance}
    return {k: float(v) for k, v in out.items()}


def preset_scene(drive: str = "one-side", variant: int = 3, **overrides):
    """The shipped scene ``examples/mrazek_<drive>.toml`` turned into a preset variant.

    Parameters
    ----------
    drive : {"one-side", "both-sides"}
        Table 1 or Table 2.
    variant : int
        The variant, 1–7.
    **overrides
        Parameter values of :func:`~mechcirc.sley.preset` (``C2=1e7``, say).

    Returns
    -------
    Scene
        :func:`sley_scene` of Table 1/2 variant 3 (the shipped file) with
        :func:`scene_overrides` of ``preset(drive, variant, **overrides)``.
    """
    from ..scene.files import apply_overrides
    from .presets import preset

    base = sley_scene(preset(drive, 3))
    return apply_overrides(base, scene_overrides(preset(drive, variant, **overrides)))
